"""Solving many scenarios in vmapped chunks."""

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
