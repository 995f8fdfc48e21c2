"""Newton's method with the implicit function theorem's derivative (`barrierjax._solve.newton`),
on arctan(x) = theta, whose root tan(theta) and derivative 1 + tan(theta)^2 are closed forms
and from whose far side plain Newton diverges (|x0| above about 1.39)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.newton import newton


def _residual(x, theta):
    return jnp.arctan(x) - theta


def _residual_and_error(x, theta):
    """The residual, and its size against the tolerance 1e-15."""
    r = _residual(x, theta)
    return r, jnp.abs(r) / 1e-15


def _linearise(x, theta):
    return 1.0 / (1.0 + x**2), *_residual_and_error(x, theta)


def _root(theta, x0=3.0, halvings=12):
    return newton(
        _linearise,
        _residual_and_error,
        lambda J, r: r / J,
        jnp.asarray(x0),
        theta,
        iterations=40,
        halvings=halvings,
    ).root


@pytest.mark.parametrize(("theta", "x0"), [(0.5, 3.0), (-0.3, 3.0), (1.2, -3.0)])
def test_line_search_reaches_the_root_where_plain_newton_diverges(theta, x0):
    assert float(_root(jnp.asarray(theta), x0)) == pytest.approx(np.tan(theta), rel=1e-14)
    plain = float(_root(jnp.asarray(theta), x0, halvings=0))
    assert not (abs(plain - np.tan(theta)) < 1e-6)


@pytest.mark.parametrize("theta", [0.5, -0.3, 1.2])
def test_derivative_is_the_closed_form_in_both_modes(theta):
    expected = 1.0 + np.tan(theta) ** 2
    assert float(jax.grad(_root)(jnp.asarray(theta))) == pytest.approx(expected, rel=1e-12)
    assert float(jax.jacfwd(_root)(jnp.asarray(theta))) == pytest.approx(expected, rel=1e-12)
    h = 1e-6
    up, down = (float(_root(jnp.asarray(theta + sign * h))) for sign in (1.0, -1.0))
    central = (up - down) / (2 * h)
    assert central == pytest.approx(expected, rel=1e-7)


def test_vmap_equals_loop_with_members_that_halve_and_members_that_do_not():
    # From x0 = 0.5 the full steps converge; from 3 and -3 they must be halved.
    thetas = jnp.asarray([0.5, -0.3, 1.2, 0.1])
    starts = jnp.asarray([3.0, 0.5, -3.0, 0.5])
    batched = jax.vmap(_root)(thetas, starts)
    looped = [float(_root(t, s)) for t, s in zip(thetas, starts)]
    np.testing.assert_allclose(np.asarray(batched), looped, rtol=4e-15)
    grads = jax.vmap(jax.grad(_root))(thetas, starts)
    np.testing.assert_allclose(np.asarray(grads), 1.0 + np.tan(np.asarray(thetas)) ** 2, rtol=1e-12)
