r"""Normal impact of a rigid-plastic vehicle on a rigid-plastic beam on a rigid-plastic backing.

Report section 3.2. A beam of mass m per unit length and plastic moment M0 rests on a
backing that yields at q0 per unit length; a vehicle of mass M that crushes at the force
P0 strikes it at speed v. Dimensionless variables (after 3.2.8; docs/errata.md, 3.3.14):

    length L = 2 (M0/q0)^(1/2),  force P_b = 4 (M0 q0)^(1/2),
    time t0 = m^(1/2) M0^(1/4) / q0^(3/4),  velocity L/t0,  energy P_b L,
    mass ratio mu = M / (m L),  force ratio phi = P0 / P_b.

Equations of motion of the deforming half-beam 0 < x < xi(t), with its velocity field
v = v0 (1 - x/xi) (3.2.1), re-derived from (3.2.3)-(3.2.4) (docs/errata.md, 3.2.8):

    a        = 2P/(m xi) - 12 M0/(m xi^2) - q0/m                    (3.2.7)
    v0 dxi/dt = 12 M0/(m xi) - q0 xi/m - P/m                          (3.2.8, corrected)

Accelerative phase (P = P0, xi fixed): q0 xi^2 + P0 xi - 12 M0 = 0 (docs/errata.md, 3.2.10), so

    S* = (phi^2 + 3)^(1/2) - phi,   V' = (phi - S*)/S*,   vehicle V_v' = -phi/mu,   (3.2.11)-(3.2.12)

until the velocities meet at T* = mu V0 S* / (phi S* + mu (phi - S*)) (3.2.14), with
V* = (phi - S*) T* / S* (3.2.13) and W* = (phi - S*) T*^2 / (2 S*).

Decelerative phase (vehicle and beam move together, P = -M a):

    V'  = -(S^2 + 3) / (2 S (S + 2 mu))                               (3.2.15)
    V S' = -p(S) / (2 S (S + 2 mu)),  p(S) = S^3 + 3 mu S^2 - 3 S - 3 mu     (3.2.16)
         = -(S - alpha)(S + beta)(S + gamma) ...                      (3.2.17)

whose quotient integrates to V(S) (3.2.18)-(3.2.19) and gives T(S) by quadrature
(3.2.20). The motion stops when S reaches alpha, the positive root of p, at T**.

Vehicle damage (crush) is D = V0 T* / 2, so D / V0^2 = T* / (2 V0): the printed closed
form for D / V0^2 lacks this factor 1/2 (docs/errata.md, 3.2 damage).

Energy (in units of P_b L): the vehicle's kinetic energy mu V0^2 / 2 equals the crush
work phi D, the backing work (1/2) integral V S dT, the hinge work (1/2) integral V/S dT
(four hinges dissipate 4 M0 v0/xi) and the beam's kinetic energy V^2 S / 3.

Both methods work in the speed-free variables tau = T/V0, v = V/V0, w = W/V0^2 (the
report's own observation after 3.2.20: for fixed S, T and V are proportional to V0 and
W to V0^2), so the speed only rescales the answer and every member of a batch costs the
same whatever its speed.

`method="closed_form"`: the integrals in S are split at S_m = S* + (alpha - S*)/4. On
[S*, S_m] a Gauss rule in z = ln(S + beta) resolves the near-singular factor
(S + beta)^(B - 1) of light, hard-hit barriers; on [S_m, alpha] product integration
integrates the end singularity (alpha - S)^(A - 1) (or ^(2A - 1) for displacement and
work) exactly, in place of the report's truncated series for the last step.

`method="ode"`: diffrax, one solve per phase. The accelerative phase ends on a
real-valued event (the relative velocity of vehicle and beam). In time T, the
decelerative phase is singular at its end (S' -> 0/0 as V -> 0, and S(T) is not smooth
there); with the independent variable sigma = ln(V*/V) and the state chi = A ln(alpha - S)
it is smooth and non-stiff for every mass ratio, so it is integrated to
sigma_end = ln(1/rtol) + 3 and the last e^-sigma_end of the velocity is added analytically
(`_complete_at_rest`).
"""

import functools
import math
from typing import Literal

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from jaxtyping import Array, Float

from .. import _checks
from .._custom_types import Scalar, Vector
from .._solve.batching import sorted_chunks
from .._solve.phases import sigma_end as _sigma_end
from .._solve.phases import solve_phase
from .._solve.quadrature import gauss_legendre, jacobi_product_nodes, jacobi_product_weights
from .._solve.sensitivity import forward_jacobian_jvp
from .axial import axial_impact


class NormalImpactHistory(eqx.Module):
    """Time histories of a normal impact, dimensionless (report 3.2 scales).

    The first half of the samples covers the accelerative phase, the second the
    decelerative phase. Energies are in units of P_b L.

    With axial force (report 3.4) a third block of `n_history` samples covers the
    plastic-string stage, before the final sample at rest; a stage that does not occur
    repeats the state it would have started from. `beam_kinetic_energy` is then the
    string's in that block, `string_work` the plastic work of stretching it since
    `t_string`, and `string_profile` (n_history, cells + 1) its displacement at the
    nodes X_j = s_final j / cells of the half-span during the string stage, and
    `string_flow_rule` (cells + 1) the share of each node's moving time in which the
    plastic flow lies outside the flow rule's corner cone, N0 eps' >= 2 M0 |kappa'|
    (the report's (3.4.49), corrected: `string.py`).
    """

    time: Vector
    vehicle_velocity: Vector
    barrier_velocity: Vector
    hinge: Vector
    displacement: Vector
    contact_force: Vector
    crush: Vector
    backing_work: Vector
    hinge_work: Vector
    beam_kinetic_energy: Vector
    vehicle_kinetic_energy: Vector
    axial_force: Vector | None = None  # N/N0, with axial force (report 3.4) only
    string_work: Vector | None = None
    string_profile: Float[Array, "samples nodes"] | None = None
    string_flow_rule: Float[Array, " nodes"] | None = None


class NormalImpact(eqx.Module):
    """Result of `normal_impact`, dimensionless (report 3.2 notation in brackets).

    - `s_star, t_star, v_star, w_star`: hinge distance, time, beam velocity and beam
      displacement under the vehicle at the end of the accelerative phase (S*, T*, V*, W*);
    - `damage`: vehicle crush D;
    - `s_final, t_final, w_final`: final hinge distance (alpha), time of rest (T**) and
      final displacement under the vehicle;
    - `crush_work, backing_work, hinge_work`: where the vehicle's kinetic energy
      mu V0^2 / 2 went, in units of P_b L (with axial force the hinge work includes the
      hinges' stretching, N times the beam's elongation);
    - `t_string`: with axial force (report 3.4), the time at which N reaches N0 and the
      beam becomes a plastic string; `inf` if it never does (and always without);
    - `string_work`: the plastic work of N0 stretching the string after `t_string`
      (3.4.45), 0 without a string stage. The final state is then the string's: `s_final`
      is the span that moved, `damage` includes the crush in the string stage and, where
      the string began while the vehicle still crushed, `t_star`, `v_star` and `w_star`
      describe the beam at `t_string`;
    - `history`: a `NormalImpactHistory`, or None when not requested.

    With force ratio <= 1 the barrier stays rigid (no hinge: S = 0, W = 0) and the
    vehicle alone crushes to rest.
    """

    s_star: Scalar
    t_star: Scalar
    v_star: Scalar
    w_star: Scalar
    damage: Scalar
    s_final: Scalar
    t_final: Scalar
    w_final: Scalar
    crush_work: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    t_string: Scalar
    string_work: Scalar
    history: NormalImpactHistory | None


# --------------------------------------------------------------------------------------
# Accelerative phase, (3.2.9)-(3.2.14), per unit impact speed.


class _Accelerative(eqx.Module):
    s_star: Scalar
    acceleration: Scalar  # beam, (phi - S*)/S*
    deceleration: Scalar  # vehicle, phi/mu
    t_star: Scalar
    v_star: Scalar
    w_star: Scalar


def _accelerative_phase(mu, phi) -> _Accelerative:
    root = jnp.sqrt(phi**2 + 3.0)
    s_star = 3.0 / (root + phi)  # = root - phi without cancellation at large phi
    # (phi - S*)/S* with phi - S* = 3 (phi^2 - 1)/(2 phi + root), exact as phi -> 1+.
    acceleration = 3.0 * (phi - 1.0) * (phi + 1.0) / ((2.0 * phi + root) * s_star)
    deceleration = phi / mu
    t_star = 1.0 / (acceleration + deceleration)
    return _Accelerative(
        s_star=s_star,
        acceleration=acceleration,
        deceleration=deceleration,
        t_star=t_star,
        v_star=acceleration * t_star,
        w_star=0.5 * acceleration * t_star**2,
    )


# --------------------------------------------------------------------------------------
# Decelerative phase, (3.2.15)-(3.2.20).


@jax.custom_jvp
def _largest_root(mu):
    """alpha: the positive root of p(S) = S^3 + 3 mu S^2 - 3 S - 3 mu, in [1, sqrt(3)].

    p is increasing and convex on [1, inf) and p(sqrt 3) = 6 mu >= 0, so Newton's method
    from sqrt(3) decreases monotonically onto alpha; eight steps reach rounding for every
    mu >= 0. Differentiated implicitly, not through the iterations.
    """

    def newton(s, _):
        p = s**3 + 3.0 * mu * s**2 - 3.0 * s - 3.0 * mu
        dp = 3.0 * s**2 + 6.0 * mu * s - 3.0
        return s - p / dp, None

    start = jnp.full_like(mu, jnp.sqrt(3.0))
    return jax.lax.scan(newton, start, None, length=8)[0]


@_largest_root.defjvp
def _largest_root_jvp(primals, tangents):
    (mu,), (dmu,) = primals, tangents
    alpha = _largest_root(mu)
    # dp/dS dalpha + dp/dmu dmu = 0
    return alpha, -(alpha**2 - 1.0) / (alpha**2 + 2.0 * mu * alpha - 1.0) * dmu


class _Decelerative(eqx.Module):
    mu: Scalar
    alpha: Scalar
    beta: Scalar
    gamma: Scalar
    a: Scalar  # exponents of (3.2.19)
    b: Scalar
    c: Scalar
    s_star: Scalar
    v_star: Scalar

    def log_ratio(self, s, log_beta_ratio=None):
        """B ln((S+beta)/(S*+beta)) + C ln((S+gamma)/(S*+gamma)); the first logarithm may
        be passed in where the caller already has it."""
        if log_beta_ratio is None:
            log_beta_ratio = jnp.log1p((s - self.s_star) / (self.s_star + self.beta))
        return self.b * log_beta_ratio + self.c * jnp.log1p((s - self.s_star) / (self.s_star + self.gamma))

    def hinge_from_chi(self, chi):
        """S from the ODE state chi = A ln(alpha - S)."""
        return self.alpha - jnp.exp(chi / self.a)

    def time_per_velocity(self, s):
        """-dT/dV = 2 S (S + 2 mu) / (S^2 + 3), the inverse of (3.2.15)."""
        return 2.0 * s * (s + 2.0 * self.mu) / (s**2 + 3.0)

    def lever(self, s):
        """2 S (S + 2 mu) / ((S + beta)(S + gamma)), so that dT/dS = lever V / (alpha - S)
        (3.2.16, with p(S) factored as in 3.2.17)."""
        return 2.0 * s * (s + 2.0 * self.mu) / ((s + self.beta) * (s + self.gamma))


def _decelerative_constants(mu, acc: _Accelerative) -> _Decelerative:
    alpha = _largest_root(mu)
    # Vieta: beta + gamma = 3 mu + alpha, beta gamma = 3 mu / alpha (no cancellation).
    total = 3.0 * mu + alpha
    gamma = 0.5 * (total + jnp.sqrt(total**2 - 12.0 * mu / alpha))
    beta = 3.0 * mu / (alpha * gamma)
    return _Decelerative(
        mu=mu,
        alpha=alpha,
        beta=beta,
        gamma=gamma,
        a=(3.0 + alpha**2) / ((alpha + beta) * (alpha + gamma)),
        b=(3.0 + beta**2) / ((alpha + beta) * (beta - gamma)),
        c=(3.0 + gamma**2) / ((gamma + alpha) * (gamma - beta)),
        s_star=acc.s_star,
        v_star=acc.v_star,
    )


def _integrate(s, dtau, dw):
    """(tau, w, backing work, hinge work) from the weighted integrands of tau and w at the
    nodes s (last axis): dW = V dT, and the works are (1/2) S dW and (1/2) dW / S."""
    return jnp.stack(
        [
            jnp.sum(dtau, -1),
            jnp.sum(dw, -1),
            0.5 * jnp.sum(dw * s, -1),
            0.5 * jnp.sum(dw / s, -1),
        ],
        axis=-1,
    )


def _head_integrals(dec: _Decelerative, s_end, n: int):
    """(tau, w, backing, hinge) integrated over [S*, s_end], s_end < alpha, by Gauss in
    z = ln(S + beta), where dS = (S + beta) dz and ln((S+beta)/(S*+beta)) = z - z(S*).

    dtau/dS = 2 S (S + 2 mu) V / ((alpha - S)(S + beta)(S + gamma))   (3.2.20), with V from
    (3.2.19) as V* exp(A ln u + B ln(..) + C ln(..)), u = (alpha - S)/(alpha - S*)."""
    z_start = jnp.log(dec.s_star + dec.beta)
    z, weights = gauss_legendre(n, z_start, jnp.log(s_end + dec.beta))
    s = jnp.exp(z) - dec.beta
    log_u = jnp.log((dec.alpha - s) / (dec.alpha - dec.s_star))
    velocity = dec.v_star * jnp.exp(dec.a * log_u + dec.log_ratio(s, z - z_start[..., None]))
    dtau = weights * (s + dec.beta) * dec.lever(s) * velocity / (dec.alpha - s)
    return _integrate(s, dtau, dtau * velocity)


def _tail_integrals(dec: _Decelerative, log_gap, n: int):
    """(tau, w, backing, hinge) integrated from S to alpha by product integration with the
    exact weights r^(A-1) and r^(2A-1), r = (alpha - S')/(alpha - S). The start S is given
    by log_gap = ln((alpha - S)/(alpha - S*)), which stays exact where alpha - S is below
    the rounding of alpha (heavy vehicles near rest)."""
    h = (dec.alpha - dec.s_star) * jnp.exp(log_gap)
    s = dec.alpha - h[..., None] * jacobi_product_nodes(n)
    # V = V* rho^A r^A exp(log_ratio), rho = h / (alpha - S*): smooth part times r^A.
    smooth_velocity = dec.v_star * jnp.exp(dec.a * log_gap[..., None] + dec.log_ratio(s))
    dtau = jacobi_product_weights(n, dec.a - 1.0) * dec.lever(s) * smooth_velocity
    dw = jacobi_product_weights(n, 2.0 * dec.a - 1.0) * dec.lever(s) * smooth_velocity**2
    return _integrate(s, dtau, dw)


def _split(dec: _Decelerative):
    """S_m = alpha - 0.75 (alpha - S*), where the head quadrature hands over to the tail,
    and its log gap ln((alpha - S_m)/(alpha - S*)) = ln 0.75."""
    s_mid = dec.alpha - 0.75 * (dec.alpha - dec.s_star)
    return s_mid, jnp.log(jnp.asarray(0.75, s_mid.dtype))


def _quadrature_points(rtol: float) -> int:
    """Nodes per segment. The rules converge geometrically; against a 30-digit reference
    over the property-test range (benchmarks/normal_impact.py) the largest relative error
    is 7e-9 with 10 nodes, 3e-10 with 12 and 5e-12 with 15, so 1.5 nodes per digit keeps
    a margin of more than ten."""
    return int(min(48, max(8, math.ceil(-1.5 * math.log10(rtol)))))


# --------------------------------------------------------------------------------------
# Closed form.


def _closed_form(mu, phi, *, rtol, n_history):
    acc = _accelerative_phase(mu, phi)
    dec = _decelerative_constants(mu, acc)
    n = _quadrature_points(rtol)
    s_mid, log_split = _split(dec)
    tau, w, backing, hinge = _head_integrals(dec, s_mid, n) + _tail_integrals(dec, log_split, n)
    t_star, w_star, s_star = acc.t_star, acc.w_star, acc.s_star
    final = dict(
        s_final=dec.alpha,
        t_final=t_star + tau,
        w_final=w_star + w,
        backing_work=0.5 * w_star * s_star + backing,
        hinge_work=0.5 * w_star / s_star + hinge,
    )
    history = None
    if n_history:
        history = _closed_form_history(acc, dec, n, final, n_history)
    return acc, final, history


def _history_gaps(dec, n_history):
    """ln((alpha - S)/(alpha - S*)) at the decelerative samples before rest, in time order:
    half uniform in S (the growth of the deformed zone, which heavy vehicles complete in a
    small fraction of the duration), half uniform in u^A = ((alpha-S)/(alpha-S*))^A, which
    is about uniform in V near rest."""
    half = n_history // 2
    in_s = jnp.log1p(-jnp.linspace(0.0, 1.0, half, endpoint=False))
    in_v = jnp.log1p(-jnp.linspace(0.0, 1.0, n_history - half, endpoint=False)[1:]) / dec.a
    return -jnp.sort(-jnp.concatenate([in_s, in_v]))


def _closed_form_history(acc, dec, n, final, n_history):
    """Accelerative phase on a uniform grid in T; decelerative phase at `_history_gaps`
    and at rest, each point by the better-conditioned of "head from S*" or "total minus
    tail to alpha"."""
    t1 = acc.t_star * jnp.linspace(0.0, 1.0, n_history)
    v1 = acc.acceleration * t1
    w1 = 0.5 * acc.acceleration * t1**2
    first = dict(
        time=t1,
        vehicle_velocity=1.0 - acc.deceleration * t1,
        barrier_velocity=v1,
        hinge=jnp.full_like(t1, acc.s_star),
        displacement=w1,
        backing_work=0.5 * w1 * acc.s_star,
        hinge_work=0.5 * w1 / acc.s_star,
    )
    log_gap = _history_gaps(dec, n_history)
    s_mid, log_split = _split(dec)
    s = dec.alpha - (dec.alpha - dec.s_star) * jnp.exp(log_gap)
    head = _head_integrals(dec, jnp.minimum(s, s_mid), n)
    totals = jnp.stack(
        [final["t_final"] - acc.t_star, final["w_final"] - acc.w_star]
        + [final[key] - first[key][-1] for key in ("backing_work", "hinge_work")]
    )
    tail = totals - _tail_integrals(dec, jnp.minimum(log_gap, log_split), n)
    cumulative = jnp.where((log_gap >= log_split)[:, None], head, tail)
    v2 = dec.v_star * jnp.exp(dec.a * log_gap + dec.log_ratio(s))
    second = dict(
        time=acc.t_star + cumulative[:, 0],
        vehicle_velocity=v2,
        barrier_velocity=v2,
        hinge=s,
        displacement=acc.w_star + cumulative[:, 1],
        backing_work=first["backing_work"][-1] + cumulative[:, 2],
        hinge_work=first["hinge_work"][-1] + cumulative[:, 3],
    )
    at_rest = dict(
        time=final["t_final"],
        vehicle_velocity=jnp.zeros_like(v2[0]),
        barrier_velocity=jnp.zeros_like(v2[0]),
        hinge=final["s_final"],
        displacement=final["w_final"],
        backing_work=final["backing_work"],
        hinge_work=final["hinge_work"],
    )
    return {key: jnp.concatenate([first[key], second[key], at_rest[key][None]]) for key in first}


# --------------------------------------------------------------------------------------
# Time integration with diffrax.


class _ContactState(eqx.Module):
    """Accelerative-phase state, per unit impact speed. Named scalar leaves rather than one
    vector: under vmap diffrax then works on contiguous batch-length arrays, about twice as
    fast as on a (batch, 6) array."""

    vehicle_velocity: Scalar
    beam_velocity: Scalar
    displacement: Scalar
    crush: Scalar
    backing_work: Scalar
    hinge_work: Scalar


class _RunOutState(eqx.Module):
    """Decelerative-phase state: chi = A ln(alpha - S) and the accumulated quantities."""

    chi: Scalar
    time: Scalar
    displacement: Scalar
    backing_work: Scalar
    hinge_work: Scalar


def _accelerative_field(theta, y: _ContactState, acc: _Accelerative) -> _ContactState:
    """Rates against theta = tau / tau_c, where tau_c = 1 / (phi/mu + (phi - S*)/S*) is the
    time the two constant accelerations take to close a unit relative speed: every
    scenario's phase then lasts about one unit, so the event's tolerances mean the same
    for all."""
    beam = y.beam_velocity
    return _ContactState(
        vehicle_velocity=-acc.deceleration * acc.t_star,
        beam_velocity=acc.acceleration * acc.t_star,
        displacement=beam * acc.t_star,
        crush=(y.vehicle_velocity - beam) * acc.t_star,
        backing_work=0.5 * beam * acc.s_star * acc.t_star,
        hinge_work=0.5 * beam / acc.s_star * acc.t_star,
    )


def _decelerative_field(sigma, y: _RunOutState, dec: _Decelerative) -> _RunOutState:
    """(3.2.15)-(3.2.16) with sigma = ln(V*/V) as the independent variable. With
    V = V* e^-sigma,

        dtau/dsigma = V * 2 S (S + 2 mu) / (S^2 + 3)
        dchi/dsigma = -A (S + beta)(S + gamma) / (S^2 + 3)      (= A p(S) / ((S^2+3)(alpha-S)))

    Both are smooth and non-stiff for every mass ratio: chi falls at a rate near 1, and
    alpha - S = exp(chi / A) underflows harmlessly where A is small (heavy vehicles).
    """
    s = dec.hinge_from_chi(y.chi)
    v = dec.v_star * jnp.exp(-sigma)
    dtau = v * dec.time_per_velocity(s)
    dw = v * dtau
    return _RunOutState(
        chi=-dec.a * (s + dec.beta) * (s + dec.gamma) / (s**2 + 3.0),
        time=dtau,
        displacement=dw,
        backing_work=0.5 * dw * s,
        hinge_work=0.5 * dw / s,
    )


def _complete_at_rest(dec, sigma_end, y: _RunOutState):
    """Add the motion from V_end = V* e^-sigma_end to rest analytically, with S frozen at
    its value at sigma_end and so V' constant: the remainders are V_end g, V_end^2 g / 2,
    ... with g = 2 S (S + 2 mu) / (S^2 + 3).

    The remainders are at most e^-sigma_end of the totals, so their error is too, whatever
    S does afterwards; near alpha, where S is usually frozen by then, it is far smaller.
    (S need not be near alpha: a light vehicle on a strong barrier starts at S* ~ beta
    ~ mu, where S grows at a rate of order mu in sigma.)
    """
    s = dec.hinge_from_chi(y.chi)
    v = dec.v_star * jnp.exp(-sigma_end)
    g = dec.time_per_velocity(s)
    dw = 0.5 * v**2 * g
    return dict(
        s_final=s,
        t_final=y.time + v * g,
        w_final=y.displacement + dw,
        backing_work=y.backing_work + 0.5 * dw * s,
        hinge_work=y.hinge_work + 0.5 * dw / s,
    )


def _ode_phases(mu, phi, *, rtol, solver, dense=False):
    """The two diffrax solves, in the speed-free variables; also used by the benchmark for
    step counts."""
    acc = _accelerative_phase(mu, phi)
    dec = _decelerative_constants(mu, acc)
    options = dict(solver=solver, rtol=rtol, atol=1e-3 * rtol, dense=dense)
    zero = jnp.zeros_like(acc.t_star)
    first = solve_phase(
        _accelerative_field,
        _ContactState(zero + 1.0, zero, zero, zero, zero, zero),
        zero,
        zero + 2.0,  # a bracket for the switch, which the event locates
        acc,
        switch=lambda t, y, args: y.vehicle_velocity - y.beam_velocity,
        max_steps=64,
        **options,
    )
    contact = first.y_end
    time_unit = acc.t_star
    acc = eqx.tree_at(
        lambda a: (a.t_star, a.v_star, a.w_star),
        acc,
        (first.t_end * time_unit, contact.beam_velocity, contact.displacement),
    )
    dec = eqx.tree_at(lambda d: d.v_star, dec, acc.v_star)
    second = solve_phase(
        _decelerative_field,
        _RunOutState(
            chi=dec.a * jnp.log(dec.alpha - acc.s_star),
            time=acc.t_star,
            displacement=acc.w_star,
            backing_work=contact.backing_work,
            hinge_work=contact.hinge_work,
        ),
        zero,
        zero + _sigma_end(rtol),
        dec,
        max_steps=4096,
        **options,
    )
    return acc, dec, time_unit, first, second


def _ode(mu, phi, *, rtol, n_history, solver):
    acc, dec, time_unit, first, second = _ode_phases(
        mu, phi, rtol=rtol, solver=solver, dense=bool(n_history)
    )
    final = _complete_at_rest(dec, _sigma_end(rtol), second.y_end)
    final["damage"] = first.y_end.crush
    history = None
    if n_history:
        history = _ode_history(first, second, dec, final, n_history, _sigma_end(rtol), time_unit)
    return acc, final, history


def _ode_history(first, second, dec, final, n_history, sigma_end, time_unit):
    """Accelerative phase uniform in T; decelerative phase in sigma, ending at rest."""
    k = jnp.linspace(0.0, 1.0, n_history)
    contact = jax.vmap(first.dense.evaluate)(first.t_end * k)
    # Half the samples uniform in V; half in sigma/A, the scale on which S grows.
    half = n_history // 2
    in_v = -jnp.log1p(-jnp.linspace(0.0, 1.0, n_history - half, endpoint=False)[1:])
    in_s = 10.0 * dec.a * jnp.linspace(0.0, 1.0, half, endpoint=False)
    sigma = jnp.minimum(jnp.sort(jnp.concatenate([in_s, in_v])), sigma_end)
    run_out = jax.vmap(second.dense.evaluate)(sigma)
    v2 = jnp.append(dec.v_star * jnp.exp(-sigma), 0.0)

    def joined(first_phase, second_phase, at_rest):
        return jnp.concatenate([first_phase, second_phase, at_rest[None]])

    return dict(
        time=joined(first.t_end * time_unit * k, run_out.time, final["t_final"]),
        vehicle_velocity=jnp.concatenate([contact.vehicle_velocity, v2]),
        barrier_velocity=jnp.concatenate([contact.beam_velocity, v2]),
        hinge=joined(jnp.full_like(k, dec.s_star), dec.hinge_from_chi(run_out.chi), final["s_final"]),
        displacement=joined(contact.displacement, run_out.displacement, final["w_final"]),
        backing_work=joined(contact.backing_work, run_out.backing_work, final["backing_work"]),
        hinge_work=joined(contact.hinge_work, run_out.hinge_work, final["hinge_work"]),
    )


# --------------------------------------------------------------------------------------
# Public function.


def _rigid_barrier(mu, phi, speed, n_history, string_cells=None) -> NormalImpact:
    """phi <= 1: the barrier never yields and the vehicle crushes to rest at P0 (with
    `string_cells`, the history has the blocks and fields of one with axial force, at
    N/N0 = 0 and without a string)."""
    zero = jnp.zeros_like(mu)
    t_stop = mu * speed / phi
    damage = 0.5 * mu * speed**2 / phi
    history = None
    if n_history:
        axial = string_cells is not None
        t = t_stop * jnp.linspace(0.0, 1.0, (3 if axial else 2) * n_history)
        vehicle = speed - phi / mu * t
        zeros = jnp.zeros_like(t)
        history = NormalImpactHistory(
            time=t,
            vehicle_velocity=vehicle,
            barrier_velocity=zeros,
            hinge=zeros,
            displacement=zeros,
            contact_force=jnp.full_like(t, phi),
            crush=speed * t - 0.5 * phi / mu * t**2,
            backing_work=zeros,
            hinge_work=zeros,
            beam_kinetic_energy=zeros,
            vehicle_kinetic_energy=0.5 * mu * vehicle**2,
            axial_force=zeros if axial else None,
            string_work=zeros if axial else None,
            string_profile=jnp.zeros((n_history, string_cells + 1)) if axial else None,
            string_flow_rule=jnp.zeros(string_cells + 1) if axial else None,
        )
    return NormalImpact(
        s_star=zero,
        t_star=t_stop,
        v_star=zero,
        w_star=zero,
        damage=damage,
        s_final=zero,
        t_final=t_stop,
        w_final=zero,
        crush_work=phi * damage,
        backing_work=zero,
        hinge_work=zero,
        t_string=zero + jnp.inf,
        string_work=zero,
        history=history,
    )


def _finish_history(raw, mu, phi, speed, acc, damage_per_speed2) -> NormalImpactHistory:
    """Add the contact force and the crush of 3.2 to speed-free histories, and scale."""
    s = raw["hinge"]
    n = s.shape[0] // 2
    in_first = jnp.arange(2 * n) < n
    force = jnp.where(in_first, phi, mu * (s**2 + 3.0) / (2.0 * s * (s + 2.0 * mu)))
    t1 = jnp.minimum(raw["time"], acc.t_star)
    crush = t1 - 0.5 * (acc.deceleration + acc.acceleration) * t1**2
    crush = jnp.where(in_first, crush, damage_per_speed2)
    return _scaled_history(dict(raw, contact_force=force, crush=crush), mu, speed)


def _scaled_history(raw, mu, speed) -> NormalImpactHistory:
    """Speed-free histories (tau, v, w and works per unit speed) scaled by the impact
    speed, with the kinetic energies."""
    vehicle = raw["vehicle_velocity"] * speed
    beam = raw["barrier_velocity"] * speed
    if "beam_kinetic_energy" in raw:
        beam_kinetic_energy = raw["beam_kinetic_energy"] * speed**2
    else:
        beam_kinetic_energy = beam**2 * raw["hinge"] / 3.0  # v = V (1 - |X|/S) (3.2.1)
    string_work = raw.get("string_work")
    return NormalImpactHistory(
        time=raw["time"] * speed,
        vehicle_velocity=vehicle,
        barrier_velocity=beam,
        hinge=raw["hinge"],
        displacement=raw["displacement"] * speed**2,
        contact_force=raw["contact_force"],
        crush=raw["crush"] * speed**2,
        backing_work=raw["backing_work"] * speed**2,
        hinge_work=raw["hinge_work"] * speed**2,
        beam_kinetic_energy=beam_kinetic_energy,
        vehicle_kinetic_energy=0.5 * mu * vehicle**2,
        axial_force=raw.get("axial_force"),
        string_work=None if string_work is None else string_work * speed**2,
        string_profile=raw["profile"] * speed**2 if "profile" in raw else None,
        string_flow_rule=raw.get("flow_rule"),
    )


@functools.partial(jax.jit, static_argnames=("method", "rtol", "n_history", "solver"))
def _normal_impact(mu, phi, speed, *, method, rtol, n_history, solver):
    yields = phi > 1.0
    safe_phi = jnp.where(yields, phi, 2.0)  # keeps the unused branch finite for gradients
    if method == "closed_form":
        acc, final, raw = _closed_form(mu, safe_phi, rtol=rtol, n_history=n_history)
        damage = 0.5 * acc.t_star
    else:
        ode = functools.partial(_ode, rtol=rtol, n_history=n_history, solver=solver)
        acc, final, raw = forward_jacobian_jvp(ode)(mu, safe_phi)
        damage = final.pop("damage")
    history = None
    if n_history:
        history = _finish_history(raw, mu, safe_phi, speed, acc, damage)
    result = NormalImpact(
        s_star=acc.s_star,
        t_star=acc.t_star * speed,
        v_star=acc.v_star * speed,
        w_star=acc.w_star * speed**2,
        damage=damage * speed**2,
        s_final=final["s_final"],
        t_final=final["t_final"] * speed,
        w_final=final["w_final"] * speed**2,
        crush_work=safe_phi * damage * speed**2,
        backing_work=final["backing_work"] * speed**2,
        hinge_work=final["hinge_work"] * speed**2,
        t_string=jnp.full_like(mu, jnp.inf),
        string_work=jnp.zeros_like(mu),
        history=history,
    )
    rigid = _rigid_barrier(mu, phi, speed, n_history)
    return jax.tree.map(lambda a, b: jnp.where(yields, a, b), result, rigid)


@functools.partial(jax.jit, static_argnames=("n_history", "string_cells", "string_courant"))
def _normal_impact_axial(mu, phi, speed, eta0, rtol, *, n_history, string_cells, string_courant):
    """With axial force (report 3.4, `axial.py` and `string.py`): the beam stage by time
    integration, then the plastic string where N reaches N0; in the speed-free variables
    the speed enters through eta0 V^2. `rtol` is traced: a new tolerance does not
    recompile."""
    yields = phi > 1.0
    safe_phi = jnp.where(yields, phi, 2.0)

    def stages(mu, phi, eta, rtol):
        return axial_impact(
            mu,
            phi,
            eta,
            rtol=rtol,
            n_history=n_history,
            string_cells=string_cells,
            string_courant=string_courant,
        )

    r = forward_jacobian_jvp(stages, n_differentiable=3)(mu, safe_phi, eta0 * speed**2, rtol)
    history = _scaled_history(r["history"], mu, speed) if n_history else None
    t_final = eqx.error_if(
        r["t_final"] * speed,
        ~r["string_finished"] & yields,
        "the plastic string stage did not come to rest within its step budget",
    )
    result = NormalImpact(
        s_star=r["s_star"],
        t_star=r["t_star"] * speed,
        v_star=r["v_star"] * speed,
        w_star=r["w_star"] * speed**2,
        damage=r["damage"] * speed**2,
        s_final=r["s_final"],
        t_final=t_final,
        w_final=r["w_final"] * speed**2,
        crush_work=safe_phi * r["damage"] * speed**2,
        backing_work=r["backing_work"] * speed**2,
        hinge_work=(r["bending_work"] + r["stretching_work"]) * speed**2,
        t_string=r["t_string"] * speed,
        string_work=r["string_work"] * speed**2,
        history=history,
    )
    rigid = _rigid_barrier(mu, phi, speed, n_history, string_cells=string_cells)
    return jax.tree.map(lambda a, b: jnp.where(yields, a, b), result, rigid)


def normal_impact(
    mass_ratio,
    force_ratio,
    speed,
    *,
    method: Literal["closed_form", "ode"] = "closed_form",
    rtol: float = 1e-8,
    n_history: int = 0,
    solver: diffrax.AbstractSolver | None = None,
    axial_ratio=None,
    string_cells: int = 128,
    string_courant: float = 1.0,
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
    - `rtol`: relative tolerance: of the ODE solver, or the target of the quadrature.
    - `n_history`: number of saved samples per phase (0: none, the cheapest).
    - `solver`: diffrax solver for `method="ode"` (default `diffrax.Tsit5()`).
    - `axial_ratio`: eta0 = N0 / (4 (M0 q0)^1/2), the beam's yield force in tension in
      the report's units (3.4), for a beam held against axial motion; non-negative.
      `None` or `0` is the model of 3.2, compiled without any axial term. Otherwise the
      beam stage of 3.4 is integrated in time (it has no closed form; `method` must be
      `"ode"`), `t_string` reports where N reaches N0, and the history has `axial_force`.
      Where N reaches N0 the motion goes on to rest as a plastic string (3.4.45),
      solved by finite elements and leapfrog (`string.py`).
    - `string_cells`: elements over the string's half-span (with `axial_ratio`).
    - `string_courant`: the string's time step over its element's wave transit time,
      in (0, 1] (1: exact for the free string; with `axial_ratio`).

    Scalars, or arrays of one shape (solved in cache-sized vmapped chunks: the fastest
    way to run a large sweep); `jax.vmap` and `jax.grad` work with respect to any
    argument.
    """
    if method not in ("closed_form", "ode"):
        raise ValueError(f"method must be 'closed_form' or 'ode'; got {method!r}")
    if not 0.0 < rtol < 1.0:
        raise ValueError(f"rtol must be in (0, 1); got {rtol!r}")
    if int(n_history) != n_history or n_history < 0 or n_history == 1:
        raise ValueError(f"n_history must be 0 or an integer >= 2; got {n_history!r}")
    mu = _checks.positive("mass_ratio", mass_ratio)
    phi = _checks.positive("force_ratio", force_ratio)
    speed = _checks.positive("speed", speed)
    if not (axial_ratio is None or (isinstance(axial_ratio, int | float) and axial_ratio == 0)):
        if method != "ode":
            raise ValueError(
                "method must be 'ode' with axial_ratio: the beam stage of report 3.4 has "
                f"no closed form; got {method!r}"
            )
        eta0 = _checks.non_negative("axial_ratio", axial_ratio)
        if int(string_cells) != string_cells or string_cells < 2:
            raise ValueError(f"string_cells must be an integer >= 2; got {string_cells!r}")
        if not 0.0 < string_courant <= 1.0:
            raise ValueError(f"string_courant must be in (0, 1]; got {string_courant!r}")
        args = jnp.broadcast_arrays(mu, phi, speed, eta0)
        solve = functools.partial(
            _normal_impact_axial,
            n_history=int(n_history),
            string_cells=int(string_cells),
            string_courant=float(string_courant),
        )
        for _ in range(args[0].ndim):
            solve = jax.vmap(solve, in_axes=(0, 0, 0, 0, None))
        return solve(*args, jnp.asarray(rtol, args[0].dtype))
    mu, phi, speed = jnp.broadcast_arrays(mu, phi, speed)
    options = dict(
        method=method,
        rtol=float(rtol),
        n_history=int(n_history),
        solver=solver if solver is not None else diffrax.Tsit5(),
    )
    if mu.ndim == 0:
        return _normal_impact(mu, phi, speed, **options)
    flat = _normal_impact_chunked(mu.ravel(), phi.ravel(), speed.ravel(), **options)
    return jax.tree.map(lambda leaf: leaf.reshape(mu.shape + leaf.shape[1:]), flat)


# Array inputs are solved in vmapped chunks of this many scenarios: a chunk's working set
# stays in cache, which on a 2-core CPU makes 10^5 ODE solves about four times faster
# than one vmap over all of them (benchmarks/normal_impact.py).
_CHUNK = {"closed_form": 8192, "ode": 2048}


@functools.partial(jax.jit, static_argnames=("method", "rtol", "n_history", "solver"))
def _normal_impact_chunked(mu, phi, speed, **options):
    solve = functools.partial(_normal_impact, **options)
    if options["method"] == "closed_form":
        return jax.lax.map(lambda x: solve(*x), (mu, phi, speed), batch_size=_CHUNK["closed_form"])
    # A vmapped solve steps until its slowest member is done. The decelerative phase's step
    # count grows with ln(alpha/S*) ~ ln(phi), so chunks of neighbouring phi waste fewer
    # steps: 1.8x faster over 10^5 random scenarios of the property-test ranges.
    return sorted_chunks(solve, (mu, phi, speed), phi, _CHUNK["ode"])
