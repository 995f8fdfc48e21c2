"""Solving many scenarios: in vmapped chunks, at padded batch sizes, and in parts that run
side by side on the CPU's cores."""

import functools
import math
import os
from concurrent.futures import ThreadPoolExecutor

import jax
import jax.numpy as jnp
import numpy as np


def sorted_chunks(solve, inputs: tuple, key, batch_size: int):
    """`solve` mapped over the leading axis of `inputs`, in vmapped chunks of at most
    `batch_size` taken in the order of `key`, and returned in the inputs' order.

    A vmapped adaptive solve steps until its slowest member is done: sorting by a
    predictor of the step count puts scenarios of similar cost in the same chunk. The
    chunks are of one size (the last padded with copies of the slowest scenario, which
    add lanes but no steps to its chunk): a remainder chunk of another size would be a
    second copy of the solve to compile (the first call on 5,000 normal impacts, padded to
    5,120 and solved in chunks of 2,048: 5.6 s, against 3.7 s in three chunks of 1,707)."""
    n = inputs[0].shape[0]
    chunks = max(1, -(-n // batch_size))
    size = -(-n // chunks)
    order = jnp.argsort(key)
    copies = chunks * size - n
    sorted_inputs = tuple(jnp.pad(a[order], (0, copies), "edge") for a in inputs)
    solved = jax.lax.map(lambda x: solve(*x), sorted_inputs, batch_size=size)
    unsort = jnp.argsort(order)
    return jax.tree.map(lambda leaf: leaf[unsort], solved)


def solved_again(solve, args: tuple, first, larger, again):
    """`solve(args, first)`, a (result, status) pair over the scenarios of `args` (inputs
    of one shape); where a concrete status flags scenarios to solve again (`again(status)`:
    a boolean per scenario), those scenarios solved again, alone, by `solve(their args,
    attempt)` with `attempt = larger(the attempt before, their args, their status)` (flat),
    until none is flagged or `larger` gives None. The other scenarios keep the results of
    the solve before: one slow scenario no longer costs every scenario of its batch a
    second solve. One scenario alone is solved as a scalar (the scalar solve's program
    compiles in a fraction of a batch's time); more are padded with copies of their last to
    at least `_SMALLEST_AGAIN` rows, so that the few each chunk of a sweep flags share one
    program an attempt. Returns (result, status, the last attempt); a traced status (under
    a caller's `jit`, `vmap` or `grad`) ends it after the first solve."""
    result, status = solve(args, first)
    shape, attempt = args[0].shape, first
    rows = np.arange(math.prod(shape))
    part_args, part_status = args, status
    while not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree.leaves(part_status)):
        flagged = np.flatnonzero(np.asarray(again(part_status)))
        if flagged.size == 0:
            break
        part_shape = part_args[0].shape
        part_args = tuple(jnp.ravel(a)[flagged] for a in part_args)
        bigger = larger(attempt, part_args, _flat_rows(part_status, part_shape, flagged))
        if bigger is None:
            break
        attempt = bigger
        rows = rows[flagged]
        if rows.size == 1:
            part = solve(tuple(a[0] for a in part_args), attempt)
            part = part if not shape else jax.tree.map(lambda leaf: leaf[None], part)
        else:
            part = solve(_at_least(part_args, _SMALLEST_AGAIN), attempt)
            part = jax.tree.map(lambda leaf: leaf[: rows.size], part)
        put = lambda whole, new: _rows_replaced(whole, shape, rows, new)
        result, status = part if not shape else jax.tree.map(put, (result, status), part)
        part_status = part[1]
    return result, status, attempt


# The fewest rows a batch solved again has: 2 to 16 flagged scenarios are one program (a
# model's batch pads them to a power of two, a program each), for lanes that cost little
# beside a loop's own work at that width.
_SMALLEST_AGAIN = 16


def _at_least(args: tuple, rows: int) -> tuple:
    """`args` (one leading axis of scenarios) padded to `rows` with copies of their last."""
    return _padded(args, max(rows, args[0].shape[0]))[:-1]


def _scenarios_flat(leaf, shape):
    """`leaf`, whose leading axes are the scenarios' `shape`, with those axes as one."""
    return leaf.reshape((math.prod(shape), *leaf.shape[len(shape) :]))


def _flat_rows(tree, shape, rows):
    """Each leaf of `tree` (leading axes: the scenarios' `shape`) at the flat indices
    `rows`."""
    return jax.tree.map(lambda leaf: _scenarios_flat(leaf, shape)[rows], tree)


def _rows_replaced(whole, shape, rows, part):
    """`whole`, whose leading axes are the scenarios' `shape`, with the scenarios at the
    flat indices `rows` replaced by `part`'s (leading axis: those scenarios)."""
    return _scenarios_flat(whole, shape).at[rows].set(part).reshape(whole.shape)


# The quantum of the models' padded sizes: above it, a batch grows to whole multiples of it,
# at most 255 copies; below, to a power of two (at most twice the work, on small batches).
PADDING_QUANTUM = 256


def padded_size(n: int, quantum: int) -> int:
    """The batch size at which `n` scenarios are solved: the next power of two up to
    `quantum`, then the next multiple of `quantum`. Sweeps of nearby sizes then run one
    compiled program (a new size is a new compilation, seconds to minutes), for at most
    twice the work on a batch just above a power of two, and less than `quantum` scenarios
    more above it."""
    if n <= quantum:
        return 1 << max(n - 1, 0).bit_length()
    return -(-n // quantum) * quantum


def solve_padded(solve, inputs: tuple, quantum: int):
    """`solve(*inputs)` for inputs of one shape, each element a scenario: run on the
    inputs flattened and padded with copies of their last scenario to
    `padded_size(n, quantum)` of them, and returned for the n real ones, in the inputs'
    shape (each leaf's leading axes). `solve` is called with the padded inputs and the
    number n of real ones, as an array (a new n is then no new program), for a solve that
    can skip the copies.

    On a CPU, concrete inputs of at least `_PART_SIZE` scenarios a core are solved in
    equal parts, as many as the process may use cores (`most_parts()` at most), each called
    from a thread of its own: within one program a second core gains XLA's runtime little
    on a step loop, and the parts' programs (one program: the parts are padded alike) run
    side by side. Traced inputs (under a caller's `jit`, `vmap` or `grad`) are solved
    whole. The threads trace with the caller's `jax_enable_x64`, not its other
    thread-local settings."""
    shape = inputs[0].shape
    n = math.prod(shape)
    flat = tuple(a.ravel() for a in inputs)
    parts = _parts(n, flat)
    if parts == 1:
        size = padded_size(n, quantum)
        return _joined([solve(*_padded(flat, size))], (n,), shape, size)
    part = -(-n // parts)
    size = padded_size(part, quantum)
    starts = range(0, n, part)
    solved = _side_by_side(
        solve, [_padded(tuple(a[k : k + part] for a in flat), size) for k in starts]
    )
    return _joined(solved, tuple(min(part, n - k) for k in starts), shape, size)


def rows_in_parts(solve, rows, *, part_size: int | None = None):
    """`solve(rows)` (rows: an array whose leading axis holds the scenarios; `solve`: a
    function of such an array, jitted, whose results hold one row per scenario or one value
    for all) in equal parts of at least `part_size` rows side by side, as `solve_padded`
    runs a model's (None: its rule, `_PART_SIZE`); the parts are padded with copies of the
    last row to one shape, so that they run one program. A result whose leading axis is as
    long as a part is taken for rows, any other for one value for all."""
    n = rows.shape[0]
    parts = _parts(n, (rows,), part_size or _PART_SIZE)
    if parts == 1:
        return solve(rows)
    part = -(-n // parts)
    starts = range(0, n, part)
    padded = [_padded((rows[k : k + part],), part)[:1] for k in starts]
    solved = _side_by_side(solve, padded)
    return _joined(solved, tuple(min(part, n - k) for k in starts), (n,), part)


def _side_by_side(solve, arguments: list) -> list:
    """`solve(*a)` for each `a` of `arguments`, each called from a thread of its own and
    waited for there, with the caller's `jax_enable_x64`.

    JAX's CPU client runs the programs that one thread dispatches one after another. Not
    waited for, a part's call returned as soon as it was dispatched, the pool handed the
    next part to the same thread, and the two parts ran in turn: a third of the calls of
    the normal ODE's and the oblique model's 10^4 scenarios on 2 cores took twice as long
    (benchmarks/README.md, "Batches in parts")."""
    # The arguments are made before any part runs: made in a part's thread, they could wait
    # behind another part's run.
    arguments = jax.block_until_ready(arguments)
    x64 = jax.config.jax_enable_x64

    def run(arguments):
        with jax.enable_x64(x64):
            return jax.block_until_ready(solve(*arguments))

    return [future.result() for future in [_pool().submit(run, a) for a in arguments]]


def _padded(inputs: tuple, size: int) -> tuple:
    """`inputs` padded to `size` rows with copies of their last, and their count."""
    n = inputs[0].shape[0]
    copies = size - n if n else 0
    rows = lambda a: [(0, copies)] + [(0, 0)] * (a.ndim - 1)
    padded = tuple(jnp.pad(a, rows(a), "edge") if copies else a for a in inputs)
    return (*padded, jnp.asarray(n, jnp.int32))


# Scenarios a part holds at least, and the most parts (`BARRIERJAX_PARTS` sets it). Whole
# against two parts on 2 cores, oblique_impact.py's box at rtol 1e-6, the median of 6 calls
# after the first (2026-11-30, once each part was waited for in its own thread): 1,024
# scenarios, the normal ODE 7.2-7.6 -> 4.8-4.9 us a scenario, the axial model 268 -> 140,
# the oblique model 41-42 -> 31-33; 1,536: 6.0-6.4 -> 4.0-5.7, 265 -> 132, 38-39 -> 31-32;
# with parts of 256 to 384 the normal ODE no longer gained. (Before, with a third of the
# calls running their parts in turn, 1,024 in parts of 512 had not paid for the oblique
# model, and the least part was 1,024.)
_PART_SIZE, _PARTS = 512, 8


def _parts(n: int, inputs: tuple, part_size: int = _PART_SIZE) -> int:
    """How many parts of at least `part_size` to solve `n` scenarios in: one where the
    inputs are traced or the backend is not a CPU (an accelerator runs the whole batch at
    once)."""
    if jax.default_backend() != "cpu" or any(isinstance(a, jax.core.Tracer) for a in inputs):
        return 1
    return max(1, min(usable_cores(), most_parts(), n // part_size))


def usable_cores() -> int:
    """The cores this process may run on (its affinity, where the system tells it)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return cores or 1


def most_parts() -> int:
    """The most parts a batch is solved in: `BARRIERJAX_PARTS` where set (1: every batch
    whole, for a process that shares its cores with others), else `_PARTS`."""
    chosen = os.environ.get("BARRIERJAX_PARTS", "").strip()
    if not chosen:
        return _PARTS
    if not chosen.isdigit() or int(chosen) < 1:
        raise ValueError(f"BARRIERJAX_PARTS must be a whole number >= 1; got {chosen!r}")
    return int(chosen)


@functools.cache
def _pool() -> ThreadPoolExecutor:
    # (Threads that wait on nothing cost nothing: one per part, of as many as any call asks.)
    return ThreadPoolExecutor(64, thread_name_prefix="barrierjax-part")


@functools.partial(jax.jit, static_argnums=(1, 2, 3))
def _joined(trees: list, counts: tuple, shape: tuple, rows: int):
    """The real rows of each part (the first `counts` of each leaf whose leading axis is
    the parts' `rows`), one part after another, in `shape`; any other leaf is one value
    for all, the first part's. One program for the whole result."""

    def join(*leaves):
        if leaves[0].ndim == 0 or leaves[0].shape[0] != rows:
            return leaves[0]
        joined = jnp.concatenate([leaf[:count] for leaf, count in zip(leaves, counts)])
        return joined.reshape(shape + joined.shape[1:])

    return jax.tree.map(join, *trees)
