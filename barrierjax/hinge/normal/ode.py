"""Report 3.2 by time integration.

`method="ode"`: diffrax, one solve per phase. The accelerative phase ends on a
real-valued event (the relative velocity of vehicle and beam). In time T, the
decelerative phase is singular at its end (S' -> 0/0 as V -> 0, and S(T) is not smooth
there); with the independent variable sigma = ln(V*/V) and the state chi = A ln(alpha - S)
it is smooth and non-stiff for every mass ratio, so it is integrated to
sigma_end = ln(1/rtol) + 3 and the last e^-sigma_end of the velocity is added analytically
(`_complete_at_rest`).
"""

import equinox as eqx
import jax
import jax.numpy as jnp

from ..._custom_types import Scalar
from ..._solve.phases import sigma_end as _sigma_end
from ..._solve.phases import solve_phase
from .phases import Accelerative, Decelerative, accelerative_phase, decelerative_constants


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


def _accelerative_field(theta, y: _ContactState, acc: Accelerative) -> _ContactState:
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


def _decelerative_field(sigma, y: _RunOutState, dec: Decelerative) -> _RunOutState:
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


# The solves of `solve_ode`, as `_solve.phases.raise_failures` names them.
PHASES = ("the accelerative phase", "the decelerative phase")


def ode_phases(mu, phi, *, rtol, solver, dense=False):
    """The two diffrax solves, in the speed-free variables; also used by the benchmark for
    step counts."""
    acc = accelerative_phase(mu, phi)
    dec = decelerative_constants(mu, acc)
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


def solve_ode(mu, phi, *, rtol, n_history, solver):
    acc, dec, time_unit, first, second = ode_phases(
        mu, phi, rtol=rtol, solver=solver, dense=bool(n_history)
    )
    final = _complete_at_rest(dec, _sigma_end(rtol), second.y_end)
    final["damage"] = first.y_end.crush
    final["failure"] = jnp.stack([first.failure, second.failure], axis=-1)  # `PHASES`
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
        hinge=joined(
            jnp.full_like(k, dec.s_star), dec.hinge_from_chi(run_out.chi), final["s_final"]
        ),
        displacement=joined(contact.displacement, run_out.displacement, final["w_final"]),
        backing_work=joined(contact.backing_work, run_out.backing_work, final["backing_work"]),
        hinge_work=joined(contact.hinge_work, run_out.hinge_work, final["hinge_work"]),
    )
