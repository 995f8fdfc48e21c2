"""The barrier's memory, report 3.3.4-3.3.6 and (3.3.21)'s convective term R.

A point x ahead of the load lies still until the right hinge reaches it, then rides the
right rigid segment, whose slope rate is -V0/S1, until the load arrives. With
Phi(T) = int_0^T V0/S1, the slope under the load is

    theta = Psi(F) - Phi,   Psi(x) = Phi at the time the right hinge passed x,

and (3.3.21)'s R is V_H Psi'(F) F' + V_H' theta: the first term is V_H^2 times the
curvature dPsi/dx that the right hinge left behind at the load point. Psi is the curve
(H, Phi) traced by the right hinge H = F + S1; it is recorded, one sample per accepted
step, in a fixed-size buffer that the vector field reads (`barrierjax._solve.recorded_rk`):
the delay T1 of (3.3.5) is never solved for (docs/errata.md, 3.3.21). Each sample holds
Phi, dPhi/dH and d2Phi/dH2 (the last from the field's derivative along the solution), and
Psi is their quintic Hermite interpolant, so that the memory is as accurate as the
Dormand-Prince steps that record it. Psi = 0 ahead of the initial hinge, x < S*.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Float, Int

from ..._custom_types import Scalar
from ..._solve.hermite import quintic_hermite
from ..._solve.recorded_rk import Recording

# The columns of the recording that hold the right hinge's trace.
MEMORY = ("hinge", "rotation", "curvature", "curvature_rate")


def _interval(recording: Recording, x, first, last):
    """The i in [first, max(last - 1, first)] with hinge[i] <= x < hinge[i + 1], clamped
    to the ends: bisection within the segment's samples, reading one sample per halving."""

    def halve(_, bounds):
        lo, hi = bounds
        mid = (lo + hi) // 2
        right = recording.rows(mid, 1, ("hinge",))["hinge"][0] <= x
        return jnp.where(right, mid, lo), jnp.where(right, hi, mid)

    halvings = max(1, math.ceil(math.log2(recording.capacity)))
    lo, _ = jax.lax.fori_loop(0, halvings, halve, (first, jnp.maximum(last, first)))
    return lo


# The samples of the right hinge's trace that one step of the load may read: the step is
# bounded to stay within them (`max_step`). A step of the load crosses about as many
# samples as a step of the hinge records, one.
_WINDOW = 8


class Past(eqx.Module):
    """What a step reads of the right hinge's recorded trace: `_WINDOW` consecutive
    samples (H, Phi, dPhi/dH, d2Phi/dH2) from `start` (H = +inf past the last recorded
    one), the segment's bounds (`Params.segment`) and `reach`, the furthest position the
    window covers."""

    hinge: Float[Array, " window"]
    rotation: Float[Array, " window"]
    curvature: Float[Array, " window"]
    curvature_rate: Float[Array, " window"]
    start: Int[Array, ""]
    first: Int[Array, ""]
    last: Int[Array, ""]
    reach: Scalar


def read_past(y, stage, recording: Recording, previous: Past | None = None) -> Past:
    """The window of the trace from the interval holding the load, found once per step:
    by bisection, or from `previous`, the last step's window. The load only advances,
    and each step keeps it short of its window's reach (`max_step`), so the interval
    holding it now lies in the last window."""
    first, last = stage.first, stage.last
    recorded = jnp.maximum(recording.count - 1, 0)
    last = jnp.minimum(last, recorded)
    if previous is None:
        interval = _interval(recording, y.position, first, last)
    else:
        below = jnp.sum(previous.hinge <= y.position).astype(previous.start.dtype)
        interval = previous.start + jnp.maximum(below - 1, 0)
        interval = jnp.clip(interval, first, jnp.maximum(last - 1, first))
    start = jnp.minimum(interval, recording.capacity - _WINDOW)
    window = recording.rows(start, _WINDOW, MEMORY)
    filled = start + jnp.arange(_WINDOW, dtype=start.dtype) <= recorded
    hinge = jnp.where(filled, window.pop("hinge"), jnp.inf)
    reach = jnp.max(jnp.where(filled, hinge, -jnp.inf))
    return Past(hinge=hinge, **window, start=start, first=first, last=last, reach=reach)


def _cubic_hermite(u, width, left, right):
    """As `barrierjax._solve.hermite.quintic_hermite`, through (value, slope) at both ends."""
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


def slope_memory(past: Past, x, s_star):
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
    psi, dpsi = quintic_hermite(u, width, left, right, derivatives=1)
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
