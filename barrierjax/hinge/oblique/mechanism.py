"""The mechanism of report 3.3: dimensionless variables, equations of motion (3.3.16),
the velocity field (3.3.2), and the start at T = 0.

Scales as in 3.2 (docs/errata.md, 3.3.14): lengths over L = 2 (M0/q0)^1/2, forces over
P_b = 4 (M0 q0)^1/2, time over t0 = m^1/2 M0^1/4 / q0^3/4, mass ratio mu = M/(m L). The
contact point moves along the beam at the vehicle's tangential speed V_H; S1 is the
distance from the contact point to the hinge ahead of it (the right hinge), S2 to the
hinge behind it, and V0 the beam's velocity under the contact point.

Equations of motion, (3.3.16) with the force ratio g = P/P_b and the load speed c = F':

    V0' = -3 / (2 S1 S2) - 1/2 + 4 g / (S1 + S2)
    V0 (S1' + 3/2 c) = 3/4 (S1 + S2)/(S1 S2) - S1/2 - 2 g S1 / (S1 + S2)
    V0 (S2' - 3/2 c) = 3/4 (S1 + S2)/(S1 S2) - S2/2 - 2 g S2 / (S1 + S2)

((3.3.10) as corrected in docs/errata.md, 3.3.10: 4P in the first line, P xi2 in the third.)

Friction (the `friction` option): Coulomb, tangential force f P on the vehicle, none on
the beam (as in the report). The normal force acts along the undeformed normal, so the
vehicle's kinetic-energy loss is crush + friction work + work on the barrier (P V0) +
`slope_work` (P theta V_H): the report holds V_H fixed, and this last term is the work
of whatever holds it so; it is reported, not fed back into V_H. Once the slide stops,
static friction holds the vehicle: V_H stays 0.
"""

import equinox as eqx
import jax.numpy as jnp

from ..._custom_types import Scalar


def beam_acceleration(s1, s2, force):
    return -1.5 / (s1 * s2) - 0.5 + 4.0 * force / (s1 + s2)


def hinge_terms(s1, s2, force):
    """g1, g2: V0 (S1' + 3/2 c) = g1 and V0 (S2' - 3/2 c) = g2."""
    total = s1 + s2
    common = 0.75 * total / (s1 * s2)
    return (
        common - 0.5 * s1 - 2.0 * force * s1 / total,
        common - 0.5 * s2 - 2.0 * force * s2 / total,
    )


def beam_powers(v0, s1, s2):
    """Backing and hinge dissipation rates: q0 int v dx and M0 times the hinges' rotation
    rates (V0/S1, V0/S2 and their sum at the load), in the units of 3.2."""
    return 0.25 * v0 * (s1 + s2), 0.25 * v0 * (1.0 / s1 + 1.0 / s2)


def beam_kinetic_energy(v0, s1, s2):
    return v0**2 * (s1 + s2) / 6.0


def velocity_field(v0, s1, s2, position, x):
    """The beam's velocity at x, (3.3.2): V0 under the load, falling linearly to zero at
    the hinges S1 ahead and S2 behind."""
    offset = x - position
    return v0 * jnp.where(
        offset >= 0.0, jnp.maximum(1.0 - offset / s1, 0.0), jnp.maximum(1.0 + offset / s2, 0.0)
    )


class Params(eqx.Module):
    """The solve's constants (the step loop's `args`)."""

    mu: Scalar
    phi: Scalar
    friction: Scalar
    s_star: Scalar
    rtol: Scalar
    t_end: Scalar  # the moving load's end time; unused otherwise
    moving_load: bool = eqx.field(static=True, default=False)


class State(eqx.Module):
    """The state of every phase: against T while the vehicle crushes, with `speed` = V0;
    then against s, dT/ds = V0, with `speed` = ln V0 (the decelerative phases end at
    V0 -> 0, where S' = g_i/V0 is 0/0 in T and every rate in s is regular). Both have the
    rate V0'(T)."""

    speed: Scalar
    s1: Scalar
    s2: Scalar
    time: Scalar
    position: Scalar
    rotation: Scalar  # Phi
    vehicle_normal: Scalar  # integrated while crushing; then the exit value (`transition`)
    vehicle_tangential: Scalar
    crush: Scalar
    contact_displacement: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar


def start_series(t, vn, vh, p: Params) -> dict:
    """The crushing phase at a small time t, from its expansion about T = 0.

    At T = 0, V0 = 0 and S' = g_i/V0 is 0/0, and for force ratios near 1 the linearised
    hinge equations are stiff in proportion to 1/V0'(0): no explicit step from T = 0 is
    stable. To first order, V0 = a T with a = V0'(0), and the hinges move in the
    antisymmetric mode S1 - S* = S* - S2 = sigma T, sigma = -3/2 a V_H / (a + 1/2 +
    phi/S*) (linearise the second and third lines of (3.3.16) about S1 = S2 = S*; the
    symmetric mode has no regular first-order part); the integrals follow to second order,
    so that the energy balance closes to O(t^3). The neglected terms are O(t^2), relative
    O(t / T*). The state's quantities, with V0 for ln V0."""
    a = beam_acceleration(p.s_star, p.s_star, p.phi)
    sigma = -1.5 * a * vh / (a + 0.5 + p.phi / p.s_star)
    vehicle = 0.0 if p.moving_load else 1.0
    deceleration = vehicle * p.friction * p.phi / p.mu
    braking = deceleration > 0.0
    stop = jnp.where(braking, vh / jnp.where(braking, deceleration, 1.0), jnp.inf)
    slide = jnp.minimum(t, stop)
    slid = vh * slide - 0.5 * deceleration * slide**2
    # (Past the stop V_H is exactly 0, not vh - deceleration stop, which may round below.)
    sliding_speed = jnp.where(t < stop, vh - deceleration * t, 0.0)
    contact_displacement = 0.5 * a * t**2
    return {
        "v0": a * t,
        "s1": p.s_star + sigma * t,
        "s2": p.s_star - sigma * t,
        "time": t,
        "position": slid,
        "rotation": 0.5 * a * t**2 / p.s_star,
        "vehicle_normal": vn - vehicle * p.phi * t / p.mu,
        "vehicle_tangential": sliding_speed,
        "crush": vehicle * (vn * t - 0.5 * p.phi * t**2 / p.mu - contact_displacement),
        "contact_displacement": contact_displacement,
        "backing_work": 0.25 * a * p.s_star * t**2,
        "hinge_work": 0.25 * a * t**2 / p.s_star,
        "friction_work": p.friction * p.phi * slid,
        "slope_work": jnp.zeros_like(t),
    }
