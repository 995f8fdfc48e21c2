"""The closed form of report 3.2, (3.2.11)-(3.2.20).

`method="closed_form"`: the integrals in S are split at S_m = S* + (alpha - S*)/4. On
[S*, S_m] a Gauss rule in z = ln(S + beta) resolves the near-singular factor
(S + beta)^(B - 1) of light, hard-hit barriers; on [S_m, alpha] product integration
integrates the end singularity (alpha - S)^(A - 1) (or ^(2A - 1) for displacement and
work) exactly, in place of the report's truncated series for the last step.
"""

import math

import jax.numpy as jnp

from ..._solve.quadrature import gauss_legendre, jacobi_product_nodes, jacobi_product_weights
from .phases import Decelerative, accelerative_phase, decelerative_constants


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


def _head_integrals(dec: Decelerative, s_end, n: int):
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


def _tail_integrals(dec: Decelerative, log_gap, n: int):
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


def _split(dec: Decelerative):
    """S_m = alpha - 0.75 (alpha - S*), where the head quadrature hands over to the tail,
    and its log gap ln((alpha - S_m)/(alpha - S*)) = ln 0.75."""
    s_mid = dec.alpha - 0.75 * (dec.alpha - dec.s_star)
    return s_mid, jnp.log(jnp.asarray(0.75, s_mid.dtype))


def quadrature_points(rtol: float) -> int:
    """Nodes per segment. The rules converge geometrically; against a 30-digit reference
    over the property-test range (benchmarks/normal_impact.py) the largest relative error
    is 7e-9 with 10 nodes, 3e-10 with 12 and 5e-12 with 15, so 1.5 nodes per digit keeps
    a margin of more than ten."""
    return int(min(48, max(8, math.ceil(-1.5 * math.log10(rtol)))))


def solve_closed_form(mu, phi, *, points, n_history):
    """The closed form with `points` Gauss-Legendre nodes per segment
    (`quadrature_points` of the tolerance)."""
    acc = accelerative_phase(mu, phi)
    dec = decelerative_constants(mu, acc)
    s_mid, log_split = _split(dec)
    head, tail = _head_integrals(dec, s_mid, points), _tail_integrals(dec, log_split, points)
    tau, w, backing, hinge = head + tail
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
        history = _closed_form_history(acc, dec, points, final, n_history)
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
