"""Many adaptive solves of different lengths, side by side in the lanes of one `vmap`,
each lane taking the next problem of a queue as soon as its own is done.

A vmapped adaptive solve steps until its slowest member is done: in chunks, every member
pays for the chunk's slowest. Here a finished lane waits only until `refill` lanes have
finished (so that finishing and restarting, a pass of their own, run for several lanes at
once), and then takes a new problem; only the queue's last lanes wait for the slowest.
"""

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp


def solve_queued(
    start: Callable,
    step: Callable,
    running: Callable,
    finish: Callable,
    inputs,
    *,
    buffers: Callable,
    seed_rows: int,
    lanes: int,
    refill: int,
    count=None,
    order=None,
):
    """`finish(c, lane)` for each problem `x` along the leading axis of `inputs`, where `c`
    is `start(x)` stepped by `step` while `running(c)` in lane `lane`.

    `buffers(c)` are the leaves of the state that a step writes in place (arrays whose
    leading axis is a capacity): `step` may write them even for a state that is not
    running (the driver keeps the state's other leaves), and `start` fills only their
    first `seed_rows` rows (the rest are never read before a step writes them), so that a
    refill copies no more. `lanes` problems run at once; finished lanes are finished and
    refilled `refill` at a time, or all together once none is running. `finish` sees the
    buffers of every lane (leading axis: the lanes), so that it reads its lane's rows where
    they lie rather than a copy of its whole buffers.

    `count` (traced; default: all of them) is how many of the problems are real: the rest
    pad the inputs to a size whose program is already compiled, and are never started
    (their results are zeros).

    `order` (traced; default: as given) is the order in which the problems are started, a
    permutation of their indices with the first `count` real ones first. The last lanes
    to finish keep the loop going for all: started first, the longest problems no longer
    end the queue."""
    n = jax.tree.leaves(inputs)[0].shape[0]
    if n == 0:
        # The results' shapes, from the same solve of a single (zero) problem.
        one = jax.tree.map(lambda a: jnp.zeros((1, *a.shape[1:]), a.dtype), inputs)
        options = {"buffers": buffers, "seed_rows": seed_rows, "lanes": lanes, "refill": refill}
        shapes = jax.eval_shape(lambda: solve_queued(start, step, running, finish, one, **options))
        return jax.tree.map(lambda s: jnp.zeros((0, *s.shape[1:]), s.dtype), shapes)
    lanes = min(lanes, n)
    refill = min(refill, lanes)
    order = jnp.arange(n) if order is None else jnp.asarray(order)
    take = lambda tree, index: jax.tree.map(lambda a: a[index], tree)
    lanes_running = jax.vmap(running)
    # Where a refill has no lane or no problem, an index out of range, each its own: every
    # write of a refill is to unique indices, and says so. JAX differentiates a scatter
    # whose indices may repeat by scattering ids over the whole operand and selecting by
    # them: the seeds' write then passed over every lane's whole buffer at every step of a
    # derivative (the oblique model's batched gradient took twice as long, and longer the
    # larger its step budget).
    beyond = jnp.arange(refill)

    carry = jax.vmap(start)(take(inputs, order[:lanes]))
    owner = jnp.arange(lanes)  # the place in the queue of each lane's problem; n: none
    count = jnp.asarray(n if count is None else count).astype(owner.dtype)

    def finish_lanes(carry, lane):
        axes = eqx.tree_at(buffers, jax.tree.map(lambda _: 0, carry), replace_fn=lambda _: None)
        taken = with_buffers(take(without_buffers(carry), lane), buffers(carry))
        return jax.vmap(finish, in_axes=(axes, 0))(taken, lane)

    def without_buffers(c):
        return eqx.tree_at(buffers, c, replace_fn=lambda _: None)

    def with_buffers(stripped, b):
        # (The state may hold Nones of its own: the stripped buffers' are told apart.)
        return eqx.tree_at(buffers, stripped, b, is_leaf=lambda x: x is None)

    def advance(carry, active):
        stepped = jax.vmap(step)(carry)
        kept = jax.tree.map(
            lambda new, old: jnp.where(active.reshape((-1,) + (1,) * (new.ndim - 1)), new, old),
            without_buffers(stepped),
            without_buffers(carry),
        )
        return with_buffers(kept, buffers(stepped))

    def refilled(carry, busy, owner, queued, results):
        """Up to `refill` finished lanes finished into `results`, and the problems next in
        the queue started in their place. Their buffers are seeded by the caller, outside
        the conditional that runs this: through it, they would be copied whole."""
        finished = ~busy & (owner < count)
        lane = jnp.nonzero(finished, size=refill, fill_value=lanes)[0]
        valid = lane < lanes
        lane_in = jnp.minimum(lane, lanes - 1)
        problem = jnp.where(valid, order[jnp.minimum(owner[lane_in], n - 1)], n + beyond)
        following = queued + jnp.cumsum(valid) - 1
        fresh = jax.vmap(start)(take(inputs, order[jnp.minimum(following, n - 1)]))
        following = jnp.where(following < count, following, n)
        lane = jnp.where(valid, lane, lanes + beyond)
        put = lambda old, new, index: old.at[index].set(new, mode="drop", unique_indices=True)
        done = finish_lanes(carry, lane_in)
        return (
            jax.tree.map(
                lambda old, new: put(old, new, lane), without_buffers(carry), without_buffers(fresh)
            ),
            put(busy, lanes_running(fresh) & (following < count), lane),
            put(owner, following, lane),
            jnp.minimum(queued + jnp.sum(valid), count),
            jax.tree.map(lambda r, d: put(r, d, problem), results, done),
            lane,
            jax.tree.map(lambda b: b[:, :seed_rows], buffers(fresh)),
        )

    def unchanged(carry, busy, owner, queued, results):
        # (The seeds' shapes from the lanes' buffers, not from tracing `refilled` again.)
        zeros = jax.tree.map(
            lambda b: jnp.zeros((refill, seed_rows, *b.shape[2:]), b.dtype), buffers(carry)
        )
        return without_buffers(carry), busy, owner, queued, results, lanes + beyond, zeros

    def body(state):
        carry, busy, owner, queued, results = state
        carry = advance(carry, busy)
        busy = lanes_running(carry) & (owner < count)
        due = (jnp.sum(~busy & (owner < count)) >= refill) | ~jnp.any(busy)
        small, busy, owner, queued, results, lane, seeds = jax.lax.cond(
            due, refilled, unchanged, carry, busy, owner, queued, results
        )
        seeded = jax.tree.map(
            lambda old, new: old.at[lane, :seed_rows].set(new, mode="drop", unique_indices=True),
            buffers(carry),
            seeds,
        )
        return with_buffers(small, seeded), busy, owner, queued, results

    results = jax.tree.map(
        lambda leaf: jnp.zeros((n, *leaf.shape[1:]), leaf.dtype),
        jax.eval_shape(finish_lanes, carry, owner[:1]),
    )
    state = (carry, lanes_running(carry) & (owner < count), owner, jnp.asarray(lanes), results)
    _, _, _, _, results = jax.lax.while_loop(lambda s: jnp.any(s[2] < count), body, state)
    return results
