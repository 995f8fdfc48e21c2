"""Oblique impact of a rigid-plastic vehicle on a rigid-plastic beam on a rigid-plastic
backing (report section 3.3), and the moving constant load of its accelerative phase.

Dimensionless variables as in 3.2 (ERRATA): lengths over L = 2 (M0/q0)^1/2, forces over
P_b = 4 (M0 q0)^1/2, time over t0 = m^1/2 M0^1/4 / q0^3/4, mass ratio mu = M/(m L). The
contact point moves along the beam at the vehicle's tangential speed V_H; S1 is the
distance from the contact point to the hinge ahead of it (the right hinge), S2 to the
hinge behind it, and V0 the beam's velocity under the contact point.

Equations of motion, (3.3.16) with the force ratio g = P/P_b and the load speed c = F':

    V0' = -3 / (2 S1 S2) - 1/2 + 4 g / (S1 + S2)
    V0 (S1' + 3/2 c) = 3/4 (S1 + S2)/(S1 S2) - S1/2 - 2 g S1 / (S1 + S2)
    V0 (S2' - 3/2 c) = 3/4 (S1 + S2)/(S1 S2) - S2/2 - 2 g S2 / (S1 + S2)

(3.3.10 as corrected in ERRATA: 4P in the first line, P xi2 in the third.)

The memory of 3.3.4-3.3.6. A point x ahead of the load lies still until the right hinge
reaches it, then rides the right rigid segment, whose slope rate is -V0/S1, until the load
arrives. With Phi(T) = int_0^T V0/S1, the slope under the load is

    theta = Psi(F) - Phi,   Psi(x) = Phi at the time the right hinge passed x,

and (3.3.21)'s R is V_H Psi'(F) F' + V_H' theta: the first term is V_H^2 times the
curvature dPsi/dx that the right hinge left behind at the load point. Psi is the curve
(H, Phi) traced by the right hinge H = F + S1; it is recorded, one sample per accepted
step, in a fixed-size buffer that the vector field reads (`_solve.recorded_rk`): the delay
T1 of (3.3.5) is never solved for. Each sample holds Phi, dPhi/dH and d2Phi/dH2 (the last
from the field's derivative along the solution), and Psi is their quintic Hermite
interpolant, so that the memory is as accurate as the Dormand-Prince steps that record it.
Psi = 0 ahead of the initial hinge, x < S*.

Phases.
1. Crushing (accelerative, in time T): the vehicle crushes at constant force phi; its
   normal velocity U falls at phi/mu. At T = 0, V0 = 0 and S' = g/V0 is 0/0; its limit
   is the antisymmetric mode S1' = -S2' = -3/2 a V_H / (a + 1/2 + phi/S*) with
   a = V0'(0) (linearise the second and third lines about S1 = S2 = S*). The steps start
   at T = 1e-2 rtol^1/2 T_scale from this expansion (`_series_start`): from T = 0 itself
   no explicit step is stable when phi is near 1. The phase ends where the vehicle stops
   crushing: U = V0 + theta V_H.
2. Contact (decelerative): the vehicle is rigid and follows the contact point, so
   g = -mu d/dT (V0 + theta V_H), which with the first line gives (3.3.22)'s form

       g (1 - f theta + 4 mu / (S1 + S2))
           = mu (S1 S2 + 3) / (2 S1 S2) + mu V_H V0 / S1 - mu V_H^2 Psi'(F),

   f being the friction coefficient. V0 -> 0 at the end, where S' = g_i/V0 is 0/0
   again; the phase is integrated in s, dT/ds = V0, in which every rate is regular, with
   ln V0 as state; it ends at V0 = V0* rtol e^-3, and the rest is added analytically.
3. Free (only after separation): where g would fall below zero the vehicle leaves; the
   beam moves on alone (g = 0, the central hinge where the load left it) to rest. The
   report keeps contact to the end; this phase is where the model departs from it.

Friction (the `friction` option): Coulomb, tangential force f P on the vehicle, none on
the beam (as in the report). The normal force acts along the undeformed normal, so the
vehicle's kinetic-energy loss is crush + friction work + work on the barrier (P V0) +
`slope_work` (P theta V_H): the report holds V_H fixed, and this last term is the work
of whatever holds it so; it is reported, not fed back into V_H.

Once the slide stops (friction), static friction holds the vehicle: V_H stays 0.

Where the model stops with an error rather than an answer:
- The load catches up with the hinge ahead of it (S1 -> 0 in the contact phase; fast
  slides, small angles): V0 and the force then grow without bound, outside the
  three-hinge mechanism; the report does not meet this case.
- The step budget runs out (`max_steps`). Heavy vehicles (mu above about 50) crush for
  T* ~ mu V_N / phi with the hinges at their steady state, where the explicit steps are
  bounded by stability, not accuracy: they need a larger budget (an L-stable step in
  `_solve.recorded_rk` would remove this).

Derivatives: the contact phase runs in segments between the breakpoints of Psi' (see
`_contact_segments`), so that they match finite differences; `max_deflection`
integrates the velocity field over the recorded steps by the trapezoidal rule on 129
points (error O(step^2)).
"""

import functools
import math

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from .. import _checks
from .._custom_types import Scalar
from .._solve.batching import sorted_chunks
from .._solve.recorded_rk import PhaseEnd, Recording, require_complete, solve_recorded
from .._solve.sensitivity import forward_jacobian_jvp

# --------------------------------------------------------------------------------------
# Results.


class ObliqueImpactHistory(eqx.Module):
    """One sample per accepted solver step, `n_saved` of them; the rest of each array
    repeats the final state. `displacement[k, j]` is W(x[j], time[k])."""

    time: Scalar
    s1: Scalar
    s2: Scalar
    v0: Scalar
    vehicle_normal_velocity: Scalar
    vehicle_tangential_velocity: Scalar
    contact_position: Scalar
    contact_force: Scalar
    slope: Scalar
    crush: Scalar
    contact_displacement: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar
    beam_kinetic_energy: Scalar
    vehicle_kinetic_energy: Scalar
    x: Scalar
    displacement: Scalar
    n_saved: Scalar


class ObliqueImpact(eqx.Module):
    """Dimensionless response to an oblique impact (report 3.3)."""

    t_star: Scalar
    t_final: Scalar
    s1_final: Scalar
    s2_final: Scalar
    w_final: Scalar
    max_deflection: Scalar
    damage: Scalar
    exit_normal_speed: Scalar
    exit_tangential_speed: Scalar
    exit_angle_deg: Scalar
    separated: Scalar
    crush_work: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar
    history: ObliqueImpactHistory | None


class MovingLoad(eqx.Module):
    s1: Scalar
    s2: Scalar
    v0: Scalar
    history: ObliqueImpactHistory | None


# --------------------------------------------------------------------------------------
# The beam mechanism, (3.3.16).


def _acceleration(s1, s2, force):
    return -1.5 / (s1 * s2) - 0.5 + 4.0 * force / (s1 + s2)


def _hinge_terms(s1, s2, force):
    """g1, g2: V0 (S1' + 3/2 c) = g1 and V0 (S2' - 3/2 c) = g2."""
    total = s1 + s2
    common = 0.75 * total / (s1 * s2)
    return (
        common - 0.5 * s1 - 2.0 * force * s1 / total,
        common - 0.5 * s2 - 2.0 * force * s2 / total,
    )


def _beam_powers(v0, s1, s2):
    """Backing and hinge dissipation rates: q0 int v dx and M0 times the hinges' rotation
    rates (V0/S1, V0/S2 and their sum at the load), in the units of 3.2."""
    return 0.25 * v0 * (s1 + s2), 0.25 * v0 * (1.0 / s1 + 1.0 / s2)


def _beam_kinetic_energy(v0, s1, s2):
    return v0**2 * (s1 + s2) / 6.0


def _interval(recording: Recording, x, first, last):
    """The i in [first, max(last - 1, first)] with hinge[i] <= x < hinge[i + 1], clamped
    to the ends: bisection within the segment's samples, reading one sample per halving."""
    column = recording.names.index("hinge")

    def halve(_, bounds):
        lo, hi = bounds
        mid = (lo + hi) // 2
        right = recording.buffer[mid, column] <= x
        return jnp.where(right, mid, lo), jnp.where(right, hi, mid)

    halvings = max(1, math.ceil(math.log2(recording.buffer.shape[0])))
    lo, _ = jax.lax.fori_loop(0, halvings, halve, (first, jnp.maximum(last, first)))
    return lo


# The samples of the right hinge's trace that one step of the load may read: the step is
# bounded to stay within them (`_lookup_bound`). A step of the load crosses about as many
# samples as a step of the hinge records, one.
_WINDOW = 8


class _Past(eqx.Module):
    """What a step reads of the right hinge's recorded trace: `_WINDOW` consecutive
    samples (H, Phi, dPhi/dH, d2Phi/dH2) from `start` (H = +inf past the last recorded
    one), the segment's bounds (`_Params.segment`) and `reach`, the furthest position the
    window covers."""

    hinge: Float[Array, " window"]
    rotation: Float[Array, " window"]
    curvature: Float[Array, " window"]
    curvature_rate: Float[Array, " window"]
    start: Int[Array, ""]
    first: Int[Array, ""]
    last: Int[Array, ""]
    reach: Scalar


def _past(t, y, p, recording: Recording, previous: _Past | None = None) -> _Past:
    """The window of the trace from the interval holding the load, found once per step:
    by bisection, or from `previous`, the last step's window. The load only advances,
    and each step keeps it short of its window's reach (`_lookup_bound`), so the interval
    holding it now lies in the last window."""
    first, last = p.segment
    recorded = jnp.maximum(recording.count - 1, 0)
    last = jnp.minimum(last, recorded)
    if previous is None:
        interval = _interval(recording, y.position, first, last)
    else:
        below = jnp.sum(previous.hinge <= y.position).astype(previous.start.dtype)
        interval = previous.start + jnp.maximum(below - 1, 0)
        interval = jnp.clip(interval, first, jnp.maximum(last - 1, first))
    start = jnp.minimum(interval, recording.buffer.shape[0] - _WINDOW)
    window = recording.rows(start, _WINDOW, _MEMORY)
    filled = start + jnp.arange(_WINDOW, dtype=start.dtype) <= recorded
    hinge = jnp.where(filled, window.pop("hinge"), jnp.inf)
    reach = jnp.max(jnp.where(filled, hinge, -jnp.inf))
    return _Past(hinge=hinge, **window, start=start, first=first, last=last, reach=reach)


def _quintic_hermite(u, width, left, right):
    """The quintic on [0, 1] through (value, slope, second derivative) at both ends, slopes
    in x = u width: its value and its slope in x at u."""

    def basis(u):
        # Value, slope and second-derivative weights of the left end, and their u-slopes.
        u2, u3, u4, u5 = u * u, u**3, u**4, u**5
        return (
            (
                1 - 10 * u3 + 15 * u4 - 6 * u5,
                u - 6 * u3 + 8 * u4 - 3 * u5,
                0.5 * (u2 - 3 * u3 + 3 * u4 - u5),
            ),
            (
                -30 * u2 + 60 * u3 - 30 * u4,
                1 - 18 * u2 + 32 * u3 - 15 * u4,
                0.5 * (2 * u - 9 * u2 + 12 * u3 - 5 * u4),
            ),
        )

    # The right end's weights are the left end's at 1 - u, with the odd derivative negated.
    (b0, b1, b2), (d0, d1, d2) = basis(u)
    (c0, c1, c2), (e0, e1, e2) = basis(1.0 - u)
    (p0, s0, k0), (p1, s1, k1) = left, right
    w2 = width * width
    value = b0 * p0 + width * b1 * s0 + w2 * b2 * k0 + c0 * p1 - width * c1 * s1 + w2 * c2 * k1
    slope = (
        d0 * p0 + width * d1 * s0 + w2 * d2 * k0 - e0 * p1 + width * e1 * s1 - w2 * e2 * k1
    ) / width
    return value, slope


def _cubic_hermite(u, width, left, right):
    """As `_quintic_hermite`, through (value, slope) at both ends."""
    (p0, s0), (p1, s1) = left, right
    u2, u3 = u * u, u * u * u
    value = (
        (2 * u3 - 3 * u2 + 1) * p0
        + (u3 - 2 * u2 + u) * width * s0
        + (-2 * u3 + 3 * u2) * p1
        + (u3 - u2) * width * s1
    )
    slope = (
        (6 * u2 - 6 * u) * p0
        + (3 * u2 - 4 * u + 1) * width * s0
        + (-6 * u2 + 6 * u) * p1
        + (3 * u2 - 2 * u) * width * s1
    ) / width
    return value, slope


def _slope_memory(past: _Past, x, s_star):
    """(Psi(x), Psi'(x)): Phi when the right hinge passed x, by quintic Hermite
    interpolation of the recorded (H, Phi, dPhi/dH, d2Phi/dH2); zero ahead of the initial
    hinge, x < S*.

    The interpolant is C2 with error O(step^6): the force reads Psi', and a lower-order or
    less smooth interpolant would put a kink into the vector field at every recorded
    sample the load crosses, outside the step control (with cubic Hermite, the error fell
    only as rtol^0.5).

    Only the segment's samples are read, so that a lookup at a jump of Psi' (recorded
    twice, left and right limits) takes the side the load is on whatever the rounding of
    x. The interval is picked from the window by comparison, not indexing: under `vmap` an
    index is a gather, which XLA runs as a kernel of its own."""
    offsets = jnp.arange(_WINDOW, dtype=past.start.dtype)
    below = jnp.sum(past.hinge <= x).astype(past.start.dtype)
    i = jnp.clip(past.start + below - 1, past.first, jnp.maximum(past.last - 1, past.first))
    i = jnp.clip(i, past.start, past.start + _WINDOW - 2)
    interior = i + 1 <= past.last
    j = jnp.where(interior, i + 1, i)
    pick = lambda samples, k: jnp.sum(jnp.where(offsets == k - past.start, samples, 0.0))
    data = lambda k: tuple(
        pick(samples, k) for samples in (past.rotation, past.curvature, past.curvature_rate)
    )
    h_i, h_j = pick(past.hinge, i), pick(past.hinge, j)
    left, right = data(i), data(j)
    width = jnp.where(interior, h_j - h_i, 1.0)
    u = jnp.where(interior, (x - h_i) / width, 0.0)
    psi, dpsi = _quintic_hermite(u, width, left, right)
    # Next to a breakpoint the second derivatives are one-sided limits of a fast-changing
    # trace: cubic there (the second-derivative data dropped), which stays stable where
    # breakpoints cluster.
    at_bound = (i == past.first) | (j == past.last)
    cubic = _cubic_hermite(u, width, left[:2], right[:2])
    psi, dpsi = (jnp.where(at_bound, c, q) for c, q in zip(cubic, (psi, dpsi)))
    # Past the segment's last sample (only within a step, which then ends or is retaken at
    # the segment's end): linear. The second derivative there can be the one-sided limit
    # at a breakpoint, orders of magnitude off a step away (at S*, for large force ratios).
    phi_i, slope_i, _ = left
    psi = jnp.where(interior, psi, phi_i + slope_i * (x - h_i))
    dpsi = jnp.where(interior, dpsi, slope_i)
    ahead = x < s_star
    return jnp.where(ahead, 0.0, psi), jnp.where(ahead, 0.0, dpsi)


# --------------------------------------------------------------------------------------
# States and vector fields.


class _Params(eqx.Module):
    mu: Scalar
    phi: Scalar
    friction: Scalar
    s_star: Scalar
    segment: tuple  # (first, last) recorded samples the memory may read: `_slope_memory`
    moving_load: bool = eqx.field(static=True, default=False)


class _Crushing(eqx.Module):
    """Phase 1 state, against time T."""

    v0: Scalar
    s1: Scalar
    s2: Scalar
    position: Scalar
    rotation: Scalar  # Phi
    vehicle_normal: Scalar
    vehicle_tangential: Scalar
    crush: Scalar
    contact_displacement: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar


class _Sliding(eqx.Module):
    """Phase 2 and 3 state, against s with dT/ds = V0."""

    log_v0: Scalar
    s1: Scalar
    s2: Scalar
    time: Scalar
    position: Scalar
    rotation: Scalar
    vehicle_normal: Scalar  # used after separation only
    vehicle_tangential: Scalar
    contact_displacement: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar


def _sliding_friction(vh, p: _Params):
    """The friction coefficient acting on the vehicle: Coulomb's f while it slides; once it
    stops sliding, static friction holds it (the barrier takes no axial motion), with no
    tangential deceleration and no work."""
    return jnp.where(vh > 0.0, p.friction, 0.0)


def _series_start(t, vn, vh, p: _Params) -> _Crushing:
    """The crushing phase's state at a small time t, from its expansion about T = 0.

    At T = 0, V0 = 0 and S' = g_i/V0 is 0/0, and for force ratios near 1 the linearised
    hinge equations are stiff in proportion to 1/V0'(0): no explicit step from T = 0 is
    stable. To first order, V0 = a T with a = V0'(0), and the hinges move in the
    antisymmetric mode S1 - S* = S* - S2 = sigma T, sigma = -3/2 a V_H / (a + 1/2 +
    phi/S*) (linearise the second and third lines of (3.3.16) about S1 = S2 = S*; the
    symmetric mode has no regular first-order part); the integrals follow to second order,
    so that the energy balance closes to O(t^3). The neglected terms are O(t^2), relative
    O(t / T*)."""
    a = _acceleration(p.s_star, p.s_star, p.phi)
    sigma = -1.5 * a * vh / (a + 0.5 + p.phi / p.s_star)
    vehicle = 0.0 if p.moving_load else 1.0
    deceleration = vehicle * p.friction * p.phi / p.mu
    braking = deceleration > 0.0
    stop = jnp.where(braking, vh / jnp.where(braking, deceleration, 1.0), jnp.inf)
    slide = jnp.minimum(t, stop)
    slid = vh * slide - 0.5 * deceleration * slide**2
    contact_displacement = 0.5 * a * t**2
    return _Crushing(
        v0=a * t,
        s1=p.s_star + sigma * t,
        s2=p.s_star - sigma * t,
        position=slid,
        rotation=0.5 * a * t**2 / p.s_star,
        vehicle_normal=vn - vehicle * p.phi * t / p.mu,
        vehicle_tangential=vh - deceleration * slide,
        crush=vehicle * (vn * t - 0.5 * p.phi * t**2 / p.mu - contact_displacement),
        contact_displacement=contact_displacement,
        backing_work=0.25 * a * p.s_star * t**2,
        hinge_work=0.25 * a * t**2 / p.s_star,
        friction_work=p.friction * p.phi * slid,
        slope_work=jnp.zeros_like(t),
    )


def _crushing_field(t, y: _Crushing, p: _Params, past: _Past) -> _Crushing:
    vh = jnp.maximum(y.vehicle_tangential, 0.0)
    force = p.phi
    g1, g2 = _hinge_terms(y.s1, y.s2, force)
    psi, _ = _slope_memory(past, y.position, p.s_star)
    theta = psi - y.rotation
    contact_velocity = y.v0 + theta * vh
    backing, hinge = _beam_powers(y.v0, y.s1, y.s2)
    vehicle = 0.0 if p.moving_load else 1.0
    return _Crushing(
        v0=_acceleration(y.s1, y.s2, force),
        s1=g1 / y.v0 - 1.5 * vh,
        s2=g2 / y.v0 + 1.5 * vh,
        position=vh,
        rotation=y.v0 / y.s1,
        vehicle_normal=-vehicle * force / p.mu,
        vehicle_tangential=-vehicle * _sliding_friction(vh, p) * force / p.mu,
        crush=vehicle * (y.vehicle_normal - contact_velocity),
        contact_displacement=contact_velocity,
        backing_work=backing,
        hinge_work=hinge,
        friction_work=p.friction * force * vh,
        slope_work=force * theta * vh,
    )


def _contact_force(y: _Sliding, p: _Params, past: _Past):
    """(force ratio, slope under the load): (3.3.20)-(3.3.22) solved for the force."""
    v0 = jnp.exp(y.log_v0)
    vh = jnp.maximum(y.vehicle_tangential, 0.0)
    psi, curvature = _slope_memory(past, y.position, p.s_star)
    theta = psi - y.rotation
    s1, s2 = y.s1, y.s2
    numerator = (
        p.mu * (s1 * s2 + 3.0) / (2.0 * s1 * s2) + p.mu * vh * v0 / s1 - p.mu * vh**2 * curvature
    )
    # The friction term: the tangential deceleration f g / mu changes theta V_H.
    force = numerator / (1.0 - _sliding_friction(vh, p) * theta + 4.0 * p.mu / (s1 + s2))
    return force, theta


def _sliding_field(in_contact: bool):
    def field(s, y: _Sliding, p: _Params, past: _Past) -> _Sliding:
        v0 = jnp.exp(y.log_v0)
        vh = jnp.maximum(y.vehicle_tangential, 0.0)
        if in_contact:
            force, theta = _contact_force(y, p, past)
            load_speed = vh
        else:
            force, theta, load_speed = 0.0, 0.0, 0.0
        g1, g2 = _hinge_terms(y.s1, y.s2, force)
        backing, hinge = _beam_powers(v0, y.s1, y.s2)
        contact_velocity = v0 + theta * load_speed
        zero = jnp.zeros_like(v0)
        return _Sliding(
            log_v0=_acceleration(y.s1, y.s2, force),
            s1=g1 - 1.5 * load_speed * v0,
            s2=g2 + 1.5 * load_speed * v0,
            time=v0,
            position=v0 * load_speed,
            rotation=v0 * v0 / y.s1,
            vehicle_normal=zero,
            vehicle_tangential=-v0 * _sliding_friction(vh, p) * force / p.mu,
            contact_displacement=v0 * contact_velocity,
            backing_work=v0 * backing,
            hinge_work=v0 * hinge,
            friction_work=v0 * p.friction * force * vh,
            slope_work=v0 * force * theta * vh,
        )

    return field


# --------------------------------------------------------------------------------------
# What each accepted step records: the right hinge's trace for the memory, and the
# quantities of the histories.


def _sample(phase, time, v0, s1, s2, position, rotation, f, rate, **extra):
    """One recorded step. The trace of the right hinge H = F + S1 carries Psi's data at H:
    Phi, dPhi/dH = Phi'/H' and d2Phi/dH2 = (Phi'' H' - Phi' H'')/H'^3 (primes: the phase's
    own variable, T or s; the ratios do not depend on which); zero while the hinge stands."""
    hinge_speed, hinge_acceleration = f.position + f.s1, rate.position + rate.s1
    moving = hinge_speed > 0.0
    speed = jnp.where(moving, hinge_speed, 1.0)
    curvature = jnp.where(moving, f.rotation / speed, 0.0)
    curvature_rate = jnp.where(
        moving, (rate.rotation * speed - f.rotation * hinge_acceleration) / speed**3, 0.0
    )
    return dict(
        hinge=position + s1,
        rotation=rotation,
        curvature=curvature,
        curvature_rate=curvature_rate,
        phase=jnp.full_like(v0, phase),
        time=time,
        v0=v0,
        s1=s1,
        s2=s2,
        position=position,
        **extra,
    )


def _record_crushing(t, y: _Crushing, f: _Crushing, rate: _Crushing, p: _Params):
    return _sample(
        1.0,
        t,
        y.v0,
        y.s1,
        y.s2,
        y.position,
        y.rotation,
        f,
        rate,
        vehicle_normal=y.vehicle_normal,
        vehicle_tangential=y.vehicle_tangential,
        force=jnp.full_like(y.v0, 0.0 if p.moving_load else 1.0) * p.phi,
        slope=f.slope_work / jnp.where(f.position != 0.0, p.phi * f.position, 1.0),
        crush=y.crush,
        contact_displacement=y.contact_displacement,
        backing_work=y.backing_work,
        hinge_work=y.hinge_work,
        friction_work=y.friction_work,
        slope_work=y.slope_work,
    )


def _record_sliding(in_contact: bool):
    def record(s, y: _Sliding, f: _Sliding, rate: _Sliding, p: _Params):
        # f holds d/ds = V0 d/dT.
        v0 = jnp.exp(y.log_v0)
        if in_contact:
            force = (f.log_v0 + 1.5 / (y.s1 * y.s2) + 0.5) * (y.s1 + y.s2) / 4.0
            vehicle_normal = f.contact_displacement / v0
            slope = (vehicle_normal - v0) / jnp.where(f.position != 0.0, f.position / v0, 1.0)
        else:
            force = jnp.zeros_like(v0)
            vehicle_normal = y.vehicle_normal
            slope = jnp.zeros_like(v0)
        return _sample(
            2.0 if in_contact else 3.0,
            y.time,
            v0,
            y.s1,
            y.s2,
            y.position,
            y.rotation,
            f,
            rate,
            vehicle_normal=vehicle_normal,
            vehicle_tangential=y.vehicle_tangential,
            force=force,
            slope=slope,
            crush=jnp.zeros_like(v0),  # the phase-1 crush, filled in afterwards
            contact_displacement=y.contact_displacement,
            backing_work=y.backing_work,
            hinge_work=y.hinge_work,
            friction_work=y.friction_work,
            slope_work=y.slope_work,
        )

    return record


# What the recording keeps: the right hinge's trace for the memory, the motion for the
# displacement field (max_deflection), and with `history` the rest of each sample.
_MEMORY = ("hinge", "rotation", "curvature", "curvature_rate")
_MOTION = ("time", "v0", "s1", "s2", "position")
_HISTORY = (
    "phase",
    "vehicle_normal",
    "vehicle_tangential",
    "force",
    "slope",
    "crush",
    "contact_displacement",
    "backing_work",
    "hinge_work",
    "friction_work",
    "slope_work",
)


def _empty_recording(capacity, dtype, history):
    names = _MEMORY + _MOTION + (_HISTORY if history else ())
    return Recording.empty(names, capacity, dtype)


# --------------------------------------------------------------------------------------
# The phases.


def _lookup_bound(rate_of_position):
    """A step bound keeping the load's position within the step's window of the hinge's
    trace: at most half the gap between the load and the window's reach."""

    def max_step(t, y, f, p, past: _Past):
        rate = rate_of_position(y)
        gap = jnp.maximum(past.reach - y.position, 0.0)
        return jnp.where(rate > 0.0, 0.5 * gap / jnp.where(rate > 0.0, rate, 1.0), jnp.inf)

    return max_step


class _Breakpoints(eqx.Module):
    """Points of the right hinge's trace where Psi' jumps or has a kink, not yet reached
    by the load, in the order the load meets them: `position` and the indices of the
    recorded samples holding the left and right limits there. Two slots suffice (see
    `_contact_segments`); an empty slot is at +inf."""

    position: Float[Array, "2"]
    left: Int[Array, "2"]
    right: Int[Array, "2"]

    def head(self):
        return self.position[0], self.left[0], self.right[0]

    def pop_and_push(self, position, left):
        """Drop the head and append a breakpoint created now: ahead of every other, since
        the hinge only advances."""
        filled = jnp.isfinite(self.position[1])
        pick = lambda old, new, empty: jnp.where(
            filled, jnp.stack([old[1], new]), jnp.stack([new, empty])
        )
        return _Breakpoints(
            pick(self.position, position, jnp.inf),
            pick(self.left, left, 0),
            pick(self.right, left + 1, 0),
        )


def _contact_segments(sliding, start, first, p: _Params, contact_event, max_steps):
    """The contact phase, as segments between the breakpoints of the deposited curvature.

    The force in contact reads Psi'(F), so its vector field jumps where Psi' jumps and has
    a kink where Psi' has one. Psi' jumps where the right hinge stood at T* (the force
    drops there, and with it S1'), and has a kink at S*, where the trace starts. When the
    load reaches such a point the force jumps (or kinks), and so does the curvature the
    right hinge deposits at that moment: a neutral delay equation propagates its
    breakpoints, x_new = H(T_k) where F(T_k) = x_k. A new breakpoint lies ahead of every
    pending one, so at most two are pending (S* and H(T*) at the start). Each segment
    ends exactly on the next one, so that no step straddles it (a straddling step misses
    the jump's contribution to the derivatives, O(1), or a kink's, O(step)), and reads
    the trace only between its two breakpoints. The end of a segment and the start of the
    next record the left and right limits at the new breakpoint. Returns the final
    segment's end and its parameters.
    """
    recording = first.recording
    int_ = recording.count.dtype
    first_hinge = p.s_star  # where the trace starts, at T = 0
    # The last sample of the crushing phase is the left limit at H(T*).
    h_t_star, left = start.position + start.s1, recording.count - 1
    no_s_star = _Breakpoints(
        jnp.stack([h_t_star, jnp.inf]), jnp.stack([left, 0]), jnp.stack([left + 1, 0])
    )
    s_star_first = _Breakpoints(
        jnp.stack([first_hinge, h_t_star]), jnp.stack([0, left]), jnp.stack([0, left + 1])
    )
    pending = jax.tree.map(
        lambda a, b: jnp.where(start.position < first_hinge, a, b), s_star_first, no_s_star
    )

    def segment(carry):
        end, p, pending, behind, _ = carry
        position, left, right = pending.head()
        p = eqx.tree_at(lambda p: p.segment, p, (behind, left))
        event = lambda s, y, f, p, past: jnp.minimum(
            contact_event(s, y, f, p, past), position - y.position
        )
        end = sliding(True, end.y, end.recording, p, event)
        crossed = position - end.y.position < contact_event(
            0.0, end.y, end.derivative, p, _past(0.0, end.y, p, end.recording)
        )
        created = pending.pop_and_push(end.y.position + end.y.s1, end.recording.count - 1)
        keep = lambda new, old: jax.tree.map(lambda a, b: jnp.where(crossed, a, b), new, old)
        return (
            end,
            p,
            keep(created, pending),
            jnp.where(crossed, right, behind),
            crossed,
        )

    # (`derivative` is a placeholder of the right structure: no segment reads it.)
    initial = PhaseEnd(first.t, start, start, recording, first.steps, first.complete)
    carry = (initial, p, pending, jnp.zeros((), int_), jnp.asarray(True))
    end, p, _, _, crossed = eqxi.while_loop(
        lambda c: c[-1] & (c[0].recording.count < max_steps),
        segment,
        carry,
        kind="lax",
        buffers=lambda c: c[0].recording.buffer,
    )
    # (Still on a breakpoint: the budget ran out between segments.)
    end = eqx.tree_at(lambda e: e.complete, end, end.complete & ~crossed)
    return require_complete(end, "contact phase"), p


# The contact phase stops where S1 falls to this fraction of S*: there the load has caught
# up with the hinge ahead of it, V0 and the force grow without bound, and the mechanism of
# 3.3 no longer holds (the report does not meet this case).
_OVERTAKEN = 1e-3

# In s, ln V0 falls at the rate |V0'|, steadily once the hinges have settled, where the
# error estimate would let the step grow without bound: cap it at this many e-folds of V0.
_EFOLDS_PER_STEP = 2.0


def _solve(mu, phi, vn, vh, friction, *, rtol, max_steps, history, t_end=None):
    """All phases in the speed-free dimensionless variables. With `t_end`, the moving
    load: phase 1 alone with no vehicle, to T = t_end."""
    dtype = jnp.result_type(mu)
    zero = jnp.zeros((), dtype)
    root = jnp.sqrt(phi**2 + 3.0)
    s_star = 3.0 / (root + phi)
    moving_load = t_end is not None
    # One row per accepted step, and the start and end of each phase and segment: a phase
    # may attempt max_steps - count steps, and fills at most two rows more than it accepts.
    capacity = max_steps + 8
    everything = (jnp.zeros((), jnp.int32), jnp.asarray(capacity, jnp.int32))
    p = _Params(mu, phi, friction, s_star, everything, moving_load=moving_load)
    recording = _empty_recording(capacity, dtype, history)
    atol = 1e-3 * rtol
    time_scale = t_end if moving_load else 1.0 / (_acceleration(s_star, s_star, phi) + phi / mu)

    # The step loop starts where the expansion's error, relative O((t / T*)^2), is far
    # below rtol; the solution does not depend on where, so neither does its derivative.
    t_start = jax.lax.stop_gradient(1e-2 * jnp.sqrt(rtol) * time_scale)
    crushing = _series_start(t_start, zero + vn, zero + vh, p)
    # The histories and the hinge trace start at T = 0 itself, with the expansion's rates.
    at_zero = functools.partial(_series_start, vn=zero + vn, vh=zero + vh, p=p)
    rate_at_zero, acceleration_at_zero = jax.jvp(
        lambda t: jax.jvp(at_zero, (t,), (jnp.ones_like(t),)), (zero,), (jnp.ones_like(zero),)
    )[1]
    recording = recording.append(
        _record_crushing(zero, at_zero(zero), rate_at_zero, acceleration_at_zero, p)
    )
    if moving_load:
        event = lambda t, y, f, p, past: t_end - t
    else:
        event = lambda t, y, f, p, past: y.vehicle_normal - f.contact_displacement
    first = solve_recorded(
        _crushing_field,
        crushing,
        t_start,
        p,
        recording,
        record=_record_crushing,
        event=event,
        rtol=rtol,
        atol=atol,
        h0=t_start,
        max_step=_lookup_bound(lambda y: y.vehicle_tangential),
        max_steps=max_steps - recording.count,
        view=_past,
    )
    first = require_complete(first, "moving load" if moving_load else "crushing phase")
    if moving_load:
        return p, first, None, None
    y = first.y
    contact = _Sliding(
        log_v0=jnp.log(y.v0),
        s1=y.s1,
        s2=y.s2,
        time=first.t,
        position=y.position,
        rotation=y.rotation,
        vehicle_normal=first.derivative.contact_displacement,
        vehicle_tangential=y.vehicle_tangential,
        contact_displacement=y.contact_displacement,
        backing_work=y.backing_work,
        hinge_work=y.hinge_work,
        friction_work=y.friction_work,
        slope_work=y.slope_work,
    )
    log_rest = jnp.log(y.v0) + jnp.log(rtol) - 3.0

    def contact_event(s, y, f, p, past):
        force, _ = _contact_force(y, p, past)
        overtaking = y.s1 / p.s_star - _OVERTAKEN
        return jnp.minimum(jnp.minimum(force / p.phi, y.log_v0 - log_rest), overtaking)

    lookup_bound = _lookup_bound(lambda y: jnp.exp(y.log_v0) * y.vehicle_tangential)

    def max_step(in_contact, s, y, f, p, past):
        bound = _EFOLDS_PER_STEP / jnp.abs(f.log_v0)
        # After separation the load stands still and the memory is not read.
        return jnp.minimum(bound, lookup_bound(s, y, f, p, past)) if in_contact else bound

    def sliding(in_contact, start, recording, p, event):
        field = _sliding_field(in_contact)
        rate = field(zero, start, p, _past(zero, start, p, recording)).log_v0
        return solve_recorded(
            field,
            start,
            zero,
            p,
            recording,
            record=_record_sliding(in_contact),
            event=event,
            rtol=rtol,
            atol=atol,
            h0=1e-2 * rtol**0.2 / jnp.abs(rate),
            max_step=functools.partial(max_step, in_contact),
            max_steps=max_steps - recording.count,
            view=_past,
        )

    second, p_end = _contact_segments(sliding, contact, first, p, contact_event, max_steps)
    force_end, theta_end = _contact_force(
        second.y, p_end, _past(zero, second.y, p_end, second.recording)
    )
    separated = force_end / phi < second.y.log_v0 - log_rest
    overtaken = second.y.s1 / s_star < 2.0 * _OVERTAKEN
    separated = eqx.error_if(
        separated,
        overtaken,
        "the load caught up with the hinge ahead of it (S1 -> 0) in the contact phase: the "
        "vehicle slides faster than the barrier's plastic zone can run ahead, outside the "
        "three-hinge mechanism of report 3.3",
    )
    # The free phase runs only after a separation; otherwise its event is negative at its
    # start and it takes no step.
    free_rest = jnp.where(separated, log_rest, second.y.log_v0 + 1.0)
    vehicle_exit = second.derivative.contact_displacement / jnp.exp(second.y.log_v0)
    free_start = eqx.tree_at(lambda s: s.vehicle_normal, second.y, vehicle_exit)
    third = sliding(
        False,
        free_start,
        second.recording,
        p,
        lambda s, y, f, p, past: y.log_v0 - free_rest,
    )
    third = require_complete(third, "free phase")
    return p, first, second, (third, separated, theta_end)


def _rest(end, in_contact):
    """Add the motion from V0_end = V0* rtol e^-3 to rest, with the hinges frozen and the
    deceleration constant (its error is far below rtol): (time, extra displacement under
    the load)."""
    v0 = jnp.exp(end.y.log_v0)
    remaining = v0 / jnp.abs(end.derivative.log_v0)
    sliding = end.derivative.contact_displacement / v0 - v0 if in_contact else 0.0
    return remaining, (0.5 * v0 + sliding) * remaining


def _velocity_field(v0, s1, s2, position, x):
    """The beam's velocity at x, (3.3.2): V0 under the load, falling linearly to zero at
    the hinges S1 ahead and S2 behind."""
    offset = x - position
    return v0 * jnp.where(
        offset >= 0.0, jnp.maximum(1.0 - offset / s1, 0.0), jnp.maximum(1.0 + offset / s2, 0.0)
    )


def _motion(samples, k):
    return tuple(samples[name][k] for name in ("v0", "s1", "s2", "position"))


def _displacement_field(samples, count, x):
    """W(x, T_k) for every recorded T_k: the velocity field integrated over the recorded
    steps by the trapezoidal rule (error O(step^2) where a hinge crosses x)."""
    v = _velocity_field(*(m[:, None] for m in _motion(samples, slice(None))), x[None, :])
    recorded = jnp.arange(1, v.shape[0], dtype=count.dtype)[:, None] < count
    dt = jnp.where(recorded, jnp.diff(samples["time"])[:, None], 0.0)
    increments = 0.5 * (v[1:] + v[:-1]) * dt
    return jnp.concatenate([jnp.zeros_like(v[:1]), jnp.cumsum(increments, axis=0)])


def _final_displacement(recording: Recording, x):
    """W(x) at the last recorded time, as `_displacement_field` but over the recorded
    steps alone (a few dozen, where the buffer holds thousands), one row read each."""

    def motion(k):
        row = {name: value[0] for name, value in recording.rows(k, 1, _MOTION).items()}
        return row.pop("time"), _velocity_field(**row, x=x)

    def step(k, carry):
        w, t, v = carry
        t_next, v_next = motion(k + 1)
        return w + 0.5 * (v + v_next) * (t_next - t), t_next, v_next

    t_first, v_first = motion(0)
    carry = (jnp.zeros_like(v_first), t_first, v_first)
    w, _, _ = jax.lax.fori_loop(0, recording.count - 1, step, carry)
    return w


def _padded(samples, count):
    """Repeat the last recorded sample over the unfilled tail."""
    index = jnp.minimum(
        jnp.arange(jax.tree.leaves(samples)[0].shape[0], dtype=count.dtype), count - 1
    )
    return jax.tree.map(lambda a: a[index], samples)


def _grid(samples, count, n_x):
    """`n_x` points spanning every plastic zone of the first `count` samples."""
    filled = jnp.arange(samples["position"].shape[0], dtype=count.dtype) < count
    return jnp.linspace(
        jnp.min(jnp.where(filled, samples["position"] - samples["s2"], jnp.inf)),
        jnp.max(jnp.where(filled, samples["position"] + samples["s1"], -jnp.inf)),
        n_x,
    )


def _history(samples, count, p: _Params, x, displacement):
    vn, vh = samples["vehicle_normal"], samples["vehicle_tangential"]
    vehicle_energy = 0.0 if p.moving_load else 0.5 * p.mu * (vn**2 + vh**2)
    return ObliqueImpactHistory(
        time=samples["time"],
        s1=samples["s1"],
        s2=samples["s2"],
        v0=samples["v0"],
        vehicle_normal_velocity=vn,
        vehicle_tangential_velocity=vh,
        contact_position=samples["position"],
        contact_force=samples["force"],
        slope=samples["slope"],
        crush=samples["crush"],
        contact_displacement=samples["contact_displacement"],
        backing_work=samples["backing_work"],
        hinge_work=samples["hinge_work"],
        friction_work=samples["friction_work"],
        slope_work=samples["slope_work"],
        beam_kinetic_energy=_beam_kinetic_energy(samples["v0"], samples["s1"], samples["s2"]),
        vehicle_kinetic_energy=jnp.zeros_like(vn) + vehicle_energy,
        x=x,
        displacement=displacement,
        n_saved=count,
    )


def _oblique(mu, phi, vn, vh, friction, rtol, *, max_steps, history, n_x):
    p, first, second, (third, separated, theta_end) = _solve(
        mu, phi, vn, vh, friction, rtol=rtol, max_steps=max_steps, history=history
    )
    damage = first.y.crush
    contact_rest, contact_extra = _rest(second, True)
    free_rest, free_extra = _rest(third, False)
    end = third.y
    t_final = end.time + jnp.where(separated, free_rest, contact_rest)
    w_final = end.contact_displacement + jnp.where(separated, free_extra, contact_extra)
    # At separation the vehicle keeps the load point's velocity; at rest in contact it is
    # (3.3.3) with V0 = 0: theta V_H.
    at_separation = second.derivative.contact_displacement / jnp.exp(second.y.log_v0)
    exit_normal = jnp.where(
        separated, at_separation, theta_end * jnp.maximum(second.y.vehicle_tangential, 0.0)
    )
    # (Friction may have stopped the slide within the last step: no negative overshoot.)
    exit_tangential = jnp.maximum(second.y.vehicle_tangential, 0.0)
    recording = third.recording
    x = _grid(recording.samples, recording.count, n_x)
    hist = None
    if history:
        samples = _padded(recording.samples, recording.count)
        displacement = _displacement_field(samples, recording.count, x)
        final_displacement = displacement[-1]
        samples["crush"] = jnp.where(samples["phase"] > 1.0, damage, samples["crush"])
        hist = _history(samples, recording.count, p, x, displacement)
    else:
        final_displacement = _final_displacement(recording, x)
    max_deflection = jnp.maximum(jnp.max(final_displacement), w_final)
    return ObliqueImpact(
        t_star=first.t,
        t_final=t_final,
        s1_final=end.s1,
        s2_final=end.s2,
        w_final=w_final,
        max_deflection=max_deflection,
        damage=damage,
        exit_normal_speed=exit_normal,
        exit_tangential_speed=exit_tangential,
        exit_angle_deg=jnp.degrees(jnp.arctan2(-exit_normal, exit_tangential)),
        separated=separated.astype(t_final.dtype),
        crush_work=phi * damage,
        backing_work=end.backing_work,
        hinge_work=end.hinge_work,
        friction_work=end.friction_work,
        slope_work=end.slope_work,
        history=hist,
    )


# --------------------------------------------------------------------------------------
# Public functions.

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
    - `max_steps`: step budget of the whole run, all phases together (also the size of
      the recorded history).

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
        return _oblique_chunked(*args, rtol, **options)
    flat = _oblique_chunked(*(a.ravel() for a in args), rtol, **options)
    return jax.tree.map(lambda leaf: leaf.reshape(args[0].shape + leaf.shape[1:]), flat)


# Array inputs are solved in vmapped chunks of this many scenarios: every member of a
# vmapped solve steps until the slowest is done, and a chunk's recordings stay in cache.
# On 1024 random scenarios of benchmarks/oblique_impact.py's box (2026-11-23, rtol 1e-6):
# 245, 244, 243 and 246 us per scenario in chunks of 128, 256, 512 and 1024; larger
# chunks wait longer on their slowest member and pay less per kernel launch.
_CHUNK = 128


@functools.partial(jax.jit, static_argnames=("max_steps", "history", "n_x"))
def _oblique_chunked(mu, phi, vn, vh, friction, rtol, **options):
    solve = forward_jacobian_jvp(functools.partial(_oblique, **options), n_differentiable=5)
    if mu.ndim == 0:
        return solve(mu, phi, vn, vh, friction, rtol)
    # The step count grows with the mass ratio (correlation 0.8 in log over the benchmark's
    # box): chunks of similar mass ratios wait less on their slowest member. Measured on
    # 1e3 random scenarios: 526 us per scenario unsorted, 353 us sorted.
    return sorted_chunks(lambda *x: solve(*x, rtol), (mu, phi, vn, vh, friction), mu, _CHUNK)


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
        one = jnp.ones_like(phi)
        p, first, _, _ = _solve(
            one, phi, one, vh, 0.0 * one, rtol=rtol, max_steps=max_steps, history=True, t_end=t_end
        )
        recording = first.recording
        samples = _padded(recording.samples, recording.count)
        x = _grid(samples, recording.count, _N_X)
        displacement = _displacement_field(samples, recording.count, x)
        return MovingLoad(
            s1=first.y.s1,
            s2=first.y.s2,
            v0=first.y.v0,
            history=_history(samples, recording.count, p, x, displacement),
        )

    solve = forward_jacobian_jvp(solve, n_differentiable=3)
    for _ in range(phi.ndim):
        solve = jax.vmap(solve, in_axes=(0, 0, 0, None))
    return solve(phi, vh, t_end, rtol)
