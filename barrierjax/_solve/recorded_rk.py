"""An adaptive Dormand-Prince 5(4) step loop whose vector field may read the solution's own
past, recorded in a fixed-size buffer.

diffrax vector fields see only the current state, but a state-dependent delay (the slope
under a moving load, report 3.3) needs the solution at an earlier, state-dependent time.
This loop records one sample per accepted step into a buffer carried in the loop state
and hands the vector field a view of it, taken once per step (for example the few samples
around the current state, so that the stages read no more than that). A phase ends where
a real-valued event function falls to zero: the crossing step is retaken with the length
that puts the event exactly on zero (safeguarded regula falsi on the step length, then one
Newton correction), so the phase's end carries an exact gradient. Differentiate in
forward mode (`sensitivity.forward_jacobian_jvp`): the loops are while loops.
"""

from collections.abc import Callable

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int, PyTree

# Dormand & Prince (1980), the tableau of diffrax.Dopri5; the last stage is first-same-as-last.
_C = np.array([0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0])
_A = [
    [],
    [1 / 5],
    [3 / 40, 9 / 40],
    [44 / 45, -56 / 15, 32 / 9],
    [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729],
    [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656],
    [35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84],
]
_B_ERROR = np.array(
    [
        35 / 384 - 5179 / 57600,
        0.0,
        500 / 1113 - 7571 / 16695,
        125 / 192 - 393 / 640,
        -2187 / 6784 + 92097 / 339200,
        11 / 84 - 187 / 2100,
        -1 / 40,
    ]
)


# The event's root is bracketed to this fraction of the step before the Newton correction.
_BRACKET_TOLERANCE = 1e-9


class Recording(eqx.Module):
    """Samples of the named quantities, one row of `buffer` each, of which the first
    `count` are filled. A row holds every quantity, so that appending a sample or reading
    a few consecutive ones is a single memory access: under `vmap` each is one gather or
    scatter, and those, not the arithmetic, dominate a step's cost on a CPU."""

    buffer: Float[Array, "capacity quantities"]
    count: Int[Array, ""]
    names: tuple[str, ...] = eqx.field(static=True)

    @classmethod
    def empty(cls, names: tuple[str, ...], capacity: int, dtype):
        """`capacity` rows of zeros. Readers mask the rows past `count`: the first of them
        may hold a rejected step's sample (`append`)."""
        buffer = jnp.zeros((capacity, len(names)), dtype)
        return cls(buffer, jnp.zeros((), jnp.int32), tuple(names))

    @property
    def samples(self) -> dict[str, Float[Array, " capacity"]]:
        return {name: self.buffer[:, k] for k, name in enumerate(self.names)}

    def rows(self, start, size: int, names: tuple[str, ...]) -> dict:
        """Rows `start` to `start + size` of the quantities `names`, which must be
        consecutive in `names` order: one read."""
        first = self.names.index(names[0])
        if self.names[first : first + len(names)] != tuple(names):
            raise ValueError(f"{names} are not consecutive in the recording's {self.names}")
        # (Indexing, not lax.dynamic_slice: inside a loop the buffer is equinox's `_Buffer`.)
        start = jnp.asarray(start)
        block = self.buffer[start + jnp.arange(size, dtype=start.dtype), first : first + len(names)]
        return {name: block[:, k] for k, name in enumerate(names)}

    def append(self, sample: dict, when=True):
        """Record `sample` (it must hold every quantity this recording keeps) if `when`.
        The first free row is written either way and filled only when `when`: under `vmap`
        a conditional write would read the row back first, a second memory access."""
        row = jnp.stack([jnp.asarray(sample[name], self.buffer.dtype) for name in self.names])
        buffer = self.buffer.at[self.count].set(row)
        count = jnp.minimum(self.count + jnp.where(when, 1, 0), self.buffer.shape[0] - 1)
        return Recording(buffer, count, self.names)


def _combine(y, h, weights, ks):
    return jax.tree.map(
        lambda y0, *k: y0 + h * sum(w * ki for w, ki in zip(weights, k) if w != 0.0), y, *ks
    )


def _step(field, t, y, f0, h, args, past):
    ks = [f0]
    for c, a in zip(_C[1:], _A[1:]):
        ks.append(field(t + c * h, _combine(y, h, a, ks), args, past))
    y1 = _combine(y, h, _A[6], ks[:6])
    error = _combine(jax.tree.map(jnp.zeros_like, y), h, _B_ERROR, ks)
    return y1, error, ks[6]


def _error_ratio(y0, y1, error, rtol, atol):
    scaled = jax.tree.map(
        lambda a, b, e: (e / (atol + rtol * jnp.maximum(jnp.abs(a), jnp.abs(b)))) ** 2,
        y0,
        y1,
        error,
    )
    leaves = jax.tree.leaves(scaled)
    return jnp.sqrt(sum(leaves) / len(leaves))


class PhaseEnd(eqx.Module):
    t: Float[Array, ""]
    y: PyTree[Float[Array, ""]]
    derivative: PyTree[Float[Array, ""]]
    recording: Recording
    steps: Int[Array, ""]
    complete: Bool[Array, ""]  # the event was reached within the step budget


def require_complete(end: PhaseEnd, phase: str) -> PhaseEnd:
    """`end`, with a run-time error if its phase spent the step budget before its event.

    The check is the caller's, not `solve_recorded`'s: under `vmap` a solve inside another
    loop also runs for members that loop has finished with, and their results (and
    failures) are discarded."""
    y = eqx.error_if(
        end.y,
        ~end.complete,
        f"{phase}: the step budget (max_steps) was spent before the phase ended: raise max_steps",
    )
    return eqx.tree_at(lambda e: e.y, end, y)


def solve_recorded(
    field: Callable,
    y0,
    t0,
    args,
    recording: Recording,
    *,
    record: Callable,
    event: Callable,
    rtol: float,
    atol: float,
    h0,
    max_step: Callable,
    max_steps: int,
    view: Callable = lambda t, y, args, recording, previous: recording,
    bracket_iterations: int = 64,
) -> PhaseEnd:
    """Integrate `field(t, y, args, past)` from `t0` until `event(t, y, f, args, past)`,
    positive at the start, falls to zero.

    `past = view(t, y, args, recording, previous)` is taken at the start of each step and
    serves every stage of it (by default the whole recording); `previous` is the last
    step's, or None at the start, so that a view can be found from the one before.
    `record(t, y, f, rate, args)` gives the sample appended to `recording` after each
    accepted step (and at the start and the end), with `f` the field there and `rate` its
    derivative along the solution, df/dt; `max_step(t, y, f, args, past)` bounds the step,
    for example so that the stages never read past what `past` holds. An event
    that is not positive at the start ends the phase there, after no step. A spent step
    budget is flagged (`complete`), not raised: see `require_complete`.

    The loop carries the recording as an in-place buffer (`equinox.internal.while_loop`):
    under `vmap`, lax's while loop would select every member's whole buffer at every step,
    and the cost of a step would grow with the buffer's capacity.
    """

    def rate(t, y, f, past):
        # Only the entries `record` reads survive dead-code elimination.
        return jax.jvp(lambda t, y: field(t, y, args, past), (t, y), (jnp.ones_like(t), f))[1]

    past = view(t0, y0, args, recording, None)
    f0 = field(t0, y0, args, past)
    recording = recording.append(record(t0, y0, f0, rate(t0, y0, f0, past), args))
    dtype = jnp.result_type(t0)
    ended_at_start = event(t0, y0, f0, args, past) <= 0.0

    def cond(carry):
        *_, steps, crossed = carry
        return ~crossed & (steps < max_steps)

    def body(carry):
        t, y, f, h, rec, previous, steps, _ = carry
        # Step lengths are a discretisation choice: no derivative flows through them.
        past = view(t, y, args, rec, previous)
        h = jax.lax.stop_gradient(jnp.minimum(h, max_step(t, y, f, args, past)))
        y1, error, f1 = _step(field, t, y, f, h, args, past)
        ratio = _error_ratio(y, y1, error, rtol, atol)
        # (A finite state whose field is not would carry a NaN into the next step length.)
        finite = jnp.all(jnp.stack([jnp.all(jnp.isfinite(x)) for x in jax.tree.leaves((y1, f1))]))
        accept = (ratio <= 1.0) & finite
        crossed = accept & (event(t + h, y1, f1, args, past) <= 0.0)
        advance = accept & ~crossed
        sample = record(t + h, y1, f1, rate(t + h, y1, f1, past), args)
        new_rec = rec.append(sample, when=advance)
        keep = lambda new, old: jax.tree.map(lambda a, b: jnp.where(advance, a, b), new, old)
        ratio = jax.lax.stop_gradient(ratio)
        factor = jnp.where(finite, jnp.clip(0.9 * ratio**-0.2, 0.2, 5.0), 0.2)
        h_next = jnp.where(crossed, h, h * factor)
        return (
            jnp.where(advance, t + h, t),
            keep(y1, y),
            keep(f1, f),
            h_next.astype(dtype),
            new_rec,
            past,
            steps + 1,
            crossed,
        )

    start = (
        t0,
        y0,
        f0,
        jnp.asarray(h0, dtype),
        recording,
        past,
        jnp.zeros((), jnp.int32),
        ended_at_start,
    )
    t, y, f, h, recording, previous, steps, crossed = eqxi.while_loop(
        cond, body, start, kind="lax", buffers=lambda carry: carry[4].buffer
    )

    # The crossing lies within (t, t + h]: Illinois regula falsi on the step length, on
    # the primal alone (the derivative comes from the implicit function theorem below).
    # Its accuracy need only be enough for the Newton correction that follows, whose
    # error is the square of it.
    def event_after(length, t, y, f, args, past):
        y1, _, f1 = _step(field, t, y, f, length, args, past)
        return event(t + length, y1, f1, args, past)

    past = view(t, y, args, recording, previous)
    primal = jax.lax.stop_gradient((t, y, f, args, past))
    primal_event = lambda length: event_after(length, *primal)

    def unresolved(state):
        lo, _, hi, e_hi, _, _, iteration = state
        wide = jnp.abs(hi - lo) > _BRACKET_TOLERANCE * jnp.abs(h)
        return wide & (e_hi != 0.0) & (iteration < bracket_iterations)

    def illinois(state):
        lo, e_lo, hi, e_hi, width_before, width_two_before, iteration = state
        moved = e_hi != e_lo  # converged to rounding: stay
        width = jnp.abs(hi - lo)
        secant = hi - e_hi * (hi - lo) / jnp.where(moved, e_hi - e_lo, 1.0)
        # Regula falsi crawls on a kinked event (the minimum of several): bisect where two
        # iterations failed to halve the bracket.
        mid = jnp.where(width > 0.5 * width_two_before, 0.5 * (lo + hi), secant)
        mid = jnp.where(moved, mid, hi)
        e_mid = primal_event(mid)
        same_side = (e_mid > 0.0) == (e_hi > 0.0)
        lo, e_lo = jnp.where(same_side, lo, hi), jnp.where(same_side, 0.5 * e_lo, e_hi)
        return lo, e_lo, mid, e_mid, width, width_before, iteration + 1

    h = jax.lax.stop_gradient(h)
    e_start, e_end = event(*primal), primal_event(h)
    # No bracket (the phase ended at its start, or never reached its event): no iteration,
    # where under vmap an aimless one would hold up the whole batch.
    bracketed = crossed & (e_start > 0.0) & (e_end <= 0.0)
    iteration = jnp.where(bracketed, 0, bracket_iterations)
    unknown = jnp.full_like(h, jnp.inf)
    start = (jnp.zeros_like(h), e_start, h, e_end, unknown, unknown, iteration)
    _, _, length, _, _, _, _ = jax.lax.while_loop(unresolved, illinois, start)
    # The derivative, by the implicit function theorem: one Newton correction whose slope
    # carries no derivative.
    value, slope = jax.jvp(
        lambda length: event_after(length, t, y, f, args, past),
        (length,),
        (jnp.ones_like(length),),
    )
    slope = jax.lax.stop_gradient(slope)
    length = length - value / jnp.where(slope != 0.0, slope, 1.0)
    length = jnp.where(ended_at_start, 0.0, length)
    y_end, _, f_end = _step(field, t, y, f, length, args, past)
    rate_end = rate(t + length, y_end, f_end, past)
    recording = recording.append(record(t + length, y_end, f_end, rate_end, args))
    return PhaseEnd(t + length, y_end, f_end, recording, steps, crossed)
