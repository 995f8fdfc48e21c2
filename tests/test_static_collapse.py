"""Static collapse with axial force (report 3.4): `static_load_deflection`."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax.hinge import static_load_deflection

EXPONENTS = [1.0, 1.3, 2.0, 3.0, 7.5]
SUPPORTS = {"pinned": 1.0, "clamped": 2.0}  # hinge rotations per central hinge rotation
DELTAS = np.concatenate([np.linspace(0.0, 16.0, 161), [1e-6, 2.0 - 1e-9, 2.0 + 1e-9]])


def _golden_max(g, lo, hi, iterations=120):
    """The maximiser of a unimodal g on [lo, hi]."""
    ratio = (np.sqrt(5.0) - 1.0) / 2.0
    a, b = lo, hi
    for _ in range(iterations):
        c, d = b - ratio * (b - a), a + ratio * (b - a)
        if g(c) >= g(d):
            b = d
        else:
            a = c
    return 0.5 * (a + b)


def _virtual_work(delta, support, a):
    """Independent of the implementation: the hinges' stress point maximises the plastic
    dissipation m theta' + n (N0/M0) e' over the yield set |m| + |n|^a <= 1 (normality),
    for the extension rate the geometry imposes, e' / theta' = delta / k in units of
    M0/N0 (u = 2 delta^2/l over k central-hinge rotations of 4 delta'/l); the load then
    follows from P delta' = the dissipation, over 4 k M0 / l."""
    k = SUPPORTS[support]
    r = delta / k
    dissipation = lambda n: (1.0 - n**a) + n * r
    n = _golden_max(dissipation, 0.0, 1.0)
    return dissipation(n), n


@pytest.mark.parametrize("support", SUPPORTS)
@pytest.mark.parametrize("a", EXPONENTS)
def test_load_equals_virtual_work_with_the_flow_rule(support, a):
    result = static_load_deflection(DELTAS, support, a)
    expected = np.array([_virtual_work(d, support, a) for d in DELTAS])
    np.testing.assert_allclose(result.load, expected[:, 0], rtol=1e-12, atol=1e-12)
    # (a = 1 at delta = k: the dissipation is flat in n, the stress point indeterminate.)
    determinate = ~((a == 1.0) & (DELTAS == SUPPORTS[support]))
    # The maximiser resolves n only to about sqrt(eps / curvature) of the dissipation.
    np.testing.assert_allclose(result.axial_force[determinate], expected[determinate, 1], atol=5e-6)


@pytest.mark.parametrize("support", SUPPORTS)
@pytest.mark.parametrize("a", EXPONENTS)
def test_closed_forms_and_the_string_branch(support, a):
    k = SUPPORTS[support]
    result = static_load_deflection(DELTAS, support, a)
    beam = DELTAS < a * k
    closed = np.where(
        beam, 1.0 + (a - 1.0) * (DELTAS / (a * k)) ** (a / (a - 1.0)) if a > 1 else 1.0, DELTAS / k
    )
    np.testing.assert_allclose(result.load, closed, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(result.string, ~beam)
    np.testing.assert_allclose(result.moment[~beam], 0.0)
    np.testing.assert_allclose(result.axial_force[~beam], 1.0)
    # On the yield curve everywhere.
    np.testing.assert_allclose(result.moment + result.axial_force**a, 1.0, atol=1e-12)


def test_rectangle_reproduces_the_report():
    """(3.4.12), (3.4.15), (3.4.16) pinned and (3.4.21) clamped, delta over h/4 = M0/N0;
    the clamped load is 1 + (delta/4)^2 (the printed (3.4.22), 1 + (delta/2)^2, jumps at
    the string point: see the module docstring)."""
    d = np.linspace(0.0, 10.0, 101)
    pinned = static_load_deflection(d, "pinned", 2.0)
    np.testing.assert_allclose(pinned.axial_force, np.minimum(d / 2.0, 1.0), atol=1e-14)
    np.testing.assert_allclose(pinned.load, np.where(d <= 2.0, 1.0 + (d / 2.0) ** 2, d), 1e-14)
    clamped = static_load_deflection(d, "clamped", 2.0)
    np.testing.assert_allclose(clamped.axial_force, np.minimum(d / 4.0, 1.0), atol=1e-14)
    np.testing.assert_allclose(clamped.load, np.where(d <= 4, 1 + (d / 4) ** 2, d / 2), 1e-14)


@pytest.mark.parametrize("support", SUPPORTS)
def test_limits_of_the_exponent(support):
    k = SUPPORTS[support]
    d = np.linspace(0.0, 6.0, 61)
    square = static_load_deflection(d, support, np.inf)
    np.testing.assert_allclose(square.load, 1.0 + d / k)
    near_one = static_load_deflection(d, support, 1.0 + 1e-3)
    exact_one = static_load_deflection(d, support, 1.0)
    np.testing.assert_allclose(near_one.load, exact_one.load, atol=2e-3)


@pytest.mark.parametrize("support", SUPPORTS)
def test_slope_is_the_axial_force(support):
    """Envelope theorem: dp/d(delta) = n / k, the string's share of the load; the load is
    continuous and increasing through the switch into the string."""
    k = SUPPORTS[support]
    for a in EXPONENTS[1:]:
        load = lambda d, a=a: static_load_deflection(d, support, a).load
        slope = jax.vmap(jax.grad(load))
        d = jnp.asarray(DELTAS[1:])
        result = static_load_deflection(d, support, a)
        np.testing.assert_allclose(slope(d), result.axial_force / k, rtol=1e-9, atol=1e-12)
        switch = a * k
        below, above = static_load_deflection(
            np.array([switch - 1e-9, switch + 1e-9]), support, a
        ).load
        assert abs(above - below) < 1e-8
        assert np.all(np.diff(static_load_deflection(DELTAS[:161], support, a).load) >= 0.0)


def test_gradient_in_the_exponent_matches_finite_differences():
    for d in [0.3, 1.4, 3.9]:  # (off the switch points, where the second derivative jumps)
        f = lambda a, d=d: static_load_deflection(d, "pinned", a).load
        g = lambda a, d=d: static_load_deflection(d, "clamped", a).axial_force
        for fn in (f, g):
            for a in [1.5, 2.0, 4.0]:
                fd = (fn(a + 1e-6) - fn(a - 1e-6)) / 2e-6
                np.testing.assert_allclose(jax.grad(fn)(a), fd, rtol=1e-6, atol=1e-9)


def test_vmap_equals_loop():
    d = jnp.linspace(0.0, 5.0, 7)
    a = jnp.linspace(1.0, 4.0, 7)
    batched = jax.vmap(lambda d, a: static_load_deflection(d, "clamped", a).load)(d, a)
    looped = [float(static_load_deflection(x, "clamped", y).load) for x, y in zip(d, a)]
    np.testing.assert_allclose(batched, looped, rtol=1e-15)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"delta": -0.1}, "delta"),
        ({"delta": np.nan}, "delta"),
        ({"delta": np.inf}, "delta"),
        ({"delta": 1.0, "interaction_exponent": 0.5}, "interaction_exponent"),
        ({"delta": 1.0, "interaction_exponent": np.nan}, "interaction_exponent"),
        ({"delta": 1.0, "support": "fixed"}, "support"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        static_load_deflection(**kwargs)
