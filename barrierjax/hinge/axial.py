r"""Normal impact on an axially restrained beam: the beam stage of report 3.4,
(3.4.23)-(3.4.40), with the interaction of bending and axial force.

The beam of 3.2, held against axial motion far away, stretches as it deflects: the three
hinges (rotation rates 2 v0/xi at the centre, v0/xi at each side) must supply the
elongation rate of the deflected beam, int w_x v_x dx = 2 v0 w0 / xi. With the
rectangle's yield curve |M/M0| + (N/N0)^2 = 1 (3.4.7) and its flow rule (3.4.8), each
hinge extends at 2 (N/N0)(M0/N0) times its rotation rate, so that (3.4.33)

    n = N/N0 = N0 w0 / (4 M0) = 2 eta0 W0,   eta0 = N0 / (4 (M0 q0)^1/2),

in the dimensionless variables of 3.2 (ERRATA). The moment equation of the half-beam
(3.4.28) holds 2 M + N w0 = 2 M0 (1 - n^2) + 4 M0 n^2 = 2 M0 (1 + n^2): the axial force
stiffens the mechanism as if M0 were M0 (1 + n^2), and (3.4.34)-(3.4.35) read, with
K = 3/2 (1 + n^2) (ERRATA for the first line of (3.4.34)),

    V0'    = 2 phi / S - 1/2 - K / S^2
    V0 S'  = K / S - S/2 - phi                                            (3.4.35)

The same identity follows from virtual power: the hinges dissipate M0 (1 - n^2) 4 v0/xi
in bending and N 2 v0 w0/xi = M0 2 n^2 4 v0/xi in stretching. The hinge distance is
non-decreasing throughout (its rate is K/S - S/2 - phi >= 0 once n > 0), as (3.4.24)
requires.

Accelerative phase: P = P0 (phi constant), from V0 = 0, W0 = 0, S = S* (3.4.37), until the
vehicle's velocity 1 - phi T/mu meets V0 (3.4.38). At T = 0, V0 S' = 0 = V0, and S' is
0/0; its limit is 0 (K/S - S/2 - phi is O(n^2) = O(T^4) there), which is the value used at
V0 = 0 exactly. S moves by O(T^4) at first; near T = 0 the rate of S relaxes as 1/V0,
which the explicit Tsit5 handles in fewer steps than the L-stable Kvaerno5 (2-30 times
fewer, measured over light to heavy vehicles at rtol 1e-6 and 1e-9), whose error estimate
is the more cautious there.

Decelerative phase: phi = -mu V0' (3.4.38), which gives (3.4.39):

    V0'   = -(S/2 + K/S) / (S + 2 mu)
    V0 S' = K (S + mu) / (S (S + 2 mu)) - S (S + 3 mu) / (2 (S + 2 mu))

integrated, as in 3.2, in sigma = ln(V*/V0), in which the approach to rest is smooth, to
V0 = V* rtol e^-3; the rest is added with S frozen. At rest S is the positive root of the
cubic (3.4.40), S^3 + 3 mu S^2 - 3 (1 + n_f^2) S - 3 mu (1 + n_f^2) = 0, n_f = 2 lambda_f.

All of it runs in the speed-free variables of `normal.py` (tau = T/V, v = V0/V, w = W0/V^2
for the impact speed V): n = 2 eta w with eta = eta0 V^2, so the speed enters through eta.

The beam stage ends where n reaches 1 (eta0 W0 = 1/2, (3.4.43)): the beam is then a
plastic string (3.4.45), whose motion this module does not solve; `t_string` reports
where it begins.
"""

import diffrax
import equinox as eqx
import jax
import jax.numpy as jnp

from .._custom_types import Scalar
from .._solve.phases import sigma_end as _sigma_end
from .._solve.phases import solve_phase


class _Params(eqx.Module):
    mu: Scalar
    phi: Scalar
    eta: Scalar  # eta0 V^2: n = 2 eta w
    s_star: Scalar


def _axial(w, p: _Params):
    """n = N/N0 (3.4.33) and K = 3/2 (1 + n^2)."""
    n = 2.0 * p.eta * w
    return n, 1.5 * (1.0 + n * n)


class _Accelerating(eqx.Module):
    vehicle_velocity: Scalar
    beam_velocity: Scalar
    hinge_offset: Scalar  # S - S*, free of the cancellation in K/S - S/2 - phi
    displacement: Scalar
    crush: Scalar
    backing_work: Scalar
    bending_work: Scalar
    stretching_work: Scalar


def _accelerating_field(tau, y: _Accelerating, p: _Params) -> _Accelerating:
    v, w = y.beam_velocity, y.displacement
    n, k = _axial(w, p)
    s = p.s_star + y.hinge_offset
    # K/S - S/2 - phi = 3/2 n^2 / S - (S - S*)(S + S* + 2 phi) / (2 S): S* is the root.
    hinge_rate_times_v = 1.5 * n * n / s - y.hinge_offset * (s + p.s_star + 2.0 * p.phi) / (2 * s)
    moving = v > 0.0
    return _Accelerating(
        vehicle_velocity=-p.phi / p.mu + 0.0 * v,
        beam_velocity=2.0 * p.phi / s - 0.5 - k / s**2,
        hinge_offset=jnp.where(moving, hinge_rate_times_v / jnp.where(moving, v, 1.0), 0.0),
        displacement=v,
        crush=y.vehicle_velocity - v,
        backing_work=0.5 * v * s,
        bending_work=0.5 * v / s * (1.0 - n * n),
        stretching_work=v * n * n / s,
    )


class _Decelerating(eqx.Module):
    hinge: Scalar
    time: Scalar
    displacement: Scalar
    backing_work: Scalar
    bending_work: Scalar
    stretching_work: Scalar


def _decelerating_rates(s, w, p: _Params):
    """(3.4.39): V0' and V0 S'."""
    n, k = _axial(w, p)
    total = s + 2.0 * p.mu
    acceleration = -(0.5 * s + k / s) / total
    hinge_rate_times_v = k * (s + p.mu) / (s * total) - s * (s + 3.0 * p.mu) / (2.0 * total)
    return n, acceleration, hinge_rate_times_v


def _decelerating_field(sigma, y: _Decelerating, args) -> _Decelerating:
    """Against sigma = ln(V*/V0): d/dsigma = -(V0 / V0') d/dT."""
    p, v_star = args
    v = v_star * jnp.exp(-sigma)
    n, acceleration, hinge_rate_times_v = _decelerating_rates(y.hinge, y.displacement, p)
    dtau = -v / acceleration
    dw = v * dtau
    return _Decelerating(
        hinge=-hinge_rate_times_v / acceleration,
        time=dtau,
        displacement=dw,
        backing_work=0.5 * dw * y.hinge,
        bending_work=0.5 * dw / y.hinge * (1.0 - n * n),
        stretching_work=dw * n * n / y.hinge,
    )


def axial_beam_stage(mu, phi, eta, *, rtol: float, n_history: int = 0, solver=None) -> dict:
    """The beam stage, speed-free (see the module docstring); `eta` = eta0 V^2. Returns
    the end-of-crushing state, the state at rest (or where the string begins), the works,
    `t_string` (inf where n stays below 1) and, with `n_history`, `history`: that many
    samples per phase and the state at rest, in the fields of `normal.py`'s histories
    plus `axial_force`."""
    solver = diffrax.Tsit5() if solver is None else solver
    root = jnp.sqrt(phi**2 + 3.0)
    s_star = 3.0 / (root + phi)
    p = _Params(mu, phi, eta, s_star)
    options = {"solver": solver, "rtol": rtol, "atol": 1e-3 * rtol, "dense": bool(n_history)}
    zero = jnp.zeros_like(mu)
    # The velocities meet by T = mu/phi at the latest, where the vehicle's has fallen to
    # zero and the beam's is not negative (the axial force slows the beam, so the phase
    # outlasts its 3.2 length 1/((phi - S*)/S* + phi/mu)).
    first = solve_phase(
        _accelerating_field,
        _Accelerating(zero + 1.0, zero, zero, zero, zero, zero, zero, zero),
        zero,
        mu / phi,
        p,
        switch=lambda t, y, p: jnp.minimum(
            y.vehicle_velocity - y.beam_velocity, 1.0 - _axial(y.displacement, p)[0]
        ),
        max_steps=4096,
        **options,
    )
    a = first.y_end
    string_in_first = _axial(a.displacement, p)[0] >= 1.0 - 1e-9
    v_star = a.beam_velocity
    second = solve_phase(
        _decelerating_field,
        _Decelerating(
            s_star + a.hinge_offset,
            first.t_end,
            a.displacement,
            a.backing_work,
            a.bending_work,
            a.stretching_work,
        ),
        zero,
        zero + _sigma_end(rtol),
        (p, v_star),
        switch=lambda sigma, y, args: 1.0 - _axial(y.displacement, args[0])[0],
        switch_required=False,
        max_steps=16384,
        **options,
    )
    d = second.y_end
    # The rest from V0 = V* e^-sigma_end, with S frozen and V0' constant.
    v_end = v_star * jnp.exp(-_sigma_end(rtol))
    _, acceleration, _ = _decelerating_rates(d.hinge, d.displacement, p)
    n_end, _ = _axial(d.displacement, p)
    remaining = v_end / -acceleration
    dw = 0.5 * v_end * remaining
    rest = {
        "s_final": d.hinge,
        "t_final": d.time + remaining,
        "w_final": d.displacement + dw,
        "backing_work": d.backing_work + 0.5 * dw * d.hinge,
        "bending_work": d.bending_work + 0.5 * dw / d.hinge * (1.0 - n_end**2),
        "stretching_work": d.stretching_work + dw * n_end**2 / d.hinge,
    }
    t_string = jnp.where(string_in_first, first.t_end, jnp.where(second.switched, d.time, jnp.inf))
    history = _history(first, second, p, v_star, rest, n_history) if n_history else None
    return dict(
        history=history,
        s_star=s_star,
        t_star=first.t_end,
        v_star=v_star,
        w_star=a.displacement,
        damage=a.crush,
        t_string=t_string,
        **rest,
    )


def _history(first, second, p: _Params, v_star, rest, n_history):
    """Phase 1 uniform in time (n_history samples), phase 2 uniform in sigma after its
    start up to where the solve stopped (n_history - 1), then the state at rest."""
    k = jnp.linspace(0.0, 1.0, n_history)
    a = jax.vmap(first.dense.evaluate)(first.t_end * k)
    sigma = second.t_end * k[1:]
    d = jax.vmap(second.dense.evaluate)(sigma)
    v = v_star * jnp.exp(-sigma)
    n1, _ = _axial(a.displacement, p)
    n2, acceleration, _ = _decelerating_rates(d.hinge, d.displacement, p)
    n_rest, _ = _axial(rest["w_final"], p)

    def joined(first_phase, second_phase, at_rest):
        return jnp.concatenate([first_phase, second_phase, jnp.atleast_1d(at_rest)])

    return {
        "time": joined(first.t_end * k, d.time, rest["t_final"]),
        "vehicle_velocity": joined(a.vehicle_velocity, v, 0.0),
        "barrier_velocity": joined(a.beam_velocity, v, 0.0),
        "hinge": joined(p.s_star + a.hinge_offset, d.hinge, rest["s_final"]),
        "displacement": joined(a.displacement, d.displacement, rest["w_final"]),
        "contact_force": joined(jnp.full_like(k, p.phi), -p.mu * acceleration, 0.0),
        "crush": joined(a.crush, jnp.full_like(sigma, a.crush[-1]), a.crush[-1]),
        "backing_work": joined(a.backing_work, d.backing_work, rest["backing_work"]),
        "hinge_work": joined(
            a.bending_work + a.stretching_work,
            d.bending_work + d.stretching_work,
            rest["bending_work"] + rest["stretching_work"],
        ),
        "axial_force": joined(n1, n2, n_rest),
    }
