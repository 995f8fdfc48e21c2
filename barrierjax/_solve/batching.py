"""Solving many scenarios: in vmapped chunks, and at padded batch sizes."""

import functools
import math

import jax
import jax.numpy as jnp


def sorted_chunks(solve, inputs: tuple, key, batch_size: int):
    """`solve` mapped over the leading axis of `inputs`, in vmapped chunks of
    `batch_size` taken in the order of `key`, and returned in the inputs' order.

    A vmapped adaptive solve steps until its slowest member is done: sorting by a
    predictor of the step count puts scenarios of similar cost in the same chunk."""
    order = jnp.argsort(key)
    solved = jax.lax.map(
        lambda x: solve(*x), tuple(a[order] for a in inputs), batch_size=batch_size
    )
    unsort = jnp.argsort(order)
    return jax.tree.map(lambda leaf: leaf[unsort], solved)


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
    can skip the copies."""
    shape = inputs[0].shape
    n = math.prod(shape)
    copies = padded_size(n, quantum) - n if n else 0
    padded = tuple(jnp.pad(a.ravel(), (0, copies), "edge") if copies else a.ravel() for a in inputs)
    return _real_rows(solve(*padded, jnp.asarray(n, jnp.int32)), n, shape)


@functools.partial(jax.jit, static_argnums=(1, 2))
def _real_rows(tree, n: int, shape: tuple):
    """The first `n` rows of every leaf, in `shape`: one program for the whole result."""
    return jax.tree.map(lambda leaf: leaf[:n].reshape(shape + leaf.shape[1:]), tree)
