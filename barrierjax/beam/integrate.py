"""Time integration of the assembled beam, report 4.2 (iii), (4.2.39)-(4.2.45).

The report expands the displacement to third order with a constant rate of acceleration over
the step (4.2.40)-(4.2.43): this is Newmark's method with beta = 1/6, gamma = 1/2 (the
linear-acceleration method), and (4.2.44)-(4.2.45) is its effective stiffness
K* = K + 6/dt^2 M. For an undamped linear system Newmark is stable iff
omega dt <= 1 / sqrt(gamma/2 - beta) for every mode, i.e. omega_max dt <= sqrt(12) = 2 sqrt(3)
for the linear-acceleration method; the report's steps (1e-3 s with 1 in steel elements, whose
axial modes reach ~1e6 rad/s) are far beyond it. Average acceleration (beta = 1/4,
gamma = 1/2) is unconditionally stable and conserves the energy of linear systems; both are
offered, and any (beta, gamma) with gamma = 1/2.

Each step solves the nonlinear equilibrium at t + dt,

    r(u) = M a(u) + f_int(u) - F = 0,   a(u) = (u - u_n - dt v_n - dt^2 (1/2 - beta) a_n)
                                                / (beta dt^2),

by Newton's method with the consistent tangent K(u) + M / (beta dt^2) (the report's K*); the
report solves it once, linearised ("an iteration procedure within each time increment could be
carried out", p. 4.2): `iterations=0` is the report's single solve (the final step below
alone), more iterations converge. The iterations run on stopped gradients, then one Newton
step with gradients,
u = u* - J(u*)^-1 r(u*), gives the implicit function theorem's derivative at the converged u*
(J is held constant in it, exact at convergence): gradients never unroll the iterations.
With `chord` > 0 the factorised tangent is held from step to step and relinearised only
where its steps stop shrinking the residual fast (`barrierjax._solve.newton`'s chord
steps): most steps then cost residuals and back substitutions, not tangents and
factorisations. The converged answer is the same to the tolerance, and the derivative takes
J afresh at u*. It pays on a single rate-independent run (report Example 1 against
OpenSees: 1.2 to 1.8 times faster), not on a rate-dependent one, whose tangent moves with
the strain rate, nor under `vmap`, where every member refactorises when one must.

Departures from the printed scheme, and why:
- The acceleration a_n at the start of each step is recomputed from equilibrium,
  M a_n = F_n - f_int(u_n), with the step's load: a load pulse that ends (or starts) at t_n
  then enters only the steps it covers, and the mass matrix of the updated frame (the report
  updates the element frames at every step) is consistent with a_n. The residual needs
  only M a_n, and the velocity update of the trapezoidal rule (beta = gamma / 2, the
  default "newmark") none of a_n: a_n is solved for only by the other schemes.
- The load in a step is its average over the step, F = int F dt / dt, so that a rectangular
  pulse delivers its exact impulse whatever the step (the report applies the pulse as load
  increments over 10 steps of its duration).
- The material is stepped from the converged state of the last step to the current iterate
  (no drift from accumulating increments); `material="report"` steps the fibres with the
  report's alpha scheme (4.2.8)-(4.2.11), `material="implicit"` with backward Euler.
"""

import functools
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check
from .._solve.newton import newton
from .layered import SCHEMES
from .model import init_sections, internal_forces, load_average, mass_matrix, tangent_stiffness

SCHEME_PARAMETERS = {
    "report": (1.0 / 6.0, 0.5, "report"),  # linear acceleration (4.2.40)-(4.2.45)
    "linear-acceleration": (1.0 / 6.0, 0.5, "implicit"),
    "newmark": (0.25, 0.5, "implicit"),  # average acceleration
    "damped-newmark": (0.3025, 0.6, "implicit"),  # gamma = 0.6, beta = (gamma + 1/2)^2 / 4
}


def stable_step(omega_max, beta=1.0 / 6.0, gamma=0.5):
    """The largest stable step of undamped Newmark for the top frequency omega_max: inf when
    2 beta >= gamma, else 1 / (omega_max sqrt(gamma / 2 - beta)) (2 sqrt(3) / omega_max for the
    linear-acceleration method)."""
    if 2 * beta >= gamma:
        return np.inf
    return 1.0 / (omega_max * np.sqrt(gamma / 2 - beta))


class BeamHistory(eqx.Module):
    """One row per saved time (the initial state first)."""

    times: jnp.ndarray  # (n,)
    displacement: jnp.ndarray  # (n, n_dofs)
    velocity: jnp.ndarray  # (n, n_dofs)
    N: jnp.ndarray  # (n, n_el, n_pts) axial force at the element's points
    M: jnp.ndarray  # (n, n_el, n_pts) moment (M = EI kappa elastically)
    strains: jnp.ndarray  # (n, n_el, n_pts, 2): (eps_m, kappa)
    plastic_strain: Any  # (n, n_el, n_pts, n_fibres), or None for a law without it
    external_work: jnp.ndarray  # (n,) cumulative work of the loads
    residual: jnp.ndarray  # (n,) relative residual of the accepted state


def _identity_on_fixed(mask, A):
    """A with the rows and columns of the fixed dofs (`mask` False) replaced by the identity's."""
    both = mask[:, None] & mask[None, :]
    return jnp.where(both, A, jnp.eye(A.shape[0], dtype=A.dtype))


def _factor_free(free, A):
    """The LU factors of A on the free dofs (fixed rows and columns replaced by the
    identity), with the free dofs' mask, for `_solve_factored`."""
    mask = jnp.asarray(free)
    lu, _, permutation = jax.lax.linalg.lu(_identity_on_fixed(mask, A))
    return lu, permutation, mask


def _solve_factored(factors, b):
    """x with A x = b on the free dofs, zero on the fixed ones, from `_factor_free`'s A."""
    lu, permutation, mask = factors
    x = jnp.where(mask, b, jnp.zeros_like(b))[permutation][:, None]
    x = jax.lax.linalg.triangular_solve(lu, x, left_side=True, lower=True, unit_diagonal=True)
    return jax.lax.linalg.triangular_solve(lu, x, left_side=True, lower=False)[:, 0]


def _solve_free(free, A, b):
    """Solve A x = b on the free dofs (fixed rows and columns replaced by the identity)."""
    mask = jnp.asarray(free)
    return jnp.linalg.solve(_identity_on_fixed(mask, A), jnp.where(mask, b, jnp.zeros_like(b)))


# The converged point's final step takes the held tangent where Newton's steps predict a
# residual below this fraction of the tolerance after it (the polish of Newton's own final
# step, which the history's `residual` reports: below 1e-8 in the report's examples), else
# the tangent afresh (`barrierjax._solve.newton`).
_POLISH = 1e-3


class _StepParams(eqx.Module):
    """What a step's equilibrium depends on: the model, the last converged state (u,
    stress, state), u + dt v, M a at the step's start, the mass M, the load F and the
    step dt."""

    model: Any
    u: Any
    predictor: Any
    start_inertia: Any
    M: Any
    F: Any
    stress: Any
    state: Any
    dt: Any


class _Equilibrium(eqx.Module):
    """The equilibrium at the end of a step, r(u1) = M a(u1) + f_int(u1) - F on the free
    dofs, for `barrierjax._solve.newton`. With u + dt v the `predictor` and a the
    acceleration at the step's start, a(u1) = (u1 - u - dt v) / (beta dt^2) - (1/2 -
    beta) / beta a, so that M a(u1) needs M a alone, the step's start in equilibrium."""

    free: tuple[bool, ...] = eqx.field(static=True)
    beta: float = eqx.field(static=True)
    tolerance: float = eqx.field(static=True)
    material: str = eqx.field(static=True)
    material_iterations: int = eqx.field(static=True)

    def unbalanced(self, p: _StepParams, u1, f):
        """M a(u1) + f - F on the free dofs (zero on the fixed ones)."""
        inertia = p.M @ ((u1 - p.predictor) / (self.beta * p.dt**2))
        r = inertia - (0.5 - self.beta) / self.beta * p.start_inertia + f - p.F
        return jnp.where(jnp.asarray(self.free), r, jnp.zeros_like(r))

    def relative(self, r, f, F):
        """Newton's residual over the largest free internal force or load."""
        size = jnp.max(jnp.abs(jnp.where(jnp.asarray(self.free), f, 0))) + jnp.max(jnp.abs(F))
        return jnp.max(jnp.abs(r)) / (size + jnp.finfo(r.dtype).tiny)

    def forces(self, p: _StepParams, u1, tangent=False):
        """The internal forces at u1 (with the tangent stiffness: `tangent`), stepping the
        material from the last converged state."""
        forces = tangent_stiffness if tangent else internal_forces
        options = {"scheme": self.material, "iterations": self.material_iterations}
        return forces(p.model, u1, p.u, p.stress, p.state, p.dt, **options)

    def linearise(self, u1, p: _StepParams):
        """The tangent K(u1) + M / (beta dt^2), the residual, and whether it converged."""
        scale = 1 / (self.beta * p.dt**2)
        K, f, _ = self.forces(p, u1, tangent=True)
        r = self.unbalanced(p, u1, f)
        return K + p.M * scale, r, self.relative(r, f, p.F) / self.tolerance

    def residual(self, u1, p: _StepParams):
        """The residual at u1 and its size against the tolerance (converged: at most 1)."""
        f, _ = self.forces(p, u1)
        r = self.unbalanced(p, u1, f)
        return r, self.relative(r, f, p.F) / self.tolerance


def step_sizes(t_end, dt, *, pulse=None, pulse_steps=10):
    """Step sizes (numpy, static length): `pulse_steps` equal steps over [0, pulse] (the
    report's increments during the impulse), then steps of `dt` up to `t_end` (the last one
    shortened to end on t_end)."""
    t_end, dt = float(t_end), float(dt)
    if not (dt > 0 and np.isfinite(dt)):
        raise ValueError(f"dt must be positive and finite; got {dt!r}")
    if not (t_end > 0 and np.isfinite(t_end)):
        raise ValueError(f"t_end must be positive and finite; got {t_end!r}")
    steps = []
    start = 0.0
    if pulse is not None:
        pulse = float(pulse)
        if not 0 < pulse <= t_end:
            raise ValueError(f"pulse must be in (0, t_end={t_end:g}]; got {pulse!r}")
        if int(pulse_steps) < 1:
            raise ValueError(f"pulse_steps must be a positive integer; got {pulse_steps!r}")
        steps = [pulse / int(pulse_steps)] * int(pulse_steps)
        start = pulse
    n = int(np.ceil((t_end - start) / dt - 1e-9))
    rest = [dt] * n
    if n:
        rest[-1] = t_end - start - dt * (n - 1)
    return np.asarray(steps + rest)


def integrate(
    model,
    dts,
    *,
    scheme="newmark",
    beta=None,
    gamma=None,
    iterations=6,
    tolerance=1e-6,
    line_search=4,
    substeps=1,
    update_mass=True,
    material_iterations=0,
    chord=0.0,
):
    """Integrate the beam from rest over the steps `dts` (1-d, static length, may be traced).

    scheme: "report" (linear acceleration, beta = 1/6, fibres by the report's alpha scheme
    (4.2.8)-(4.2.11), as in 4.2; a law without that scheme, such as rate-independent
    plasticity, keeps its exact return map, and "report" is then "linear-acceleration"),
    "linear-acceleration" (the same with backward-Euler fibres),
    or "newmark" (average acceleration, beta = 1/4, backward-Euler fibres; the default, the
    only one stable at the report's steps). `beta`, `gamma` override the scheme's. Newton:
    up to `iterations` on stopped gradients (ending early once the relative residual
    max|r| / (max|f_int| + max|F|) is at most `tolerance`; chord steps with the tangent held
    from earlier count as iterations) plus one with gradients, each with a backtracking line
    search over up to `line_search` step lengths, the full step first
    and halved while the residual does not fall (1 = plain Newton); `chord`: the held
    tangent serves the next iteration while its steps shrink the residual to this fraction
    or less (0: a tangent at every iteration, Newton's method); `substeps` equal
    sub-steps per step (the
    history keeps the end of each step): full Newton on backward-Euler Cowper-Symonds fibres
    diverges from the predictor when a step moves a hinge far into the viscoplastic range
    (1e-3 s in Example 1), and sub-steps of about 1e-4 s converge. `material_iterations` is
    the count of (4.2.11) for the report's fibre scheme. `update_mass`: the consistent mass
    in the element frames at the start of each step (the report's updated frame), else in the
    initial frames (a constant M: average acceleration then conserves the energy of a linear
    structure exactly; the updated mass does not, its first-order change with the chord
    rotation makes v^T M v drift). Returns a `BeamHistory`."""
    if scheme not in SCHEME_PARAMETERS:
        raise ValueError(f"scheme must be one of {tuple(SCHEME_PARAMETERS)}; got {scheme!r}")
    b0, g0, material = SCHEME_PARAMETERS[scheme]
    beta = b0 if beta is None else float(beta)
    gamma = g0 if gamma is None else float(gamma)
    if not 0 < beta <= 0.5:
        raise ValueError(f"beta must be in (0, 0.5]; got {beta!r}")
    if not 0.5 <= gamma <= 1:
        raise ValueError(f"gamma must be in [0.5, 1]; got {gamma!r}")
    if int(iterations) < 0:
        raise ValueError(f"iterations must be a non-negative integer; got {iterations!r}")
    if not 0 <= chord < 1:
        raise ValueError(f"chord must be in [0, 1); got {chord!r}")
    assert material in SCHEMES
    if material == "report" and not hasattr(model.section.law, "report_update"):
        material = "implicit"  # a rate-independent law: its return map is exact
    if np.ndim(dts) != 1 or np.shape(dts)[0] < 1:
        raise ValueError(f"dts must be 1-d with at least one step; got shape {np.shape(dts)}")
    dts = check("dts", dts, lambda d: d > 0, "positive")
    substeps = int(substeps)
    if substeps < 1:
        raise ValueError(f"substeps must be a positive integer; got {substeps!r}")
    free = model.free()
    dtype = model.coords.dtype
    line_search = int(line_search)
    equilibrium = _Equilibrium(
        free=tuple(bool(b) for b in free),
        beta=beta,
        tolerance=float(tolerance),
        material=material,
        material_iterations=int(material_iterations),
    )

    start_weight = (1 - gamma) - gamma * (0.5 - beta) / beta
    # Chord steps solve with factors held from step to step; Newton's method factorises
    # within each solve (faster under `vmap`: 0.49 s against 0.63 s for 16 runs).
    if chord:
        factor, solve = functools.partial(_factor_free, free), _solve_factored
    else:
        factor, solve = (lambda J: J), functools.partial(_solve_free, free)

    def step(carry, dt):
        t, u, v, f_int, stress, state, work, factors = carry
        F = load_average(model, t, t + dt)
        M = mass_matrix(model, u if update_mass else jnp.zeros_like(u))
        start_inertia = jnp.where(jnp.asarray(free), F - f_int, 0.0)  # M a_n, in equilibrium
        if start_weight:
            a = _solve_free(free, M, start_inertia)
            # M a again: Newton's solves then wait for this one. Under `vmap`, XLA's CPU
            # runtime would otherwise run two batched LAPACK factorisations at once, and on
            # a pool of two threads (two cores) each can wait forever for the other's
            # threads (jaxlib 0.10; the gradient of 16 vmapped runs hung).
            start_inertia = M @ a
        predictor = u + dt * v

        # Newton starts from the last converged state, as OpenSees does: a constant-
        # acceleration predictor overshoots (on Example 1's first step it puts the tip
        # element's fibres at yield where the converged step is elastic) and plain Newton
        # then diverges. A line search guards the iterations near a hinge.
        params = _StepParams(model, u, predictor, start_inertia, M, F, stress, state, dt)
        held = None
        if chord:
            # The residual at u from the carried forces, without stepping the sections:
            # exact for a rate-independent law, an estimate for one that relaxes over dt
            # (so its size is not trusted: inf makes Newton take a step).
            start_residual = equilibrium.unbalanced(params, u, f_int)
            held = (factors, start_residual, jnp.full((), jnp.inf, dtype))
        solution = newton(
            equilibrium.linearise,
            equilibrium.residual,
            solve,
            u,
            params,
            iterations=int(iterations),
            halvings=max(line_search, 1) - 1,
            factor=factor,
            held=held,
            contraction=chord,
            polish=_POLISH,
        )
        u1 = solution.root
        f1, (stress1, state1, N, Mom, strains) = equilibrium.forces(params, u1)
        unbalanced = equilibrium.unbalanced(params, u1, f1)
        rel = jax.lax.stop_gradient(equilibrium.relative(unbalanced, f1, F))
        # v1 = v + dt ((1 - gamma) a + gamma a(u1)): the start's acceleration a enters with
        # this weight, zero for the trapezoidal rule (beta = gamma / 2), which then
        # needs no solve with M.
        v1 = v + gamma / beta * (u1 - predictor) / dt
        if start_weight:
            v1 = v1 + dt * start_weight * a
        work = work + jnp.dot(u1 - u, F)
        carry = (t + dt, u1, v1, f1, stress1, state1, work, solution.factors if chord else None)
        plastic = getattr(state1, "plastic_strain", None)
        return carry, (t + dt, u1, v1, N, Mom, strains, plastic, work, rel)

    stress0, state0 = init_sections(model)
    zero = jnp.zeros((), dtype)
    u0 = jnp.zeros(model.n_dofs, dtype)
    # The first step's held Jacobian is its mass term alone (the structure at rest); like
    # every held Jacobian, it serves Newton's iterations only, which carry no derivative.
    held = None
    if chord:
        mass = mass_matrix(model, u0) / (beta * (dts[0] / substeps) ** 2)
        held = _factor_free(free, jax.lax.stop_gradient(mass).astype(dtype))
    init = (zero, u0, u0, u0, stress0, state0, zero, held)
    if substeps == 1:
        _, out = jax.lax.scan(step, init, dts.astype(dtype))
    else:

        def saved_step(carry, dt):
            carry, outs = jax.lax.scan(
                lambda c, _: step(c, dt / substeps), carry, None, length=substeps
            )
            last = jax.tree.map(lambda x: x[-1], outs)
            return carry, last[:-1] + (jnp.max(outs[-1]),)

        _, out = jax.lax.scan(saved_step, init, dts.astype(dtype))
    t, u, v, N, Mom, strains, plastic, work, rel = out
    pts = (len(model.connectivity), model.n_points)

    def first(x, row):
        return jnp.concatenate([row[None].astype(x.dtype), x])

    z_pts = jnp.zeros(pts, dtype)
    plastic0 = getattr(state0, "plastic_strain", None)
    return BeamHistory(
        times=first(t, zero),
        displacement=first(u, u0),
        velocity=first(v, u0),
        N=first(N, z_pts),
        M=first(Mom, z_pts),
        strains=first(strains, jnp.zeros(pts + (2,), dtype)),
        plastic_strain=None if plastic is None else first(plastic, plastic0),
        external_work=first(work, zero),
        residual=first(rel, zero),
    )
