"""`normal_impact`, the public function of report 3.2."""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, Literal

import jax
import jax.numpy as jnp

from ... import _checks
from ..._solve.batching import PADDING_QUANTUM, solve_padded, sorted_chunks
from ..._solve.phases import SOLVED, default_solver, raise_failures
from ..._solve.sensitivity import forward_jacobian_jvp
from ...compilation_cache import stored_program
from .closed_form import quadrature_points, solve_closed_form
from .ode import PHASES, solve_ode
from .results import NormalImpact, finish_history, normal_result, rigid_barrier

if TYPE_CHECKING:
    import diffrax


_STATIC = ("method", "points", "n_history", "solver")


@stored_program
@functools.partial(jax.jit, static_argnames=_STATIC)
def _normal_impact(mu, phi, speed, rtol, *, method, points, n_history, solver):
    """(the result, the ODE's phases' failure codes: `ode.PHASES`, none for the closed
    form). `rtol` is traced: the ODE at a new tolerance does not recompile. The closed
    form depends on it only through its number of quadrature nodes, `points` (None for
    the ODE)."""
    yields = phi > 1.0
    safe_phi = jnp.where(yields, phi, 2.0)  # keeps the unused branch finite for gradients
    if method == "closed_form":
        acc, final, raw = solve_closed_form(mu, safe_phi, points=points, n_history=n_history)
        damage = 0.5 * acc.t_star
        failure = jnp.full(mu.shape + (len(PHASES),), SOLVED, jnp.int32)
    else:
        ode = lambda mu, phi, rtol: solve_ode(
            mu, phi, rtol=rtol, n_history=n_history, solver=solver
        )
        acc, final, raw = forward_jacobian_jvp(ode, n_differentiable=2)(mu, safe_phi, rtol)
        damage = final.pop("damage")
        failure = final.pop("failure")
    history = None
    if n_history:
        history = finish_history(raw, mu, safe_phi, speed, acc, damage, final["s_final"])
    result = normal_result(
        damage=damage * speed**2,
        duration=final["t_final"] * speed,
        displacement=final["w_final"] * speed**2,
        hinge=final["s_final"],
        crush_work=safe_phi * damage * speed**2,
        backing_work=final["backing_work"] * speed**2,
        hinge_work=final["hinge_work"] * speed**2,
        string_work=jnp.zeros_like(mu),
        s_star=acc.s_star,
        t_star=acc.t_star * speed,
        v_star=acc.v_star * speed,
        w_star=acc.w_star * speed**2,
        t_string=jnp.full_like(mu, jnp.inf),
        history=history,
    )
    rigid = rigid_barrier(mu, phi, speed, n_history)
    result = jax.tree.map(lambda a, b: jnp.where(yields, a, b), result, rigid)
    return result, jnp.where(yields[..., None], failure, SOLVED)


def checked_inputs(mass_ratio, force_ratio, speed, rtol, n_history):
    """The checks that `normal_impact` and `axial_impact` share: the options, then the
    inputs, as arrays."""
    _checks.tolerance("rtol", rtol)
    _checks.history_samples(n_history)
    return (
        _checks.positive("mass_ratio", mass_ratio),
        _checks.positive("force_ratio", force_ratio),
        _checks.positive("speed", speed),
    )


def normal_impact(
    mass_ratio,
    force_ratio,
    speed,
    *,
    method: Literal["closed_form", "ode"] = "closed_form",
    rtol: float = 1e-8,
    n_history: int = 0,
    solver: diffrax.AbstractSolver | None = None,
) -> NormalImpact:
    """Normal impact of a rigid-plastic vehicle on a rigid-plastic beam on a rigid-plastic
    backing (report 3.2), in the report's dimensionless variables.

    **Arguments:**

    - `mass_ratio`: mu = M / (m L) (3.2, after 3.2.8), positive.
    - `force_ratio`: phi = P0 / P_b, positive; phi <= 1 is the report's trivial case
      (rigid barrier, the vehicle alone crushes) and is returned, not refused.
    - `speed`: V0, the vehicle's dimensionless impact speed, positive.
    - `method`: `"closed_form"` ((3.2.11)-(3.2.20), quadrature in S with the end
      singularity at S = alpha integrated exactly) or `"ode"` (diffrax, one solve per
      phase, switching on real-valued events).
    - `rtol`: relative tolerance: of the ODE solver (a new one runs the same compiled
      program), or the target of the quadrature (which sets its number of nodes).
    - `n_history`: number of saved samples per phase (0: none, the cheapest).
    - `solver`: diffrax solver for `method="ode"` (default `diffrax.Tsit5()`).

    With axial force (report 3.4) the model is `barrierjax.hinge.axial_impact`.

    Scalars, or arrays of one shape (solved in cache-sized vmapped chunks: the fastest
    way to run a large sweep; padded with copies to the next power of two, or above 256
    to the next multiple of 256, so that sweeps of nearby sizes share one compiled
    program; on a CPU, 1,024 scenarios or more in parts run side by side, one a core);
    `jax.vmap` and `jax.grad` work with respect to any argument. A failed ODE solve (a
    spent step budget, say) raises a `RuntimeError` naming the phase and the scenario;
    inside a caller's `jit`, `vmap` or `grad`, an error where the program runs.
    """
    _checks.solve_method(method)
    mu, phi, speed = checked_inputs(mass_ratio, force_ratio, speed, rtol, n_history)
    if not jnp.shape(mu) == jnp.shape(phi) == jnp.shape(speed):  # (else no program to run)
        mu, phi, speed = jnp.broadcast_arrays(mu, phi, speed)
    options = dict(
        method=method,
        points=quadrature_points(rtol) if method == "closed_form" else None,
        n_history=int(n_history),
        solver=default_solver(solver) if method == "ode" else None,
    )
    rtol = _checks.float_array(rtol, mu.dtype)
    if mu.ndim == 0:
        result, failures = _normal_impact(mu, phi, speed, rtol, **options)
    else:
        chunked = lambda mu, phi, speed, _: _normal_impact_chunked(mu, phi, speed, rtol, **options)
        result, failures = solve_padded(chunked, (mu, phi, speed), PADDING_QUANTUM)
    return raise_failures("normal_impact", result, failures, PHASES)


# Array inputs are solved in vmapped chunks of this many scenarios: a chunk's working set
# stays in cache, which on a 2-core CPU makes 10^5 ODE solves about four times faster
# than one vmap over all of them (benchmarks/normal_impact.py).
_CHUNK = {"closed_form": 8192, "ode": 2048}


@functools.partial(jax.jit, static_argnames=_STATIC)
def _normal_impact_chunked(mu, phi, speed, rtol, **options):
    solve = lambda mu, phi, speed: _normal_impact(mu, phi, speed, rtol, **options)
    if options["method"] == "closed_form":
        return jax.lax.map(lambda x: solve(*x), (mu, phi, speed), batch_size=_CHUNK["closed_form"])
    # A vmapped solve steps until its slowest member is done. The decelerative phase's step
    # count grows with ln(alpha/S*) ~ ln(phi), so chunks of neighbouring phi waste fewer
    # steps: 1.8x faster over 10^5 random scenarios of the property-test ranges.
    return sorted_chunks(solve, (mu, phi, speed), phi, _CHUNK["ode"])
