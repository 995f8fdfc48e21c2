"""barrierjax._solve.sensitivity: forward Jacobians behind a custom JVP, and with
`arrays_from` a `vmap` that hands the solve its problems as arrays."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.sensitivity import forward_jacobian_jvp


def _recorded(arrays_from=1):
    """A solve of independent problems (elementwise in a and b; k fixed), the wrapped
    function, and the shapes the solve ran with (tracing apart: `custom_vmap` traces it on
    scalars too)."""
    shapes = []

    def solve(a, b, k):
        jax.debug.callback(lambda x: shapes.append(np.shape(x)), a)
        return {"y": a**2 * b + k, "steps": jnp.zeros(jnp.shape(a), jnp.int32)}

    return forward_jacobian_jvp(solve, n_differentiable=2, arrays_from=arrays_from), shapes


A = jnp.linspace(0.5, 2.0, 6)
B = jnp.linspace(3.0, 1.0, 6)


def test_a_vmap_of_the_gradient_solves_the_arrays_and_equals_the_closed_form():
    wrapped, shapes = _recorded()
    grad = jax.grad(lambda a, b: wrapped(a, b, 3.0)["y"], argnums=(0, 1))
    da, db = jax.vmap(grad)(A, B)
    np.testing.assert_allclose(da, 2 * A * B, rtol=1e-14)
    np.testing.assert_allclose(db, A**2, rtol=1e-14)
    # The six problems, each direction a copy of them: never one problem at a time.
    assert shapes and all(shape == (12,) for shape in shapes)


def test_a_vmap_of_the_solve_solves_the_arrays():
    wrapped, shapes = _recorded()
    y = jax.vmap(lambda a, b: wrapped(a, b, 3.0)["y"])(A, B)
    np.testing.assert_allclose(y, A**2 * B + 3.0, rtol=1e-14)
    assert shapes == [(6,)]


def test_nested_vmaps_and_an_unmapped_argument_are_flattened_into_one_axis():
    wrapped, shapes = _recorded()
    a, b = A.reshape(2, 3), B[:3]
    grad = jax.grad(lambda a, b: wrapped(a, b, 3.0)["y"], argnums=(0, 1))
    da, db = jax.vmap(jax.vmap(grad, in_axes=(0, 0)), in_axes=(0, None))(a, b)
    np.testing.assert_allclose(da, 2 * a * b, rtol=1e-14)
    np.testing.assert_allclose(db, a**2, rtol=1e-14)
    assert all(shape == (12,) for shape in shapes)


def test_a_vmap_of_fewer_problems_than_arrays_from_batches_the_solve_as_jax_does():
    wrapped, shapes = _recorded(arrays_from=7)
    y = jax.vmap(lambda a, b: wrapped(a, b, 3.0)["y"])(A, B)
    np.testing.assert_allclose(y, A**2 * B + 3.0, rtol=1e-14)
    assert shapes == [()] * 6


def test_a_vmap_over_a_fixed_argument_batches_the_solve_as_jax_does():
    wrapped, shapes = _recorded()
    k = jnp.arange(6.0)
    grad = jax.grad(lambda a, k: wrapped(a, 2.0, k)["y"])
    np.testing.assert_allclose(jax.vmap(grad)(A, k), 4 * A, rtol=1e-14)
    assert all(shape == () for shape in shapes)


@pytest.mark.parametrize("arrays_from", [None, 1])
def test_a_scalar_jacobian_is_unchanged(arrays_from):
    wrapped, _ = _recorded(arrays_from)
    jacobian = jax.jacfwd(lambda x: wrapped(x[0], x[1], 3.0)["y"])(jnp.array([1.5, 2.0]))
    np.testing.assert_allclose(jacobian, [6.0, 2.25], rtol=1e-14)
