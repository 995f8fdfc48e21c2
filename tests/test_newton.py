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


def _counted(linearise, counter):
    """`linearise`, counting its evaluations (a callback: the loop body is traced once)."""

    def counted(x, theta):
        jax.debug.callback(lambda: counter.append(1))
        return linearise(x, theta)

    return counted


def _held_root(theta, held_slope, *, contraction, polish, counter):
    """The root from x0 = 0.5 with the slope `held_slope` held (a stale Jacobian)."""
    x0 = jnp.asarray(0.5)
    r0, error0 = _residual_and_error(x0, theta)
    return newton(
        _counted(_linearise, counter),
        _residual_and_error,
        lambda J, r: r / J,
        x0,
        theta,
        iterations=200,
        held=(jnp.asarray(held_slope), r0, error0),
        contraction=contraction,
        polish=polish,
    ).root


def test_held_jacobian_reaches_the_root_with_fewer_linearisations():
    theta = jnp.asarray(0.45)
    newton_calls, chord_calls = [], []
    exact = float(_root(theta, 0.5))
    slope = 1.0 / (1.0 + 0.5**2)  # the Jacobian at x0, held from a nearby problem
    newton_like = _held_root(theta, slope, contraction=0.0, polish=0.0, counter=newton_calls)
    chord = _held_root(theta, slope, contraction=0.5, polish=0.0, counter=chord_calls)
    assert float(newton_like) == pytest.approx(exact, rel=1e-14)
    assert float(chord) == pytest.approx(exact, rel=1e-14)
    assert len(chord_calls) < len(newton_calls)


@pytest.mark.parametrize("theta", [0.5, -0.3])
def test_derivative_takes_the_jacobian_afresh_whatever_was_held(theta):
    # A slope held three times too steep: every chord step shrinks the error by 2/3 or so,
    # and the final step too (polish 1e9 keeps it); the derivative is still exact.
    def root(theta):
        return _held_root(theta, 3.0 / (1.0 + 0.5**2), contraction=0.9, polish=1e9, counter=[])

    expected = 1.0 + np.tan(theta) ** 2
    assert float(root(jnp.asarray(theta))) == pytest.approx(np.tan(theta), rel=1e-12)
    assert float(jax.grad(root)(jnp.asarray(theta))) == pytest.approx(expected, rel=1e-12)
    assert float(jax.jacfwd(root)(jnp.asarray(theta))) == pytest.approx(expected, rel=1e-12)
