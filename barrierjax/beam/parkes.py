r"""Parkes's rigid-plastic cantilever with a tip mass struck at the tip (Parkes 1955).

The reference against which the beam finite element of report 4.2-4.3 is checked in the
limit of a stiff, rate-independent material and small deflections (Example 1 of 4.3 is
Parkes's problem: the Bodner-Symonds tests).

A cantilever of length L, mass m per unit length and fully plastic moment M0 carries a mass
M at its free end. The tip receives an impulse I = M V0, either at once (the tip mass starts
at the speed V0, the beam at rest) or as a rectangular force F = I/tau lasting tau.
Rigid-perfectly plastic material, small deflections (Parkes 1955; the derivation follows
Jones, Structural Impact, 1989, section 3.8, re-derived here). x is measured from the tip,
xi(t) is the hinge's distance from the tip, and

    u = m xi / M            (the beam mass between tip and hinge over the tip mass),
    u_L = m L / M = 1/gamma (gamma = M/(m L), the mass ratio),
    T = M^2 V0 / (3 M0 m)   (the time scale),     K0 = M V0^2 / 2.

Travelling hinge (impulsive case). The segment 0 < x < xi turns about the hinge, whose
material point is at rest (the velocity is continuous): v = omega (xi - x), V = omega xi at
the tip; the beam beyond is at rest at M = M0. The moment peaks at the hinge, so the shear
there is zero. Linear momentum of the segment is then conserved:

    M V + m V xi / 2 = M V0,     so  V = 2 V0 / (2 + u).

Moment of momentum about the fixed point that the hinge occupies at time t:
d/dt [V xi (M + m xi/3)] - xi' (M V0) = -M0 (the second term: the reference point of
V xi (M + m xi/3) moves with the hinge while the momentum M V0 is constant). With V above,

    xi' = 3 M0 (2M + m xi)^2 / (M V0 m xi (4M + m xi)),
    t(u) = T u^2 / (2 + u)                    (t = m V0 xi^2 / (6 M0 (1 + m xi/(2M)))).

Tip deflection and rotation of the segment (integrals of V dt and omega dt = V/xi dt):

    W(u)     = 2 V0 T B(u),  B(u) = ln(1 + u/2) - u (4 + u) / (2 (2 + u)^2),
    Theta(u) = (2 M V0^2 / (3 M0)) u (8 + 3u) / (4 (2 + u)^2).

The travelling hinge dissipates M0 omega (the jump in the rotation rate across it), so
D(u) = M0 Theta(u) = K0 u (8 + 3u) / (3 (2 + u)^2), and the kinetic energy
K(u) = V^2 (M + m xi/3)/2 = 4 K0 (1 + u/3) / (2 + u)^2 makes K + D = K0 (checked in the tests).
The hinge reaches the root at t1 = T u_L^2 / (2 + u_L) = M V0 L / (3 M0 (1 + 2 gamma)).

Root hinge. The whole beam turns about the root: J omega' = -M0 with
J = M L^2 + m L^3 / 3 = M L^2 (1 + u_L/3), from omega1 = V1/L, V1 = 2 V0 / (2 + u_L), so
the root turns theta2 = J omega1^2 / (2 M0) (= K(u_L)/M0) in J omega1 / M0.

Final tip deflection (impulsive): delta = W(u_L) + L theta2, which simplifies to

    delta = (2 gamma M V0^2 L / (3 M0)) [ln(1 + 1/(2 gamma)) + 1 / (2 (1 + 2 gamma))].

Limits: gamma -> inf (heavy tip mass) gives delta -> M V0^2 L / (2 M0), the rigid rotation
about the root that dissipates K0 = M0 delta / L; gamma -> 0 at fixed impulse grows like
(2 I^2 / (3 m M0)) ln(1/(2 gamma)) (the deformation crowds to the tip).

Rectangular pulse (tau > 0). While the force acts the hinge stands still at xi0 (xi' = 0 in
the moment balance with the tip force, F xi0 - M0 + ... , whose solution is the stationary
hinge where the shear vanishes): M0 = F m xi0^2 / (6 (M + m xi0/2)), which in u reads
u0^2 / (2 + u0) = tau / T, the same relation as t(u) above: after the pulse the hinge
travels on from u0 as if the impulse had been given at once, and reaches the root at the
same t1. During the pulse the segment turns about xi0 through
theta0 = I tau / (2 xi0 M (1 + u0/2)), the tip moves V0 tau / (2 + u0), the force does the
work 2 K0 / (2 + u0) (< K0: the beam shares the momentum while the force acts), and
M0 theta0 = K0 (2 u0/3) / (2 + u0)^2 is dissipated. If tau >= t1 (u0 >= u_L) the hinge
forms at the root at once: J omega' = F L - M0 during the pulse (no motion if F L <= M0).

Everything is in closed form, so `jax.grad` and `jax.vmap` go straight through; B(u) is
summed from its Taylor series below u = 0.1, where the closed form cancels.
"""

import equinox as eqx
import jax.numpy as jnp

from .. import _checks
from .._custom_types import Scalar, Vector

# Taylor coefficients of B(u) = int_0^u s (4 + s) / (2 + s)^3 ds, from u^2 to u^14.
_B_SERIES = (
    1 / 4,
    -5 / 24,
    9 / 64,
    -7 / 80,
    5 / 96,
    -27 / 896,
    35 / 2048,
    -11 / 1152,
    27 / 5120,
    -65 / 22528,
    77 / 49152,
    -45 / 53248,
    13 / 28672,
)
_B_SERIES_BELOW = 0.1


def _b(u):
    """B(u) = int_0^u s (4 + s) / (2 + s)^3 ds: the travelling hinge's tip deflection in
    units of 2 V0 T."""
    small = u < _B_SERIES_BELOW
    us = jnp.where(small, u, 0.0)
    series = us**2 * jnp.polyval(jnp.asarray(_B_SERIES[::-1], dtype=us.dtype), us)
    ul = jnp.where(small, 1.0, u)
    closed = jnp.log1p(ul / 2) - ul * (4 + ul) / (2 * (2 + ul) ** 2)
    return jnp.where(small, series, closed)


def _theta(u):
    """int_0^u (4 + s) / (2 + s)^3 ds: the segment's rotation in units of 2 V0 T m / M."""
    return u * (8 + 3 * u) / (4 * (2 + u) ** 2)


def _time(u):
    """t(u) / T = u^2 / (2 + u)."""
    return u**2 / (2 + u)


def _time_inverse(s):
    """The root u >= 0 of u^2 / (2 + u) = s >= 0 (double where: sqrt at s = 0)."""
    positive = s > 0
    ss = jnp.where(positive, s, 1.0)
    root = (ss + jnp.sqrt(ss * ss + 8 * ss)) / 2
    return jnp.where(positive, root, 0.0)


class ParkesHistory(eqx.Module):
    """The motion, sampled `n_history` times in each of the three phases (pulse,
    travelling hinge, root hinge; a phase that does not occur repeats its end point):
    `time`, `hinge_position` (distance from the tip), `tip_velocity`, `tip_deflection`,
    `dissipated` (energy dissipated so far), `phase` (0, 1, 2)."""

    time: Vector
    hinge_position: Vector
    tip_velocity: Vector
    tip_deflection: Vector
    dissipated: Vector
    phase: Vector


class ParkesCantilever(eqx.Module):
    """Parkes's solution (see the module docstring).

    - `tip_deflection`: the final tip deflection (small-deflection theory).
    - `root_rotation`: the final kink at the root, radians (with the pulse's when the
      pulse outlasts the travelling phase and its hinge stands at the root).
    - `pulse_rotation`: the kink left at `hinge_start` by the pulse (the root's when the
      hinge stands at the root: `root_rotation` includes it then).
    - `travelling_deflection`: the tip deflection gained before the hinge reaches the root
      (pulse and travelling-hinge phases).
    - `hinge_start`: xi0, where the hinge stands while the pulse acts (0 for an impulse;
      `length` if the pulse outlasts the travelling phase).
    - `root_time`: t1, when the hinge reaches the root; `end_time`: when the motion stops.
    - `input_energy`: the work done on the beam and tip mass (K0 = M V0^2/2 for an
      impulse); `pulse_energy`, `travelling_energy`, `root_energy`: dissipated during
      the pulse at the stationary hinge, at the travelling hinge, and at the root.
    - `positions`, `final_shape`: the permanent deflection at `n_history` points from the
      tip (x = 0) to the root (x = L).
    - `history`: a `ParkesHistory`.
    """

    tip_deflection: Scalar
    root_rotation: Scalar
    pulse_rotation: Scalar
    travelling_deflection: Scalar
    hinge_start: Scalar
    root_time: Scalar
    end_time: Scalar
    input_energy: Scalar
    pulse_energy: Scalar
    travelling_energy: Scalar
    root_energy: Scalar
    positions: Vector
    final_shape: Vector
    history: ParkesHistory


def parkes_cantilever(
    tip_mass,
    speed,
    *,
    plastic_moment,
    mass_per_length,
    length,
    pulse_duration=0.0,
    n_history: int = 64,
) -> ParkesCantilever:
    """Parkes's (1955) rigid-plastic cantilever of length L with a tip mass M, struck
    transversely at the tip (see the module docstring for the derivation).

    **Arguments:**

    - `tip_mass`: M, positive.
    - `speed`: V0 = I / M, the tip mass's speed after the impulse I, positive.
    - `plastic_moment`: M0, the fully plastic moment (sigma0 B H^2 / 4 for a rectangle).
    - `mass_per_length`: m, the beam's mass per unit length.
    - `length`: L.
    - `pulse_duration`: tau >= 0; 0 (default) for an impulse, else the impulse M V0 is
      delivered by the rectangular force M V0 / tau lasting tau.
    - `n_history`: samples per phase in the history and points in the final shape
      (static).

    Consistent units (e.g. in, lbf, s). Scalars; `jax.vmap` over them and `jax.grad` with
    respect to any of them work (at tau = 0 the derivative with respect to tau is
    infinite: u0 grows like sqrt(tau)).
    """
    n_history = _checks.history_samples(n_history, optional=False)
    return _parkes(
        _checks.positive("tip_mass", tip_mass),
        _checks.positive("speed", speed),
        _checks.positive("plastic_moment", plastic_moment),
        _checks.positive("mass_per_length", mass_per_length),
        _checks.positive("length", length),
        _checks.non_negative("pulse_duration", pulse_duration),
        n_history,
    )


@eqx.filter_jit
def _parkes(M, V0, M0, m, L, tau, n):
    T = M**2 * V0 / (3 * M0 * m)
    K0 = M * V0**2 / 2
    I = M * V0
    uL = m * L / M
    J = M * L**2 * (1 + uL / 3)
    theta_unit = 2 * M * V0**2 / (3 * M0)  # Theta(u) = theta_unit * _theta(u)
    t1 = T * _time(uL)
    root_at_once = tau >= t1  # the pulse outlasts the travelling phase

    # Phase 0, pulse, hinge standing at xi0 = us M / m (case A: us < uL).
    us = jnp.minimum(_time_inverse(tau / T), uL)
    theta0_a = theta_unit * us / (2 * (2 + us) ** 2)
    # (= I tau / (2 xi0 M (1 + u0/2)) with tau = T u0^2 / (2 + u0) and xi0 = M u0 / m)
    tip0_a = V0 * tau / (2 + us)
    work0_a = 2 * K0 / (2 + us)
    # Case B: root hinge during the pulse, J omega' = F L - M0 (F = I/tau > 0 here).
    safe_tau = jnp.where(root_at_once, tau, 1.0)
    alpha_b = jnp.maximum(I * L / safe_tau - M0, 0.0) / J
    theta0_b = alpha_b * safe_tau**2 / 2
    omega1_b = alpha_b * safe_tau
    xi0 = jnp.where(root_at_once, L, us * M / m)
    theta0 = jnp.where(root_at_once, theta0_b, theta0_a)
    tip0 = jnp.where(root_at_once, L * theta0_b, tip0_a)
    work0 = jnp.where(root_at_once, (I / safe_tau) * L * theta0_b, work0_a)
    pulse_energy = M0 * theta0

    # Phase 1, travelling hinge from us to uL (empty in case B: us = uL).
    W1 = 2 * V0 * T * (_b(uL) - _b(us))
    travelling_energy = M0 * theta_unit * (_theta(uL) - _theta(us))

    # Phase 2, root hinge.
    omega1 = jnp.where(root_at_once, omega1_b, 2 * V0 / ((2 + uL) * L))
    theta2 = J * omega1**2 / (2 * M0)
    root_energy = M0 * theta2
    t_root = jnp.where(root_at_once, tau, t1)
    end_time = t_root + J * omega1 / M0
    travelling = tip0 + W1
    tip_deflection = travelling + L * theta2
    root_rotation = theta2 + jnp.where(root_at_once, theta0_b, 0.0)

    # Final shape: rotation about xi0 during the pulse, the travelling hinge's deposit
    # (a point at x has moved int omega (xi - x) dt since the hinge passed it), the root.
    x = jnp.linspace(0.0, 1.0, n, dtype=L.dtype) * L
    ux = jnp.clip(m * x / M, us, uL)
    shape = (
        theta0 * jnp.maximum(xi0 - x, 0.0)
        + 2 * V0 * T * (_b(uL) - _b(ux))
        - x * theta_unit * (_theta(uL) - _theta(ux))
        + theta2 * (L - x)
    )

    # History.
    r = jnp.linspace(0.0, 1.0, n, dtype=L.dtype)
    # Pulse: the tip speed grows linearly, deflection and dissipation quadratically.
    v_pulse = jnp.where(root_at_once, L * omega1_b, 2 * V0 / (2 + us))
    tA = r * tau
    VA = v_pulse * jnp.where(tau > 0, r, 1.0)  # an impulse: V0 at t = 0+
    wA = tip0 * r**2
    dA = pulse_energy * r**2
    u_hist = us + r * (uL - us)
    tB = tau + T * (_time(u_hist) - _time(us))
    VB = 2 * V0 / (2 + u_hist)
    wB = tip0 + 2 * V0 * T * (_b(u_hist) - _b(us))
    dB = pulse_energy + M0 * theta_unit * (_theta(u_hist) - _theta(us))
    s = r * (end_time - t_root)
    omega_hist = omega1 - M0 * s / J
    tC = t_root + s
    VC = L * omega_hist
    wC = travelling + L * (omega1 * s - M0 * s**2 / (2 * J))
    dC = pulse_energy + travelling_energy + M0 * (omega1 * s - M0 * s**2 / (2 * J))
    ones = jnp.ones_like(r)
    history = ParkesHistory(
        time=jnp.concatenate([tA, tB, tC]),
        hinge_position=jnp.concatenate([xi0 * ones, u_hist * M / m, L * ones]),
        tip_velocity=jnp.concatenate([VA, VB, VC]),
        tip_deflection=jnp.concatenate([wA, wB, wC]),
        dissipated=jnp.concatenate([dA, dB, dC]),
        phase=jnp.concatenate([0 * ones, ones, 2 * ones]),
    )
    return ParkesCantilever(
        tip_deflection=tip_deflection,
        root_rotation=root_rotation,
        pulse_rotation=theta0,
        travelling_deflection=travelling,
        hinge_start=xi0,
        root_time=t_root,
        end_time=end_time,
        input_energy=work0,
        pulse_energy=pulse_energy,
        travelling_energy=travelling_energy,
        root_energy=root_energy,
        positions=x,
        final_shape=shape,
        history=history,
    )
