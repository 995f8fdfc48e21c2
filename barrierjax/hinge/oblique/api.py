"""The public functions of report 3.3: `oblique_impact` and `moving_load`."""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp

from ... import _checks
from ..._solve.queue import solve_queued
from ..._solve.recorded_rk import Carry
from ..._solve.sensitivity import forward_jacobian_jvp
from .results import (
    MovingLoad,
    ObliqueImpact,
    build_history,
    displacement_field,
    finish,
    padded,
    plastic_zone_grid,
)
from .transitions import initial_carry, outcome_of, raise_failures, step_loop

_N_X = 129


def _check_options(rtol, max_steps):
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"rtol must be in (0, 1); got {rtol!r}")
    if int(max_steps) != max_steps or max_steps < 16:
        raise ValueError(f"max_steps must be an integer >= 16; got {max_steps!r}")


def oblique_impact(
    mass_ratio,
    force_ratio,
    normal_speed,
    tangential_speed,
    *,
    friction=0.0,
    rtol: float = 1e-8,
    history: bool = False,
    max_steps: int = 1024,
) -> ObliqueImpact:
    """Oblique impact (report 3.3) in the report's dimensionless variables.

    **Arguments:**

    - `mass_ratio`: mu = M / (m L), positive.
    - `force_ratio`: phi = P0 / P_b, above 1 (at or below 1 the barrier never yields).
    - `normal_speed`, `tangential_speed`: the vehicle's impact velocity components over
      L / t0; the normal one positive, the tangential one non-negative (zero is the
      normal impact of 3.2).
    - `friction`: Coulomb coefficient between vehicle and barrier, non-negative.
    - `rtol`: relative tolerance of the step loop (absolute: 1e-3 rtol).
    - `history`: also return the recorded steps and the displacement field.
    - `max_steps`: step budget of the whole run: every attempted step, and one for the
      start of each phase and segment (also the size of the recorded history).

    Differentiable with respect to every argument (forward-mode sensitivities, whichever
    way JAX differentiates); scalars, or arrays of one shape solved under `vmap`.
    """
    _check_options(rtol, max_steps)
    mu = _checks.positive("mass_ratio", mass_ratio)
    phi = _checks.check(
        "force_ratio", force_ratio, lambda x: (x > 1.0) & (x < jnp.inf), "above 1 and finite"
    )
    vn = _checks.positive("normal_speed", normal_speed)
    vh = _checks.non_negative("tangential_speed", tangential_speed)
    friction = _checks.non_negative("friction", friction)
    args = jnp.broadcast_arrays(mu, phi, vn, vh, friction)
    options = {"max_steps": int(max_steps), "history": bool(history), "n_x": _N_X}
    rtol = jnp.asarray(rtol, args[0].dtype)
    if args[0].ndim == 0:
        return _oblique_solved(*args, rtol, **options)
    flat = _oblique_solved(*(a.ravel() for a in args), rtol, **options)
    return jax.tree.map(lambda leaf: leaf.reshape(args[0].shape + leaf.shape[1:]), flat)


def _of_lane(carry: Carry, lane) -> Carry:
    return eqx.tree_at(lambda c: c.recording, carry, carry.recording.of_lane(lane))


# Array inputs are solved in this many vmapped lanes, each taking the next scenario as soon
# as its own is done (`_solve.queue`), finished and refilled this many at a time. On 1e4
# random scenarios at rtol 1e-6 (benchmarks/oblique_impact.py's box, 2 CPU cores, best of
# 4 interleaved calls): 78 us per scenario with 256 lanes, 61-67 with 384, 106 with 512
# (the lanes' buffers, 74 kB each at the default max_steps, then outgrow the caches).
_LANES, _REFILL = 384, 48


@functools.partial(jax.jit, static_argnames=("max_steps", "history", "n_x"))
def _oblique_solved(mu, phi, vn, vh, friction, rtol, *, max_steps, history, n_x):
    def solve(*inputs_and_rtol):
        *inputs, rtol = inputs_and_rtol
        loop = step_loop(rtol, max_steps)
        start = lambda x: initial_carry(loop, *x, history=history)
        results = functools.partial(finish, history=history, n_x=n_x)
        if mu.ndim == 0:
            return results(loop.solve(start(inputs)))
        return solve_queued(
            start,
            loop.step,
            loop.running,
            lambda carry, lane: results(loop.solution(_of_lane(carry, lane))),
            tuple(inputs),
            buffers=lambda carry: carry.recording.buffer,
            seed_rows=1,
            lanes=_LANES,
            refill=_REFILL,
        )

    solve = forward_jacobian_jvp(solve, n_differentiable=5)
    result, outcome = solve(mu, phi, vn, vh, friction, rtol)
    return raise_failures(result, outcome)


def moving_load(
    force_ratio, tangential_speed, t_end, *, rtol: float = 1e-8, max_steps: int = 1024
) -> MovingLoad:
    """A constant force moving along the beam at constant speed: the accelerative-phase
    equations (3.3.16) alone, from S1 = S2 = S*, V0 = 0 to T = `t_end`. Its steady state
    is (3.3.18)-(3.3.19): S1 = phi - sqrt(phi^2 - 1), S2 = phi + sqrt(phi^2 - 1),
    V0 = sqrt(phi^2 - 1) / V_H."""
    _check_options(rtol, max_steps)
    phi = _checks.check(
        "force_ratio", force_ratio, lambda x: (x > 1.0) & (x < jnp.inf), "above 1 and finite"
    )
    vh = _checks.positive("tangential_speed", tangential_speed)
    t_end = _checks.positive("t_end", t_end)
    args = jnp.broadcast_arrays(phi, vh, t_end)
    return _moving_load(*args, jnp.asarray(rtol, args[0].dtype), max_steps=int(max_steps))


@functools.partial(jax.jit, static_argnames=("max_steps",))
def _moving_load(phi, vh, t_end, rtol, *, max_steps):
    def solve(phi, vh, t_end, rtol):
        loop = step_loop(rtol, max_steps)
        one = jnp.ones_like(phi)
        solution = loop.solve(
            initial_carry(loop, one, phi, one, vh, 0.0 * one, history=True, t_end=t_end)
        )
        recording, y = solution.recording, solution.y
        samples = padded(recording.samples, recording.count)
        x = plastic_zone_grid(samples, recording.count, _N_X)
        displacement = displacement_field(samples, recording.count, x)
        return MovingLoad(
            s1=y.s1,
            s2=y.s2,
            v0=y.speed,
            history=build_history(samples, recording.count, solution.args, x, displacement),
        ), outcome_of(solution)

    solve = forward_jacobian_jvp(solve, n_differentiable=3)
    for _ in range(phi.ndim):
        solve = jax.vmap(solve, in_axes=(0, 0, 0, None))
    result, outcome = solve(phi, vh, t_end, rtol)
    return raise_failures(result, outcome, moving_load=True)
