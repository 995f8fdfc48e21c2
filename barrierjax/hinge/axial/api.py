"""`axial_impact`, the public function of report 3.4's dynamic model: the beam stage
(`stages`) and the plastic string (`barrierjax.hinge.string`), scaled by the impact speed
into the `NormalImpact` of report 3.2."""

import functools

import jax
import jax.numpy as jnp
import numpy as np

from ... import _checks
from ..._solve.batching import solve_padded, solved_again, sorted_chunks
from ..._solve.phases import SOLVED, STEPS_SPENT, raise_failures
from ..._solve.sensitivity import forward_jacobian_jvp
from ...compilation_cache import stored_program
from ..normal.api import checked_inputs, normal_impact
from ..normal.results import NormalImpact, normal_result, rigid_barrier, scaled_history
from .stages import PHASES, axial_stages


@stored_program
@functools.partial(
    jax.jit, static_argnames=("n_history", "string_cells", "string_courant", "budget", "stiff")
)
def _axial_impact(
    mu, phi, speed, eta0, rtol, *, n_history, string_cells, string_courant, budget, stiff
):
    """(the result, the failure codes of `stages.PHASES`): the beam stage by time
    integration, then the plastic string where N reaches N0; in the speed-free variables
    the speed enters through eta0 V^2. `rtol` is traced: a new
    tolerance does not recompile. A flat array of scenarios is solved inside this `jit`,
    in sorted vmapped chunks (`_CHUNK`), and their derivatives taken as problems of their
    own (`forward_jacobian_jvp`); a `vmap` around a scalar call hands the chunks its arrays
    (the scalar solve under `vmap` stepped every scenario until the slowest was done).
    `budget`: the solves' step budgets, as a multiple of `stages._BUDGETS`; `stiff`: the
    crushing phase in implicit steps."""
    yields = phi > 1.0
    safe_phi = jnp.where(yields, phi, 2.0)

    def stages(mu, phi, eta, rtol):
        def one(mu, phi, eta):
            options = {"n_history": n_history, "string_cells": string_cells}
            options |= {"budget": budget, "stiff": stiff}
            return axial_stages(mu, phi, eta, rtol=rtol, string_courant=string_courant, **options)

        if mu.ndim == 0:
            return one(mu, phi, eta)
        return sorted_chunks(one, (mu, phi, eta), mu * eta, _CHUNK)

    differentiable = forward_jacobian_jvp(stages, n_differentiable=3, arrays_from=_CHUNK)
    r = differentiable(mu, safe_phi, eta0 * speed**2, rtol)
    finish = functools.partial(_finish, n_history=n_history, string_cells=string_cells)
    return (finish if mu.ndim == 0 else jax.vmap(finish))(r, mu, phi, speed, yields, safe_phi)


def _finish(r, mu, phi, speed, yields, safe_phi, *, n_history, string_cells):
    """The `NormalImpact` of the speed-free stages `r`, in the report's units, and the
    stages' failure codes."""
    t_string = r["t_string"] * speed
    history = None
    if n_history:
        history = scaled_history(r["history"], mu, speed, r["s_final"], t_string)
    result = normal_result(
        damage=r["damage"] * speed**2,
        duration=r["t_final"] * speed,
        displacement=r["w_final"] * speed**2,
        hinge=r["s_final"],
        crush_work=safe_phi * r["damage"] * speed**2,
        backing_work=r["backing_work"] * speed**2,
        hinge_work=(r["bending_work"] + r["stretching_work"]) * speed**2,
        string_work=r["string_work"] * speed**2,
        s_star=r["s_star"],
        t_star=r["t_star"] * speed,
        v_star=r["v_star"] * speed,
        w_star=r["w_star"] * speed**2,
        t_string=t_string,
        history=history,
    )
    rigid = rigid_barrier(mu, phi, speed, n_history, string_cells=string_cells)
    result = jax.tree.map(lambda a, b: jnp.where(yields, a, b), result, rigid)
    return result, jnp.where(yields, r["failure"], SOLVED)


def axial_impact(
    mass_ratio,
    force_ratio,
    speed,
    axial_ratio,
    *,
    rtol: float = 1e-8,
    n_history: int = 0,
    string_cells: int = 128,
    string_courant: float = 1.0,
) -> NormalImpact:
    """Normal impact on a beam held against axial motion (report 3.4), in the report's
    dimensionless variables: the beam stage of (3.4.34)-(3.4.39) by time integration,
    and where N reaches N0 the plastic string (3.4.45) to rest (`string.py`).

    **Arguments:**

    - `mass_ratio`, `force_ratio`, `speed`, `rtol`, `n_history`: as in `normal_impact`.
    - `axial_ratio`: eta0 = N0 / (4 (M0 q0)^1/2), the beam's yield force in tension in
      the report's units, non-negative. A Python `0` is the model of 3.2 itself
      (`normal_impact`, compiled without any axial term).
    - `string_cells`: elements over the string's half-span.
    - `string_courant`: the string's time step over its element's wave transit time, in
      (0, 1] (1: exact for the free string).

    Returns a `NormalImpact`: `t_string` is where N reaches N0 (inf if it never does),
    `string_work` the string's plastic work, and the history has `axial_force` and the
    string's profile. Scalars, or arrays of one shape (in sorted vmapped chunks of 64,
    padded with copies to the next power of two or whole chunk, so that batches of nearby
    sizes share one compiled program; on a CPU, 1,024 scenarios or more in parts run side
    by side, one a core); `rtol` is traced, so a new tolerance does not recompile. A
    failed solve raises as in `normal_impact`, naming the stage. Where a solve spends its
    step budget (a heavy vehicle with a force ratio close to 1, whose crushing phase needs
    explicit steps in proportion to 1 / (phi - 1); a long string), those scenarios are
    solved again with 4 times the budgets, and then with 16 times and the crushing phase
    in implicit steps (diffrax's Kvaerno5), each a new compilation; inside a caller's
    `jit`, `vmap` or `grad` they cannot be, and a spent budget is a run-time error. Needs
    float64 (JAX's `jax_enable_x64`) where `axial_ratio` is not a Python `0`.
    """
    if isinstance(axial_ratio, int | float) and axial_ratio == 0:
        return normal_impact(mass_ratio, force_ratio, speed, rtol=rtol, n_history=n_history)
    if jnp.result_type(float) != jnp.float64:
        raise ValueError(
            "axial_impact needs float64 (in float32 its crushing phase's steps shrink to "
            f"nothing at any rtol): {_checks.ENABLE_FLOAT64}"
        )
    mu, phi, speed = checked_inputs(mass_ratio, force_ratio, speed, rtol, n_history)
    eta0 = _checks.non_negative("axial_ratio", axial_ratio)
    if int(string_cells) != string_cells or string_cells < 2:
        raise ValueError(f"string_cells must be an integer >= 2; got {string_cells!r}")
    if not 0.0 < string_courant <= 1.0:
        raise ValueError(f"string_courant must be in (0, 1]; got {string_courant!r}")
    args = jnp.broadcast_arrays(mu, phi, speed, eta0)
    rtol = jnp.asarray(rtol, args[0].dtype)
    options = dict(
        n_history=int(n_history),
        string_cells=int(string_cells),
        string_courant=float(string_courant),
    )

    def solve(args, attempt):
        budgets = {"budget": attempt[0], "stiff": attempt[1]}
        if args[0].ndim == 0:
            return _axial_impact(*args, rtol, **options, **budgets)
        padded = lambda *x: _axial_impact(*x[:-1], rtol, **options, **budgets)
        return solve_padded(padded, args, _CHUNK)

    result, failures, _ = solved_again(solve, args, _ATTEMPTS[0], _next_attempt, _spent)
    return raise_failures("axial_impact", result, failures, PHASES)


# The solves of a scenario: (its budgets as a multiple of `stages._BUDGETS`, the crushing
# phase in implicit steps), each tried where the one before spent a budget. Explicit steps
# four times as many first: their answers are those of the first solve's method, and the
# implicit step's Newton iteration does not get through a crushing phase that ends where
# the beam stops (V0 -> 0, where the hinge's rate g / V0 is singular), which they do
# (mass ratio 346, phi - 1 = 9.9e-4, speed 4.2, eta0 13: 10,115 explicit steps, while the
# implicit ones stall at the stop). The implicit steps take the crushing phases too stiff
# for explicit ones, phi - 1 below about 1.5e-4 (`benchmarks/solvable_range.py`).
_ATTEMPTS = ((1, False), (4, False), (16, True))


def _next_attempt(attempt, args, failures):
    """The attempt after `attempt`, or None after the last."""
    later = _ATTEMPTS.index(attempt) + 1
    return _ATTEMPTS[later] if later < len(_ATTEMPTS) else None


def _spent(failures):
    """Whether each scenario's solve spent a step budget (`failures`: its stages' codes)."""
    return np.any(np.asarray(failures) == STEPS_SPENT, axis=-1)


# The batch is padded (`padded_size`) to the next power of two up to a chunk, then to whole
# chunks, so that a few programs serve every size; and solved in vmapped chunks of this many
# scenarios, in the order of mu eta0 V^2 (heavier vehicles and a larger axial term run
# longer). One vmap over all of them ran 100 scenarios in 0.31 s and 128 in 1.07 s (a cliff
# between 120 and 124, likely its working set outgrowing a core's 1 MB L2 cache; not
# profiled); 1000 random ones (mu 0.1-10, phi 1.1-8, V 0.2-2, eta0 0.1-5) took 21.3 s as
# one vmap, 4.7 s in chunks of 64, 3.4 s sorted by mu, 2.3 s sorted by mu eta0 V^2 (2 cores).
_CHUNK = 64
