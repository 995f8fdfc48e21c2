"""barrierjax._solve.recorded_rk: locating a stage's end within a step."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.recorded_rk import _A, _dip, _locate, _stored, _tied


def _located_time(a, b, h):
    """Where z = a - b t, on a step of length h from t = 0 (state (t, z), field (1, -b)),
    falls to zero: a / b."""
    zero = jnp.zeros_like(b)
    start = ((zero, a), (zero + 1.0, -b), (zero, zero))
    end = ((zero + h, a - b * h), (zero + 1.0, -b), (zero, zero))
    event = lambda y, f: jnp.stack([y[1]])
    (t, _), _, _ = _locate(event, start, end, jnp.stack([a]), jnp.stack([a - b * h]), h)
    return t


@pytest.mark.parametrize("h", [2.0, 1.5, 1.0 + 1e-9])
def test_a_linear_event_is_located_with_the_implicit_function_derivative(h):
    # The secant from the step's ends lands on the zero of a linear term. The safeguarded
    # Newton iterations once took an open bracket, rejected a step onto its end (the zero
    # itself) and bisected away from it; the last correction put the zero back, but its
    # derivative, taken off the zero, was wrong (dt/db 6 % off at h = 2; in oblique_impact,
    # t_star's derivative 0.7 % off where friction stops the slide while crushing).
    a, b = 1.0, 1.0
    t, dt_db = jax.jvp(lambda b: _located_time(a, b, h), (jnp.asarray(b),), (jnp.asarray(1.0),))
    assert float(t) == pytest.approx(a / b, rel=1e-14)
    assert float(dt_db) == pytest.approx(-a / b**2, rel=1e-12)


def test_the_start_carries_tangents_from_the_inputs_and_its_values_unchanged():
    """`_tied`, which gives the step loop's first carry the inputs' tangents (so that the
    loop's JVP traces its body once): values kept, infinite inputs included, integers
    untouched; the tangent of a tied constant is a function of the input's, where an
    untied constant's is the literal zero."""
    tree = (jnp.asarray(2.5), jnp.asarray(3, jnp.int32), jnp.asarray(jnp.inf), jnp.ones(2))
    out = _tied(tree, (jnp.asarray(jnp.inf), jnp.asarray(1.0)))
    for before, after in zip(tree, out):
        assert after.dtype == before.dtype
        np.testing.assert_array_equal(np.asarray(after), np.asarray(before))

    def linear_part(f):
        return jax.make_jaxpr(jax.linearize(f, 1.0)[1])(1.0).jaxpr

    assert linear_part(lambda x: _tied((jnp.zeros(()),), (x,))[0]).eqns
    assert not linear_part(lambda x: jnp.zeros(())).eqns


@pytest.mark.parametrize("h", [0.0, 3e-7, 2.5, np.inf])
def test_stored_values_and_tangents_are_unchanged(h):
    """`_stored`, the division by a one that XLA cannot see through: every value to the
    bit (signed zeros and infinities included) and the tangents too. (Not subnormals: XLA's
    CPU kernels flush them to zero, in this division as in any other arithmetic.)"""
    values = jnp.asarray([0.0, -0.0, 2.3e-308, -1.7e308, 1.0 / 3.0, np.inf, -np.inf])
    stored = _stored((values, {"x": values[4]}), jnp.asarray(h))
    np.testing.assert_array_equal(np.asarray(stored[0]), np.asarray(values))
    assert np.signbit(np.asarray(stored[0])).tolist() == np.signbit(np.asarray(values)).tolist()
    assert float(stored[1]["x"]) == float(values[4])
    direction = jnp.arange(7.0) / 3.0
    _, tangent = jax.jvp(lambda v: _stored(v, jnp.asarray(h)), (values,), (direction,))
    np.testing.assert_array_equal(np.asarray(tangent), np.asarray(direction))


def test_the_stages_are_diffrax_dopri5s():
    # Written out in the module (so that importing barrierjax does not import diffrax); the
    # same doubles as diffrax's tableau, the last row its fifth-order solution.
    import diffrax

    tableau = diffrax.Dopri5.tableau
    assert _A[1:] == [[float(w) for w in row] for row in tableau.a_lower]
    assert _A[-1] == [float(w) for w in tableau.b_sol[:-1]] and tableau.b_sol[-1] == 0.0


def test_a_term_that_dips_below_zero_within_a_step_is_found():
    """`_dip`: a term positive at both ends of a step that falls below zero and back within
    it (a step that straddles both its zeros, where the ends alone see no crossing): the
    fraction of the step at its deepest point, from the cubic through the ends' values and
    slopes (here exact: the term is a parabola)."""
    term = lambda depth, centre: ((0.0 - centre) ** 2 - depth, (1.0 - centre) ** 2 - depth)
    slopes = lambda centre: (-2.0 * centre, 2.0 * (1.0 - centre))
    ends = lambda depth, centre: [jnp.asarray([v]) for v in term(depth, centre)]
    for centre in (0.3, 0.5, 0.8):
        e0, e1 = ends(0.01, centre)
        d0, d1 = (jnp.asarray([v]) for v in slopes(centre))
        u, dipped = _dip(e0, e1, d0, d1)
        assert bool(dipped) and float(u) == pytest.approx(centre, rel=1e-12)
        # Above zero throughout: no dip, whatever the turning point.
        e0, e1 = ends(-0.01, centre)
        assert not bool(_dip(e0, e1, d0, d1)[1])
    # Falling throughout (no turning point), or an inactive term (+inf): no dip; of two
    # dipping terms, the first to reach its deepest point.
    inf = jnp.inf
    e0, e1, d0, d1 = (jnp.asarray(v) for v in ([0.5, inf, 0.24, 0.08], [0.1, inf, 0.24, 0.48],
                                                [-0.4, 0.0, -1.0, -0.6], [-0.4, 0.0, 1.0, 1.4]))
    u, dipped = _dip(e0, e1, d0, d1)
    assert bool(dipped) and float(u) == pytest.approx(0.3, rel=1e-12)
