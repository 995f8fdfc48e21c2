"""An adaptive Dormand-Prince 5(4) step loop through a sequence of stages, whose vector
field may read the solution's own past, recorded in a fixed-size buffer.

diffrax vector fields see only the current state, but a state-dependent delay (the slope
under a moving load, report 3.3) needs the solution at an earlier, state-dependent time.
This loop records one sample per accepted step into a buffer carried in the loop state
and hands the vector field a view of it, taken once per step (for example the few samples
around the current state, so that the stages read no more than that).

A model runs through stages (phases, and segments of them), each with its own vector
field and a real-valued event that ends it where it falls to zero; what comes next is the
model's `transition`. All stages run in one loop, one step per iteration: under `vmap`
every member steps until the slowest is done, so one loop over all stages costs the
batch its slowest member's total, where a loop per stage would cost the sum, stage by
stage, of the slowest members' counts. For the same reason the event is located without
retaking the step: on the accepted step's quintic Hermite interpolant (from the value,
the field and its derivative along the solution at both ends, error O(step^6), below the
step's own), by safeguarded Newton iterations and then one Newton correction whose slope
carries no derivative, so that the stage's end carries the implicit function theorem's
gradient. Differentiate in forward mode (`sensitivity.forward_jacobian_jvp`): the loop is
a while loop.
"""

from collections.abc import Callable

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.flatten_util
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int, PyTree

from .hermite import Quintic, cubic_powers, polynomial

# Dormand & Prince (1980): the stages, as diffrax.Dopri5 has them (the last row is the
# fifth-order solution, first-same-as-last; tests/test_recorded_rk.py compares them), and,
# for the error, the paper's own embedded fourth-order pair, b5 - b4 with b4 = (5179/57600,
# 0, 7571/16695, 393/640, -92097/339200, 187/2100, 1/40). diffrax.Dopri5's b_error is 2/3
# of it (another embedded pair): with it the same rtol would take steps about 8 % longer.
# The vector fields are autonomous (time is a state), so the stages' nodes c are not
# needed. (Written out, not read from diffrax, so that importing the package does not
# import diffrax: see `_solve.phases`.)
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


class Recording(eqx.Module):
    """Samples of the named quantities, one row of `buffer` each, of which the first
    `count` are filled. A row holds every quantity, so that appending a sample or reading
    a few consecutive ones is a single memory access: under `vmap` each is one gather or
    scatter, and those, not the arithmetic, dominate a step's cost on a CPU."""

    buffer: Float[Array, "capacity quantities"]
    count: Int[Array, ""]
    names: tuple[str, ...] = eqx.field(static=True)
    # A recording read in place from one lane of a batch's buffer ("lanes capacity
    # quantities"), `of_lane`; None for a buffer of its own.
    lane: Int[Array, ""] | None = None

    @classmethod
    def empty(cls, names: tuple[str, ...], capacity: int, dtype):
        """`capacity` rows of zeros. Readers mask the rows past `count`: the first of them
        may hold a rejected step's sample (`append`)."""
        buffer = jnp.zeros((capacity, len(names)), dtype)
        return cls(buffer, jnp.zeros((), jnp.int32), tuple(names))

    def of_lane(self, lane):
        """This recording read from lane `lane` of `buffer`, which holds a batch's: under
        `vmap`, taking each lane's buffer would copy it whole, where the reads need a few
        rows."""
        return Recording(self.buffer, self.count, self.names, lane)

    @property
    def capacity(self) -> int:
        return self.buffer.shape[-2]

    def _read(self, rows, columns):
        if self.lane is None:
            return self.buffer[rows, columns]
        return self.buffer[self.lane, rows, columns]

    @property
    def samples(self) -> dict[str, Float[Array, " capacity"]]:
        return {name: self._read(slice(None), k) for k, name in enumerate(self.names)}

    def rows(self, start, size: int, names: tuple[str, ...]) -> dict:
        """Rows `start` to `start + size` of the quantities `names`, which must be
        consecutive in `names` order: one read."""
        first = self.names.index(names[0])
        if self.names[first : first + len(names)] != tuple(names):
            raise ValueError(f"{names} are not consecutive in the recording's {self.names}")
        # (Indexing, not lax.dynamic_slice: inside a loop the buffer is equinox's `_Buffer`.)
        start = jnp.asarray(start)
        block = self._read(
            start + jnp.arange(size, dtype=start.dtype), slice(first, first + len(names))
        )
        return {name: block[:, k] for k, name in enumerate(names)}

    def append(self, sample: dict, when=True):
        """Record `sample` (it must hold every quantity this recording keeps) if `when`.
        The first free row is written either way and filled only when `when`: under `vmap`
        a conditional write would read the row back first, a second memory access."""
        row = jnp.stack([jnp.asarray(sample[name], self.buffer.dtype) for name in self.names])
        buffer = self.buffer.at[self.count].set(row)
        count = jnp.minimum(self.count + jnp.where(when, 1, 0), self.capacity - 1)
        return Recording(buffer, count, self.names)


def _combine(y, h, weights, ks):
    return jax.tree.map(
        lambda y0, *k: y0 + h * sum(w * ki for w, ki in zip(weights, k) if w != 0.0), y, *ks
    )


def _stored(tree, h):
    """`tree` divided by one: a one computed from the step length `h`, which XLA cannot
    tell from any other number. XLA's CPU fusion copies cheap arithmetic (products, sums,
    selects) into every kernel that reads its result, and in a step written out it copied
    each stage's field into the kernels of every later stage: the oblique model's step,
    optimised, held 7,247 products, more than its jaxpr's 6,050. A division is expensive
    to XLA, so it is computed once and its result stored and read: 3,885 products, and a
    step 12-15 % faster (benchmarks/README.md). Exact: x / 1.0 is x. Used on a CPU only:
    on a GPU, where XLA fuses otherwise, its effect was not measured."""
    one = jnp.maximum(jnp.sign(jnp.abs(h)), 1.0)
    return jax.tree.map(lambda x: x / one, tree)


def _step(vector, y, f0, h, unroll, hold=lambda tree: tree):
    """One Dormand-Prince step of length `h` from `y`, where the field is `f0`: (the
    solution, its error estimate, the field there). The six stages run in a loop, which
    traces and compiles the vector field once, or with `unroll` are written out, each
    stage's point and the step's end and error passed through `hold` (`_stored`, say)."""
    if unroll:
        ks = [f0]
        for a in _A[1:]:
            ks.append(vector(hold(_combine(y, h, a, ks))))
    else:
        a = jnp.asarray([row + [0.0] * (7 - len(row)) for row in _A], jnp.result_type(h))

        def stage(i, ks):
            # (Every weight, zeros too, in the unrolled sums' order: the same roundings.)
            point = jax.tree.map(
                lambda y0, k: y0 + h * sum(a[i, j] * k[j] for j in range(7)), y, ks
            )
            return jax.tree.map(lambda k, f: k.at[i].set(f), ks, vector(point))

        ks = jax.tree.map(lambda f: jnp.zeros((7, *f.shape), f.dtype).at[0].set(f), f0)
        ks = jax.lax.fori_loop(1, 7, stage, ks)
        ks = [jax.tree.map(lambda k, j=j: k[j], ks) for j in range(7)]
    y1 = _combine(y, h, _A[6], ks[:6])
    error = _combine(jax.tree.map(jnp.zeros_like, y), h, _B_ERROR, ks)
    if unroll:
        y1, error = hold((y1, error))
    return y1, error, ks[6]


def _error_ratio(y0, y1, error, rtol, atol):
    scaled = jax.tree.map(
        lambda a, b, e: (e / (atol + rtol * jnp.maximum(jnp.abs(a), jnp.abs(b)))) ** 2,
        y0,
        y1,
        error,
    )
    leaves = jax.tree.leaves(scaled)
    return jnp.sqrt(sum(jnp.sum(x) for x in leaves) / sum(x.size for x in leaves))


def _interpolant(start, end, length):
    """The step's quintic Hermite interpolant of (y, f, f') through `start` and `end`, each
    (y, f, f'), as a function of the fraction of the step (with `derivatives=1`, (y, f)
    alone): one `Quintic` per leaf of the state, formed once."""
    ends = zip(*(jax.tree.leaves(x) for x in (*start, *end)))
    quintics = [Quintic(length, data[:3], data[3:]) for data in ends]
    structure = jax.tree.structure(start[0])

    def at(u, derivatives=2):
        values = [quintic(u, derivatives) for quintic in quintics]
        return tuple(structure.unflatten([v[k] for v in values]) for k in range(derivatives + 1))

    return at


def _locate(event, start, end, e_start, e_end, length):
    """Where the first of the terms of `event` falls to zero on the step from `start` to
    `end` (each (y, f, f')), every term being positive at the start and one not at the
    end: the interpolant there.

    Each term is smooth where the minimum of them would have kinks, so each that crosses
    is found on its own by Newton's method safeguarded by bisection (the interpolant's
    derivatives are exact), from the secant through the step's ends; then one Newton
    correction of the first, whose slope carries no derivative: the fraction's
    derivative is the implicit function theorem's. The interpolant is formed once per
    step; its evaluations are Horner's rule."""
    at = _interpolant(start, end, length)
    terms_at = lambda u: event(*at(u, derivatives=1))
    crossing = e_end <= 0.0
    # (Only the stopped fractions leave the iterations: their tangents are dead code.)
    e_start, e_end = jax.lax.stop_gradient((e_start, e_end))
    u = jnp.clip(e_start / jnp.where(crossing, e_start - e_end, 1.0), 0.0, 1.0)

    def newton(_, bracketed):
        u, lo, hi = bracketed
        e, slope = jnp.stack(
            [jnp.stack(jax.jvp(lambda v: terms_at(v)[i], (u[i],), (1.0,))) for i in range(len(u))]
        ).T
        lo, hi = jnp.where(e > 0.0, u, lo), jnp.where(e > 0.0, hi, u)
        step = u - e / jnp.where(slope != 0.0, slope, 1.0)
        # (A closed bracket: a step onto its end is the zero itself, where the secant has
        # landed on a linear term's; an open one bisected away from it, and the derivative
        # of the last correction, taken there, was off.)
        return jnp.where((step >= lo) & (step <= hi), step, 0.5 * (lo + hi)), lo, hi

    # (The bracket's ends tied to u, so that under `vmap` they are batched from the start,
    # as the iterations make them: else the loop's body is batched twice.)
    bracket = _tied((u, jnp.zeros_like(u), jnp.ones_like(u)), u)
    u, _, _ = jax.lax.fori_loop(0, _NEWTON_ITERATIONS, newton, bracket)
    u = jax.lax.stop_gradient(jnp.where(crossing, u, jnp.inf))
    first = jnp.argmin(u)
    u = jnp.min(u)
    e, slope = jax.jvp(lambda v: terms_at(v)[first], (u,), (jnp.ones_like(u),))
    slope = jax.lax.stop_gradient(slope)
    return at(jnp.clip(u - e / jnp.where(slope != 0.0, slope, 1.0), 0.0, 1.0))


def _dip(e_start, e_end, slope_start, slope_end):
    """Where a term of the event, positive at both ends of the step, dips below zero
    within it: (the fraction of the step at the earliest of such terms' deepest points,
    whether any does). Each term is taken as the cubic through its values and slopes
    (along the step's fraction) at the ends; a term falling at the start and rising at the
    end has one minimum within, where the cubic's slope, a quadratic, changes sign."""
    cubic = cubic_powers(1.0, (e_start, slope_start), (e_end, slope_end))
    _, c, b, a = cubic[:4]
    turning = (e_start > 0.0) & (e_end > 0.0) & (slope_start < 0.0) & (slope_end > 0.0)
    # The root in (0, 1) of 3a u^2 + 2b u + c (one, as the slope changes sign there), in
    # the form that does not cancel.
    root = jnp.sqrt(jnp.maximum(b**2 - 3.0 * a * c, 0.0))
    q = -(b + jnp.where(b >= 0.0, root, -root))
    safe = lambda x: jnp.where(x != 0.0, x, 1.0)
    candidates = jnp.stack([q / safe(3.0 * a), c / safe(q)])
    inside = (candidates > 0.0) & (candidates < 1.0)
    u = jnp.where(inside[0], candidates[0], candidates[1])
    u = jnp.where(turning & jnp.any(inside, axis=0), u, 1.0)
    depth, _ = polynomial(cubic, 1.0, u, derivatives=1)
    dips = turning & (depth < 0.0)
    return jnp.min(jnp.where(dips, u, 1.0)), jnp.any(dips)


# Newton iterations of `_locate`, from the secant. Three were not always enough: on one
# scenario of benchmarks/oblique_impact.py's (a) at rtol 1e-10, a vmapped run located a
# stage's end 5e-7 off in time (the bisection safeguard had taken over), and t_final came
# out 2e-7 off where the same scenario alone was 5e-10 off; with four (or six) both agree.
# Each costs about 5 % of a vmapped sweep (1e4 scenarios: 66.7 us per scenario with three,
# 76.0 with six). They run in a loop of their own: unrolled, XLA fused them into the step's
# kernels, and each added about 40 s to the compilation of a batch.
_NEWTON_ITERATIONS = 4

# A solve that is running steps or starts a stage; one that ended, by its last stage or
# stalled: a step bounded to length zero, from which the controller, growing the last
# length, never recovers.
_STEP, _START, _DONE, _STALLED = 0, 1, 2, 3


def _tied(tree, inputs):
    """`tree` with every real-valued leaf given a zero that depends on every real-valued
    leaf of `inputs`: the same values, but under `jax.jvp` each leaf has a (symbolic)
    tangent wherever an input has one. A while loop's JVP starts from the carries whose
    tangents are nonzero at its start and traces the body again each time a step turns
    another one nonzero. The oblique model's loop was traced twice, and its scalar
    gradient took 4.5 s to trace; tied, once and 3.3 s. Under `vmap` likewise each leaf
    is batched wherever an input is, and a loop's body is batched once. The zero is a
    select, not a product, so that an infinite input cannot make it NaN."""
    real = lambda x: jnp.issubdtype(jnp.result_type(x), jnp.inexact)
    zero = jnp.zeros(())
    for x in filter(real, jax.tree.leaves(inputs)):
        zero = zero + jnp.sum(jnp.where(True, 0.0, x)).astype(zero.dtype)
    return jax.tree.map(lambda x: x + zero.astype(jnp.result_type(x)) if real(x) else x, tree)


class Solution(eqx.Module):
    y: PyTree[Float[Array, ""]]
    derivative: PyTree[Float[Array, ""]]
    stage: PyTree
    recording: Recording
    args: PyTree
    complete: Bool[Array, ""]  # every stage ended within the step budget
    stalled: Bool[Array, ""]  # a step's length fell to zero (`_STALLED`)


class Carry(eqx.Module):
    """The step loop's state between iterations."""

    y: PyTree[Float[Array, ""]]
    f: PyTree[Float[Array, ""]]  # the field at y
    rate: PyTree[Float[Array, ""]]  # its derivative along the solution
    h: Float[Array, ""]  # the next step's length
    event: Float[Array, " terms"]  # the event's terms at y
    recording: Recording
    past: PyTree  # the view the last step took
    stage: PyTree
    args: PyTree
    mode: Int[Array, ""]
    iterations: Int[Array, ""]


class RecordedRK(eqx.Module):
    """The step loop: integrate the autonomous `field(y, stage, past, args)` through the
    stages that start with `stage` (`start`, then `step` while `running`, or `solve`).

    A stage lasts while every term of `event(y, f, stage, args)` (a vector, read from the
    state and the field alone so that it can be located on an interpolant) is positive;
    where the first falls to zero, `transition(y, f, stage, recording, past, args) -> (y,
    stage, rescale, done)` gives the next stage, the state it starts from and the factor
    that turns a step length in this stage's variable into one in the next's, or ends the
    solve. Each stage starts with a step of length zero, which evaluates its field; a
    stage whose event is not positive there ends after it. A term positive at both ends of
    a step may still have dipped below zero within it (the ends' values and slopes say so,
    `_dip`): the step is then taken again, shorter, to end within the dip.

    `past = view(y, f, h, stage, recording, previous)` is taken at the start of each step
    (`h` the length the step will try, unless `max_step` bounds it) and serves every stage
    of it; `previous` is the last step's, or None at the start, so that a view can be
    found from the one before. `record(y, f, rate, stage, past, args)` gives
    the sample appended to the recording after each accepted step (and at each stage's
    start and end), with `f` the field there and `rate` its derivative along the solution;
    `max_step(y, f, stage, past, args)` bounds the step, for example so that the stages
    never read past what `past` holds. `args` are the solve's constants. The budget
    `max_steps` counts every iteration; spending it is flagged (`Solution.complete`), not
    raised: the caller decides (under `vmap`, for example, which members' failures count).
    So is a stall (`Solution.stalled`): a step that `max_step` or the controller leaves
    with length zero ends the solve, where it would spend any budget in place.

    `batched` picks how a step is written (`step`): for a loop that runs under `vmap`,
    where it runs fastest, or for a single solve, where it compiles fastest.

    The parts serve drivers that run many solves side by side (`_solve.queue`).
    """

    field: Callable
    record: Callable
    event: Callable
    transition: Callable
    view: Callable
    max_step: Callable
    rtol: float
    atol: float
    max_steps: int = eqx.field(static=True)
    batched: bool = eqx.field(static=True, default=False)

    def start(self, y0, stage, recording: Recording, h0, args) -> Carry:
        """The carry at `y0`. Its real-valued leaves that a step changes carry a tangent
        from the start wherever `y0` or `args` carry one (`_tied`), so that `solve`'s JVP
        traces the step once."""
        dtype = jnp.result_type(*jax.tree.leaves(y0))
        n_events = jax.eval_shape(lambda: self.event(y0, y0, stage, args)).shape[0]
        zeros = jax.tree.map(jnp.zeros_like, y0)
        y, f, rate, h, event, stage = _tied(
            (y0, zeros, zeros, jnp.asarray(h0, dtype), jnp.ones(n_events, dtype), stage),
            (y0, args),
        )
        return Carry(
            y=y,
            f=f,
            rate=rate,
            h=h,
            event=event,
            recording=recording,
            past=self.view(y, f, h, stage, recording, None),
            stage=stage,
            args=args,
            mode=jnp.asarray(_START),
            iterations=jnp.zeros((), jnp.int32),
        )

    def solve(self, carry: Carry) -> Solution:
        """Step from `carry` to the end. The loop carries the recording as an in-place
        buffer (`equinox.internal.while_loop`): under `vmap`, lax's while loop would select
        every member's whole buffer at every step, and the cost of a step would grow with
        the buffer's capacity."""
        carry = eqxi.while_loop(
            self.running, self.step, carry, kind="lax", buffers=lambda c: c.recording.buffer
        )
        return self.solution(carry)

    def running(self, carry: Carry):
        return (carry.mode < _DONE) & (carry.iterations < self.max_steps)

    def solution(self, carry: Carry) -> Solution:
        return Solution(
            carry.y,
            carry.f,
            carry.stage,
            carry.recording,
            carry.args,
            carry.mode == _DONE,
            carry.mode == _STALLED,
        )

    def step(self, carry: Carry) -> Carry:
        """One iteration: a step (accepted or not), or a stage's zero-length start. Writes
        the recording's first free row whatever it does (`Recording.append`).

        The step's arithmetic (the stages, the error, the event's location) runs on the
        state leaf by leaf with its stages written out where `batched`: under `vmap` each
        leaf is then a contiguous array, where a flat vector would put each lane's leaves
        side by side and every operation on one leaf would read a strided column (a
        third of the speed). Otherwise it runs on the state flattened into one vector,
        with the stages in a loop: a fraction of the operations to compile (seconds
        instead of tens of seconds for a gradient)."""
        y, f, r, stage, args = carry.y, carry.f, carry.rate, carry.stage, carry.args
        past = self.view(y, f, carry.h, stage, carry.recording, carry.past)
        stepping = carry.mode == _STEP
        # Step lengths are a discretisation choice: no derivative flows through them.
        bound = self.max_step(y, f, stage, past, args)
        h_try = jax.lax.stop_gradient(jnp.minimum(carry.h, bound))
        length = jnp.where(stepping, h_try, 0.0)
        if self.batched:
            flat, state = lambda x: x, lambda x: x
        else:
            flat = lambda x: jax.flatten_util.ravel_pytree(x)[0]
            state = jax.flatten_util.ravel_pytree(y)[1]
        vector = lambda x: flat(self.field(state(x), stage, past, args))
        hold = lambda tree: tree
        if self.batched and jax.default_backend() == "cpu":
            hold = lambda tree: _stored(tree, length)
            # (Its JVP, the rate below, is stored too: the tangent is divided by the same one.)
            vector = lambda x, field=vector: hold(field(x))
        event = lambda x, fx: self.event(state(x), state(fx), stage, args)
        y, f, r = flat(y), flat(f), flat(r)
        y1, error, f1 = _step(vector, y, f, length, unroll=self.batched, hold=hold)
        # Only the entries `record` reads of the rate survive dead-code elimination.
        r1 = jax.jvp(vector, (y1,), (f1,))[1]
        e1 = event(y1, f1)
        ratio = jax.lax.stop_gradient(_error_ratio(y, y1, error, self.rtol, self.atol))
        # (A finite state whose field is not would carry a NaN into the next step length.)
        finite = jnp.all(jnp.stack([jnp.all(jnp.isfinite(x)) for x in jax.tree.leaves((y1, f1))]))
        # A term that dips below zero and back within the step ends the stage there too:
        # the step is taken again, to the dip's deepest point, where it crosses.
        slope = lambda x, fx, rx: jax.jvp(event, (x, fx), (fx, rx))[1] * length
        dip_at, dipped = jax.lax.stop_gradient(
            _dip(carry.event, e1, slope(y, f, r), slope(y1, f1, r1))
        )
        # (A start, of length zero, has slopes zero: no dip.)
        within_error = (ratio <= 1.0) & finite
        accept = within_error & ~dipped
        ended = accept & (jnp.min(e1) <= 0.0)
        # A stage ending within a step ends on the step's interpolant; one ending at its
        # start ends there.
        located = _locate(
            event, (y, f, r), (y1, f1, r1), carry.event, e1, jnp.where(stepping, length, 1.0)
        )
        reached = tuple(
            state(jax.tree.map(lambda a, b: jnp.where(ended & stepping, a, b), a, b))
            for a, b in zip(located, (y1, f1, r1))
        )
        recording = carry.recording.append(self.record(*reached, stage, past, args), when=accept)
        y_next, stage_next, rescale, done = self.transition(
            *reached[:2], stage, recording, past, args
        )
        keep = lambda new, old, when: jax.tree.map(lambda a, b: jnp.where(when, a, b), new, old)
        y_reached, f_reached, r_reached = reached
        factor = jnp.where(finite, jnp.clip(0.9 * ratio**-0.2, 0.2, 5.0), 0.2)
        factor = jnp.where(within_error & dipped, dip_at, factor)
        mode = jnp.where(
            ended, jnp.where(done, _DONE, _START), jnp.where(accept, _STEP, carry.mode)
        )
        mode = jnp.where(stepping & ~(h_try > 0.0), _STALLED, mode)
        return Carry(
            y=keep(keep(y_next, y_reached, ended), carry.y, accept),
            f=keep(f_reached, carry.f, accept),
            rate=keep(r_reached, carry.rate, accept),
            h=jnp.where(stepping, h_try * factor, carry.h) * jnp.where(ended, rescale, 1.0),
            event=jnp.where(accept, e1, carry.event),
            recording=recording,
            past=past,
            stage=keep(stage_next, stage, ended),
            args=args,
            mode=mode,
            iterations=carry.iterations + 1,
        )
