"""`sharded_batch`: a batched function compiled with its rows sharded across every device
of every process (`jax.sharding`, and the processes of `jax.distributed`), as the sweeps
(`barrierjax.sweep`, `barrierjax.system.sweep`) solve their chunks."""

from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from ._solve.batching import rows_in_parts


def sharded_batch(
    fn: Callable, *, part_size: int | None = None, compiler_options: dict | None = None
) -> Callable:
    """`fn` (rows -> a pytree of arrays, one value per row or one for all) compiled with
    its rows sharded across every device of every process (`jax.sharding`; the processes
    of `jax.distributed.initialize`, each holding every row and computing its devices'
    share); returns a function of a NumPy array of rows, to NumPy arrays (the whole batch,
    gathered to every process). One device: a plain jit, on a CPU run in parts of at least
    `part_size` rows (None: the models' rule) side by side, one a core
    (`_solve.batching.rows_in_parts`). The row count must be a multiple of the device
    count. `compiler_options`: `jax.jit`'s, for XLA."""
    devices = jax.devices()
    if len(devices) == 1:
        compiled = jax.jit(fn, compiler_options=compiler_options)
        return lambda values: jax.tree.map(
            np.asarray, rows_in_parts(compiled, jnp.asarray(values), part_size=part_size)
        )
    rows = NamedSharding(Mesh(np.array(devices), ("rows",)), PartitionSpec("rows"))
    compiled = jax.jit(fn, in_shardings=rows, compiler_options=compiler_options)

    def solve(values):
        array = jax.make_array_from_callback(values.shape, rows, lambda index: values[index])
        out = compiled(array)
        if jax.process_count() == 1:
            return jax.tree.map(np.asarray, out)
        from jax.experimental import multihost_utils

        return multihost_utils.process_allgather(out, tiled=True)

    return solve
