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
from jaxtyping import Array, Bool, Float, Int

from ..._custom_types import Scalar
from ..._solve.hermite import Quintic, cubic_powers, polynomial
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


# The samples of the right hinge's trace that one step's view holds (`read_past`): the
# interval holding the load lies in the last step's view.
_WINDOW = 8

# How far past the end of its interval of the trace (as a multiple of the distance to it
# at the step's start) a step may take the load: the piece formed for the interval is
# read a little beyond it rather than the step ending a rounding short of its end.
_PAST_SAMPLE = 1.01

# Intervals of the trace shorter than this fraction of the load's step (as the controller
# would take it) are spanned by one piece.
_SPAN = 0.1


class Past(eqx.Module):
    """What a step reads of the right hinge's recorded trace: Psi on the interval holding
    the load, as a polynomial in the fraction u of the interval (`origin`, `width`,
    `powers`); where the step crosses the interval's end, `joint` (`crossing`), on the
    next interval too (`width_next`, `powers_next`); how far the load may go on them
    (`room`); and, for the next step's view, the `_WINDOW` consecutive samples' positions
    from `start` (+inf past the last recorded one)."""

    origin: Scalar
    width: Scalar
    powers: tuple[Scalar, ...]
    crossing: Bool[Array, ""]
    joint: Scalar
    width_next: Scalar
    powers_next: tuple[Scalar, ...]
    room: Scalar
    hinge: Float[Array, " window"]
    start: Int[Array, ""]


def read_past(y, f, h, stage, recording: Recording, previous: Past | None = None) -> Past:
    """Psi on the interval of the trace holding the load, formed once per step: the
    interval by bisection, or from `previous`, the last step's view. The load only
    advances, and each step keeps it within its interval (`room`, `max_step`), so the
    interval holding it now lies in the last view.

    The piece is Psi's quintic Hermite interpolant through the interval's ends (Phi,
    dPhi/dH, d2Phi/dH2), which is C2 with error O(step^6): the force reads Psi', and a
    lower-order or less smooth interpolant would put a kink into the vector field at
    every recorded sample the load crosses, outside the step control (with cubic Hermite,
    the error fell only as rtol^0.5). Only the segment's samples are read (`Stage.first`
    to `Stage.last`), so that a lookup at a jump of Psi' (recorded twice, left and right
    limits) takes the side the load is on whatever the rounding. Next to a breakpoint the
    second derivatives are one-sided limits of a fast-changing trace: the piece is cubic
    there (the second-derivative data dropped), which stays stable where breakpoints
    cluster. Past the segment's last sample (only within a step, which then ends or is
    retaken at the segment's end), linear: the second derivative there can be the
    one-sided limit at a breakpoint, orders of magnitude off a step away (at S*, for
    large force ratios).

    Formed once, a step's seven field evaluations each read it by Horner's rule, where
    each picked the interval from the window and formed it (a third of a batch's step,
    benchmarks/README.md, "Twenty-seventh pass"). A step that the controller would take
    past the interval's end is given the next interval's piece too, and each evaluation
    reads the one its position lies on: in a moving load's steady state the load crosses
    a sample every step (bounded to one interval, its steps would shrink to the gaps they
    record, generation after generation)."""
    x = y.position
    first, last = stage.first, stage.last
    recorded = jnp.maximum(recording.count - 1, 0)
    last = jnp.minimum(last, recorded)
    if previous is None:
        interval = _interval(recording, x, first, last)
    else:
        below = jnp.sum(previous.hinge <= x).astype(previous.start.dtype)
        interval = previous.start + jnp.maximum(below - 1, 0)
        interval = jnp.clip(interval, first, jnp.maximum(last - 1, first))
    start = jnp.minimum(interval, recording.capacity - _WINDOW)
    window = recording.rows(start, _WINDOW, MEMORY)
    offsets = jnp.arange(_WINDOW, dtype=start.dtype)
    filled = start + offsets <= recorded
    hinge = jnp.where(filled, window.pop("hinge"), jnp.inf)
    reach = jnp.max(jnp.where(filled, hinge, -jnp.inf))

    below = jnp.sum(hinge <= x).astype(start.dtype)
    i = jnp.clip(start + below - 1, first, jnp.maximum(last - 1, first))
    i = jnp.clip(i, start, start + _WINDOW - 2)
    interior = i + 1 <= last
    # Where the trace was recorded in steps much shorter than the load's (after a
    # breakpoint, where the steps restart short), the piece spans those short intervals,
    # so that the load's step is at least a fraction of what it would be: bounded to
    # consecutive samples, it would record shorter steps in turn, generation after
    # generation.
    travel = 0.0 if f is None else jnp.maximum(f.position * h, 0.0)
    long = hinge[1:] - hinge[:-1] >= _SPAN * travel
    ends = jnp.where(long & (offsets[:-1] > i - start), offsets[:-1], _WINDOW - 1)
    j = jnp.clip(start + jnp.min(ends), i + 1, jnp.minimum(last, start + _WINDOW - 1))
    j = jnp.where(interior, j, i)
    # (Picked by comparison, not indexing: under `vmap` an index is a gather, which XLA
    # runs as a kernel of its own.)
    pick = lambda samples, k: jnp.sum(jnp.where(offsets == k - start, samples, 0.0))
    data = lambda k: tuple(pick(window[name], k) for name in MEMORY[1:])

    def piece(i, j):
        """Psi on samples i to j as (origin, width, powers): quintic, cubic at a bound,
        linear from i where j = i (past the segment's last sample)."""
        interior = j > i
        h_i, h_j = pick(hinge, i), pick(hinge, j)
        left, right = data(i), data(j)
        width = jnp.where(interior, h_j - h_i, 1.0)
        phi_i, slope_i, _ = left
        zero = jnp.zeros_like(phi_i)
        at_bound = (i == first) | (j == last)
        powers = jax.tree.map(
            lambda quintic, cubic, linear: jnp.where(
                interior, jnp.where(at_bound, cubic, quintic), linear
            ),
            Quintic(width, left, right).powers,
            cubic_powers(width, left[:2], right[:2]),
            (phi_i, slope_i, zero, zero, zero, zero),
        )
        return h_i, h_j, width, powers

    h_i, h_j, width, powers = piece(i, j)
    within = interior & (x < h_j)
    # (Where the load has not reached the piece, ahead of the trace's start S*, the margin
    # is the piece's own: as a multiple of the whole distance, the step could take the
    # load past more of the short intervals recorded there than the next step's view
    # holds, which then lost it, its step length zero for good.)
    past_end = lambda end: jnp.where(
        x >= h_i, _PAST_SAMPLE * (end - x), end - x + (_PAST_SAMPLE - 1.0) * (end - h_i)
    )
    room = jnp.where(within, past_end(h_j), 0.5 * jnp.maximum(reach - x, 0.0))
    # Where the step would take the load past that piece's end, the next interval's too:
    # the load crosses a sample in the step (in a moving load's steady state, every step).
    k = jnp.minimum(j + 1, jnp.minimum(last, start + _WINDOW - 1))
    _, h_k, width_next, powers_next = piece(j, k)
    crossing = within & (k > j) & (room < travel)
    room = jnp.where(crossing, past_end(h_k), room)
    # The next step's view is found from this one's samples, so the load stays within
    # them: a margin past a piece's end could otherwise carry it over a cluster of short
    # intervals (recorded where the steps restarted short) longer than a view, which then
    # lost it, its step length zero for good.
    room = jnp.minimum(room, jnp.maximum(reach - x, 0.0))
    return Past(
        origin=h_i,
        width=width,
        powers=powers,
        crossing=crossing,
        joint=h_j,
        width_next=width_next,
        powers_next=powers_next,
        room=room,
        hinge=hinge,
        start=start,
    )


def slope_memory(past: Past, x, s_star):
    """(Psi(x), Psi'(x)): Phi when the right hinge passed x, from the step's piece of the
    recorded trace (`read_past`); zero ahead of the initial hinge, x < S*."""
    psi, dpsi = polynomial(past.powers, past.width, (x - past.origin) / past.width, 1)
    psi_next, dpsi_next = polynomial(
        past.powers_next, past.width_next, (x - past.joint) / past.width_next, 1
    )
    on_next = past.crossing & (x >= past.joint)
    psi, dpsi = jnp.where(on_next, psi_next, psi), jnp.where(on_next, dpsi_next, dpsi)
    ahead = x < s_star
    return jnp.where(ahead, 0.0, psi), jnp.where(ahead, 0.0, dpsi)
