"""The public functions of report 3.3: `oblique_impact` and `moving_load`."""

import functools
import math
import types

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer

from ... import _checks, _xla_flags
from ..._solve.batching import PADDING_QUANTUM, solve_padded, solved_again
from ..._solve.phases import SolveError
from ..._solve.queue import solve_queued
from ..._solve.recorded_rk import Carry
from ..._solve.sensitivity import forward_jacobian, forward_jacobian_jvp
from ...compilation_cache import stored_program
from ..response import RESULT_UNITS, kinetic_energy_balance
from .results import MovingLoad, ObliqueImpact, build_history, finish, rigid_barrier
from .transitions import (
    OVERTAKEN_MESSAGE,
    STALLED_MESSAGE,
    Outcome,
    initial_carry,
    outcome_of,
    phase_name,
    raise_failures,
    step_loop,
)

_N_X = 129


# The default tolerance, and the smallest one a dtype can meet: below about a hundred
# roundings the step control cannot reach it, and the steps shrink until the budget is spent.
_DEFAULT_RTOL, _ROUNDINGS = 1e-8, 100.0


def _tolerance(rtol, dtype):
    """`rtol` as an array of `dtype`; `None` is the default, or the smallest tolerance
    the dtype can meet where that is larger (float32: 1.2e-5)."""
    smallest = _ROUNDINGS * float(jnp.finfo(dtype).eps)
    if rtol is None:
        rtol = max(_DEFAULT_RTOL, smallest)
    elif rtol < smallest:
        raise ValueError(
            f"rtol must be at least {smallest:.2g} in {jnp.dtype(dtype).name}; got {rtol!r} "
            f"(pass a larger rtol, or {_checks.ENABLE_FLOAT64})"
        )
    return _checks.float_array(rtol, dtype)


def _force_ratio(force_ratio):
    """phi, checked: at or below 1 the barrier never yields and 3.3's mechanism has no
    hinges."""
    return _checks.check(
        "force_ratio", force_ratio, lambda x: (x > 1.0) & (x < jnp.inf), "above 1 and finite"
    )


def _check_options(rtol, max_steps):
    if rtol is not None:
        _checks.tolerance("rtol", rtol)
    _checks.step_budget(max_steps)


# The step budget a solve starts with when none is given, and the largest it grows to by
# itself (a recording holds a row per step: 74 kB a lane at 1024 steps without history).
_FIRST_BUDGET, _LARGEST_BUDGET = 1024, 65536


def _within_budget(solve, args, max_steps, grow, *, moving_load=False):
    """(`solve(args, budget)`'s result, the failed scenarios' reasons by flat index, the
    flat batch's size or None for one scenario), where `solve` returns (result, `Outcome`).

    Traced inside a caller's `jit`, `vmap` or `grad`, failures are run-time errors
    (`raise_failures`). Otherwise each failure's reason is one line that says what to pass;
    and with `max_steps=None` the scenarios that spent their budget are solved again,
    alone (`solved_again`), with `grow(budget, their args, their outcome)` (a new
    compilation each time), up to `_LARGEST_BUDGET`."""
    name = "moving_load" if moving_load else "oblique_impact"

    def solve_read(args, budget):
        result, outcome = solve(args, budget)
        # (Under `jax.grad` outside a `jit` the outcome's times carry tangents, its flags
        # none: read without them, it is concrete there; so are the inputs `grow` reads.)
        return result, jax.lax.stop_gradient(outcome)

    def larger(budget, args, outcome):
        budget = grow(budget, jax.lax.stop_gradient(args), outcome)
        return budget if max_steps is None and budget <= _LARGEST_BUDGET else None

    def spent(outcome):
        failed = np.asarray(outcome.overtaken) | np.asarray(outcome.stalled)
        return ~np.asarray(outcome.complete) & ~failed

    first = _FIRST_BUDGET if max_steps is None else int(max_steps)
    result, outcome, budget = solved_again(solve_read, args, first, larger, spent)
    if isinstance(outcome.time, Tracer):
        return raise_failures(result, outcome, moving_load), {}, None
    overtaken, stalled = (np.asarray(flag).ravel() for flag in (outcome.overtaken, outcome.stalled))
    spent = np.flatnonzero(~np.asarray(outcome.complete).ravel() & ~overtaken & ~stalled)
    phases, times = np.asarray(outcome.phase).ravel(), np.asarray(outcome.time).ravel()
    where = lambda k: f"{phase_name(int(phases[k]), moving_load)} at T = {times[k]:.4g}"
    # (Where a scenario is flagged twice, the load's overtaking the hinge is its reason.)
    reasons = {int(k): f"{name}: in {where(k)}, {STALLED_MESSAGE}" for k in np.flatnonzero(stalled)}
    reasons |= {int(k): f"{name}: {OVERTAKEN_MESSAGE}" for k in np.flatnonzero(overtaken)}
    if spent.size:
        rows = lambda tree: jax.tree.map(lambda leaf: jnp.ravel(leaf)[spent], tree)
        suggestion = grow(budget, rows(jax.lax.stop_gradient(args)), rows(outcome))
        reasons |= {
            int(k): f"{name}: the step budget max_steps={budget} was spent in {where(k)}: "
            f"pass max_steps={suggestion} or more"
            for k in spent
        }
    return result, reasons, _batch_size(outcome)


def _batch_size(outcome: Outcome) -> int | None:
    return None if np.ndim(outcome.complete) == 0 else int(np.size(outcome.complete))


def _power_of_two_above(steps: float) -> int:
    """Budgets are powers of two, so that few of them are ever compiled."""
    return 2 ** math.ceil(math.log2(steps))


def oblique_impact(
    mass_ratio,
    force_ratio,
    normal_speed,
    tangential_speed,
    *,
    friction=0.0,
    rtol: float | None = None,
    n_history: int = 0,
    max_steps: int | None = None,
) -> ObliqueImpact:
    """Oblique impact (report 3.3) in the report's dimensionless variables.

    **Arguments:**

    - `mass_ratio`: mu = M / (m L), positive.
    - `force_ratio`: phi = P0 / P_b, positive; at or below 1 the barrier never yields and
      the vehicle crushes against it as against a rigid wall (`results.rigid_barrier`,
      in closed form; the step loop runs a light vehicle's impact in those lanes and
      discards it).
    - `normal_speed`, `tangential_speed`: the vehicle's impact velocity components over
      L / t0; the normal one positive, the tangential one non-negative (zero is the
      normal impact of 3.2).
    - `friction`: Coulomb coefficient between vehicle and barrier, non-negative.
    - `rtol`: relative tolerance of the step loop (absolute: 1e-3 rtol). `None`: 1e-8, or
      in float32 the smallest it can meet, 1.2e-5; a smaller one raises a `ValueError`.
    - `n_history`: samples of the history, equally spaced in time (0: none, the
      cheapest).
    - `max_steps`: step budget of the whole run: every attempted step, and one for the
      start of each phase and segment (also the size of the recorded history). `None`:
      1024, and where that is spent (heavy vehicles, mu above about 50), the scenarios
      that spent it are solved again, alone, with four times as many, again and again up
      to 65536 (each a new compilation; one scenario by the scalar program, quicker to
      compile, and the batch's others left as solved). A spent budget raises a
      one-line `SolveError` (a `RuntimeError`) that says what to pass; inside a caller's
      `jit`, `vmap` or `grad` the budget cannot grow and a spent one is a run-time error.

    A result whose kinetic-energy balance does not close (off by more than 1 % of the
    impact's energy, or 10^4 rtol) raises a `SolveError` too, where the result is concrete
    (not inside a caller's `jit`, `vmap` or `grad`): float32 solves of heavy vehicles.
    Such an error names every failed scenario of a batch (`SolveError.failures`) and
    carries the batch's result (`SolveError.result`): the other scenarios' are answers.

    Differentiable with respect to every argument (forward-mode sensitivities, whichever
    way JAX differentiates); scalars, or arrays of one shape solved under `vmap` (padded
    to the next power of two, above 256 to a multiple of 256, so that batches of nearby
    sizes share one compiled program; the forward solve skips the copies, the
    derivatives' solves them; on a CPU, 1,024 scenarios or more in parts run side by side,
    one a core).
    """
    _check_options(rtol, max_steps)
    n_history = _checks.history_samples(n_history)
    mu = _checks.positive("mass_ratio", mass_ratio)
    phi = _checks.positive("force_ratio", force_ratio)
    vn = _checks.positive("normal_speed", normal_speed)
    vh = _checks.non_negative("tangential_speed", tangential_speed)
    friction = _checks.non_negative("friction", friction)
    yields, inputs = _lanes(mu, phi, vn, vh, friction)
    rtol = _tolerance(rtol, inputs[0].dtype)

    def solve(inputs, budget):
        options = {"max_steps": budget, "n_history": n_history, "n_x": _N_X}
        # (XLA's options are for a program compiled by itself, not inside a caller's.)
        traced = any(isinstance(x, Tracer) for x in inputs)
        solved = _oblique_solved if inputs[0].ndim == 0 or traced else _oblique_batch_solved
        differentiable = forward_jacobian_jvp(
            functools.partial(solved, **options),
            n_differentiable=5,
            value_and_jacobian=functools.partial(_oblique_jacobian, **options),
            # (A `vmap` of a scalar solve can only be around traced inputs.)
            arrays_from=_VMAP_AS_ARRAYS if traced and inputs[0].ndim == 0 else None,
        )
        if inputs[0].ndim == 0:
            return differentiable(*inputs, rtol, None)
        padded = lambda *x: differentiable(*x[:-1], rtol, x[-1])
        return solve_padded(padded, inputs, PADDING_QUANTUM)

    grow = lambda budget, *_: 4 * budget
    result, reasons, size = _within_budget(solve, inputs, max_steps, grow)
    result = _with_rigid_barriers(result, yields, mu, phi, vn, vh, friction, n_history=n_history)
    # (A failed solve's own reason stands before its energy balance's.)
    reasons = _energy_unclosed(result, mu, vn, vh, rtol) | reasons
    if reasons:
        raise SolveError.of(reasons, size, result)
    return result


# A concrete result whose energy balance is off by more than this fraction of the impact's
# kinetic energy, or 10^4 times the tolerance where that is larger, is refused. In float64,
# benchmarks/oblique_impact.py's box (4,096 scenarios each) closes to 3.0e-6 of it at
# rtol 1e-8 at worst, 4.1e-4 at 1e-6 and 3.2e-2 at 1e-4 (99 % of them to 2.6e-8, 1.0e-6
# and 3.8e-4); in float32 (rtol 1.2e-5) heavy vehicles (mass ratio above about 100) came
# out with 23 % and 990 % of it unaccounted for, leaving faster than they came.
_ENERGY_FLOOR, _ENERGY_PER_RTOL = 1e-2, 1e4


def _energy_unclosed(result: ObliqueImpact, mu, vn, vh, rtol) -> dict[int, str]:
    """The scenarios of a concrete `result` whose energy balance does not close
    (`kinetic_energy_balance`), each with its reason by flat index; none where traced
    (under `jit`, `vmap`, `grad`)."""
    if any(isinstance(x, Tracer) for x in jax.tree.leaves((result, mu, vn, vh, rtol))):
        return {}
    names = [name for name in RESULT_UNITS if name.endswith("_work")] + ["exit_speed"]
    values = types.SimpleNamespace(**{name: np.asarray(getattr(result, name)) for name in names})
    mu, vn, vh = (np.asarray(x) for x in (mu, vn, vh))
    lost = kinetic_energy_balance(values, mu, vn, vh) / (0.5 * mu * (vn**2 + vh**2))
    bound = max(_ENERGY_FLOOR, _ENERGY_PER_RTOL * float(rtol))
    off = np.flatnonzero(~(np.abs(lost) <= bound).ravel())
    hint = "" if lost.dtype == np.float64 else f"; {_checks.ENABLE_FLOAT64}"
    return {
        int(k): f"oblique_impact: the energy balance does not close: {lost.ravel()[k]:.2g} "
        f"of the impact's kinetic energy unaccounted for (the solve lost its accuracy{hint})"
        for k in off
    }


@stored_program
@jax.jit
def _lanes(mu, phi, vn, vh, friction):
    """Where the barrier yields, and the step loop's inputs: broadcast, strongly typed (a
    Python number and an array of its dtype then run one program), and where it does not
    yield, `_STAND_IN`'s impact, which the loop solves in a few dozen steps (their results
    are discarded): a lane at the vehicle's own inputs could fail, or spend budgets, for
    a scenario whose answer is the closed form."""
    yields = phi > 1.0
    args = jnp.broadcast_arrays(mu, phi, vn, vh, friction)
    args = [jnp.where(yields, a, stand_in) for a, stand_in in zip(args, _STAND_IN, strict=True)]
    return yields, tuple(jnp.asarray(a, a.dtype) for a in args)


# The impact a lane of an unyielding barrier solves instead (mu, phi, V_N, V_H, friction).
_STAND_IN = (1.0, 2.0, 0.3, 0.5, 0.0)


@stored_program
@functools.partial(jax.jit, static_argnames="n_history")
def _with_rigid_barriers(solved: ObliqueImpact, yields, mu, phi, vn, vh, friction, *, n_history):
    """`solved` where the barrier `yields`, `rigid_barrier` elsewhere: one program (op by
    op, each new shape compiled some 20 small ones)."""
    mu, phi, vn, vh, friction = jnp.broadcast_arrays(mu, phi, vn, vh, friction)
    rigid = rigid_barrier(mu, phi, vn, vh, friction, n_history=n_history, n_x=_N_X)
    yields = jnp.broadcast_to(yields, mu.shape)

    def choose(solved, closed_form):
        mask = yields.reshape(yields.shape + (1,) * (solved.ndim - yields.ndim))
        return jnp.where(mask, solved, closed_form.astype(solved.dtype))

    return jax.tree.map(choose, solved, rigid)


def _of_lane(carry: Carry, lane) -> Carry:
    return eqx.tree_at(lambda c: c.recording, carry, carry.recording.of_lane(lane))


# Array inputs are solved in this many vmapped lanes, each taking the next scenario as soon
# as its own is done (`_solve.queue`), finished and refilled this many at a time. On 1e4
# random scenarios at rtol 1e-6 (benchmarks/oblique_impact.py's box, 2 CPU cores, best of
# 4 interleaved calls): 78 us per scenario with 256 lanes, 61-67 with 384, 106 with 512
# (the lanes' buffers, 74 kB each at the default max_steps, then outgrow the caches).
# Refilled 16 at a time, 5,000 scenarios, one core, heaviest first: 38.7-40.9 us per
# scenario, against 41.9-45.4 with 48 and 41.5-43.0 with 8 (2026-11-27).
_LANES, _REFILL = 384, 16


def _solve(mu, phi, vn, vh, friction, rtol, count, *, max_steps, n_history, n_x, batched):
    """The step loop from impact to exit: for scalars, one solve; for arrays, their
    scenarios in the lanes of a queue (the first `count` of them: the rest pad the batch
    to a size already compiled), with the loop written for a batch (`batched`) or for a
    single solve under `vmap`."""
    loop = step_loop(rtol, max_steps, batched=batched)
    start = lambda x: initial_carry(loop, *x, history=n_history > 0)
    results = functools.partial(finish, n_history=n_history, n_x=n_x)
    inputs = (mu, phi, vn, vh, friction)
    if jnp.ndim(mu) == 0:
        return results(loop.solve(start(inputs)))
    return solve_queued(
        start,
        loop.step,
        loop.running,
        lambda carry, lane: results(loop.solution(_of_lane(carry, lane))),
        inputs,
        buffers=lambda carry: carry.recording.buffer,
        seed_rows=1,
        lanes=_LANES,
        refill=_REFILL,
        count=count,
        order=_heaviest_first(mu, count),
    )


def _heaviest_first(mu, count):
    """The real scenarios by decreasing mass ratio, then the padding. The heavier the
    vehicle, the more steps its impact takes (rank correlation 0.88 over 3,000 scenarios of
    benchmarks/oblique_impact.py's box), so that the queue ends on short solves: on 5,000
    scenarios (refilled 48 at a time) its loop ran 835 iterations in the order given, 141
    of them after the last start, and 755, 50 after, heaviest first; 671 had every lane
    been busy throughout."""
    index = jnp.arange(mu.shape[0])
    real = index < jnp.asarray(mu.shape[0] if count is None else count).astype(index.dtype)
    return jnp.argsort(jnp.where(real, -mu, jnp.inf))


# A `vmap` of this many scalar solves or more runs the batch's program (below it, the
# scalar loop under `vmap`). Its gradient, steady, at 64, 128 and 256 scenarios: 2.59,
# 5.08 and 5.28 s against 1.54, 4.46 and 6.60-7.22 (2 cores, 2026-11-28); its forward,
# 1,024 scenarios: 0.21 s against 0.83, but 4 s more to compile.
_VMAP_AS_ARRAYS = 256

_STATIC = ("max_steps", "n_history", "n_x")


def _solved(mu, phi, vn, vh, friction, rtol, count, *, max_steps, n_history, n_x):
    options = {"max_steps": max_steps, "n_history": n_history, "n_x": n_x}
    return _solve(mu, phi, vn, vh, friction, rtol, count, **options, batched=mu.ndim > 0)


# A batch's step runs faster with 512-bit vectors and XLA's MLIR fusion emitters
# (`_xla_flags`).
_oblique_solved = stored_program(jax.jit(_solved, static_argnames=_STATIC))
_BATCH_OPTIONS = _xla_flags.batched_step_options()
_oblique_batch_solved = stored_program(
    jax.jit(_solved, static_argnames=_STATIC, compiler_options=_BATCH_OPTIONS),
    compiler_options=_BATCH_OPTIONS,
)


# One program for every derivative, whichever arguments carry tangents (the custom JVP of
# `oblique_impact` calls it outside any jit of its own). A batch's derivatives come from
# the step loop written for a single solve: its forward under `vmap` ran 2.9 times slower
# (1e4 scenarios), but the loop written for a batch, differentiated, took 46 s to compile
# for 10 scenarios against 23 s (2 cores).
@functools.partial(jax.jit, static_argnames=_STATIC)
def _oblique_jacobian(mu, phi, vn, vh, friction, rtol, count, *, max_steps, n_history, n_x):
    options = {"max_steps": max_steps, "n_history": n_history, "n_x": n_x}
    single = functools.partial(_solve, **options, batched=False)
    # Every problem is solved, the padding's copies too: the directions are stacked as
    # problems of their own, and the real ones are then no longer the first `count`.
    del count
    return forward_jacobian(single, (mu, phi, vn, vh, friction, rtol, None), n_differentiable=5)


def moving_load(
    force_ratio,
    tangential_speed,
    t_end,
    *,
    rtol: float | None = None,
    max_steps: int | None = None,
    n_history: int = 200,
) -> MovingLoad:
    """A constant force moving along the beam at constant speed: the accelerative-phase
    equations (3.3.16) alone, from S1 = S2 = S*, V0 = 0 to T = `t_end`. Its steady state
    is (3.3.18)-(3.3.19): S1 = phi - sqrt(phi^2 - 1), S2 = phi + sqrt(phi^2 - 1),
    V0 = sqrt(phi^2 - 1) / V_H.

    `rtol`, `max_steps` and `n_history` (here at least 2) as in `oblique_impact`; with
    `max_steps=None` a spent budget grows to what the time reached says the run needs."""
    _check_options(rtol, max_steps)
    n_history = _checks.history_samples(n_history, optional=False)
    phi = _force_ratio(force_ratio)
    vh = _checks.positive("tangential_speed", tangential_speed)
    t_end = _checks.positive("t_end", t_end)
    args = jnp.broadcast_arrays(phi, vh, t_end)
    rtol = _tolerance(rtol, args[0].dtype)

    def larger(budget, args, outcome):
        """The budget in proportion to the time left, with a quarter to spare."""
        reached = np.asarray(outcome.time / args[2])
        return _power_of_two_above(1.25 * budget / max(float(np.min(reached)), 1e-3))

    result, reasons, size = _within_budget(
        lambda args, budget: _moving_load(*args, rtol, max_steps=budget, n_history=n_history),
        args,
        max_steps,
        larger,
        moving_load=True,
    )
    if reasons:
        raise SolveError.of(reasons, size, result)
    return result


@functools.partial(jax.jit, static_argnames=("max_steps", "n_history"))
def _moving_load(phi, vh, t_end, rtol, *, max_steps, n_history):
    def solve(phi, vh, t_end, rtol):
        loop = step_loop(rtol, max_steps)
        one = jnp.ones_like(phi)
        solution = loop.solve(
            initial_carry(loop, one, phi, one, vh, 0.0 * one, history=True, t_end=t_end)
        )
        recording, y = solution.recording, solution.y
        return MovingLoad(
            s1=y.s1,
            s2=y.s2,
            v0=y.speed,
            steps=recording.count,
            history=build_history(
                recording.samples, recording.count, solution.args, _N_X, n_history
            ),
        ), outcome_of(solution)

    solve = forward_jacobian_jvp(solve, n_differentiable=3)
    for _ in range(phi.ndim):
        solve = jax.vmap(solve, in_axes=(0, 0, 0, None))
    return solve(phi, vh, t_end, rtol)
