"""barrierjax._solve.batching: the padded batch sizes that let sweeps of nearby sizes share
one compiled program."""

import jax
import jax.numpy as jnp
import numpy as np

from barrierjax._solve.batching import padded_size, solve_padded


def test_padded_sizes_are_powers_of_two_then_multiples_of_the_quantum():
    sizes = [padded_size(n, 1024) for n in range(1, 5000)]
    expected = {1: 1, 2: 2, 3: 4, 5: 8, 100: 128, 1000: 1024, 1024: 1024, 1025: 2048}
    assert {n: padded_size(n, 1024) for n in expected} == expected
    assert padded_size(10_000, 1024) == 10_240
    n = np.arange(1, 5000)
    assert np.all(np.asarray(sizes) >= n) and np.all(np.diff(sizes) >= 0)
    assert np.all(np.asarray(sizes) < np.maximum(2 * n, n + 1024))
    assert len(set(sizes)) == 11 + 4  # 1 .. 1024, then 2048 .. 5120


def test_the_padded_solve_returns_the_real_rows_and_their_derivatives():
    calls = []

    def solve(x, y, count):
        calls.append((x.shape, int(count)))
        return {"sum": x + y, "rows": jnp.stack([x, 2 * y], axis=-1)}

    x, y = jnp.arange(5.0), jnp.arange(5.0) ** 2
    out = solve_padded(solve, (x, y), 1024)
    assert calls == [((8,), 5)]
    np.testing.assert_array_equal(out["sum"], x + y)
    assert out["rows"].shape == (5, 2)
    grad = jax.grad(lambda x: jnp.sum(solve_padded(solve, (x, y), 1024)["sum"] ** 2))(x)
    np.testing.assert_allclose(grad, 2 * (x + y), rtol=1e-15)
    # Inputs of any one shape: solved flat, returned in that shape.
    grid = solve_padded(solve, (x[:4].reshape(2, 2), y[:4].reshape(2, 2)), 1024)
    assert calls[-1] == ((4,), 4) and grid["rows"].shape == (2, 2, 2)
    np.testing.assert_array_equal(grid["sum"], (x[:4] + y[:4]).reshape(2, 2))
