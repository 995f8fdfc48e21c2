"""The design optimiser and brute forces on a `Formulation` with a closed-form optimum."""

import equinox as eqx
import jax
import jax.numpy as jnp
import pytest

jax.config.update("jax_enable_x64", True)

from barrierjax.design import (
    Formulation,
    default_starts,
    grid_along_boundary,
    grid_minimise,
    minimise,
    to_boundary,
)


class _Box(eqx.Module):
    lower: jax.Array
    upper: jax.Array


def _measure(problem, u):
    """f = (u0 - 0.7)^2 + u1 falls towards small u1, where g = 0.4 + 0.2 u0^2 - u1 <= 0
    stops it: on the boundary f = (u0 - 0.7)^2 + 0.4 + 0.2 u0^2, least at u0 = 7/12."""
    return (u[0] - 0.7) ** 2 + u[1], jnp.stack([0.4 + 0.2 * u[0] ** 2 - u[1]])


def _unit(problem, u):
    return u


U0 = 7.0 / 12.0
F_BEST = (U0 - 0.7) ** 2 + 0.4 + 0.2 * U0**2


@pytest.fixture(scope="module")
def form():
    box = _Box(jnp.zeros(2), jnp.ones(2))
    return Formulation(box, jnp.asarray(1.0), measure=_measure, design=_unit, stiffening=1)


def test_to_boundary_lands_on_the_constraint(form):
    u, f, c = to_boundary(form, jnp.array([0.5, 0.9]))  # feasible with slack: moved down
    assert float(u[1]) == pytest.approx(0.4 + 0.2 * 0.25, abs=1e-12)
    assert -1e-12 <= float(c) <= 0.0 and float(f) == pytest.approx(0.04 + 0.45, abs=1e-12)


def _curved(problem, u):
    """Along u1 the constraint is steep and curved, exp(8 (0.3 - u1)) - 1, zero at 0.3;
    at u0 = 1 a second term, 0.3 - u1, crosses it there: the larger has a kink at the
    root, slopes -8 and -1 (at u0 = 0 the second term is -1, never the larger)."""
    steep = jnp.expm1(8.0 * (0.3 - u[1]))
    return u[1], jnp.stack([steep, u[0] * (0.3 - u[1]) - (1.0 - u[0])])


@pytest.mark.parametrize("u0", [0.0, 1.0])  # one smooth term; two with a kink at the root
@pytest.mark.parametrize("start", [0.95, 0.01])  # feasible with slack; infeasible
def test_to_boundary_lands_on_a_curved_or_kinked_constraint_to_rounding(u0, start):
    box = _Box(jnp.zeros(2), jnp.ones(2))
    curved = Formulation(box, jnp.asarray(1.0), measure=_curved, design=_unit, stiffening=1)
    u, f, c = to_boundary(curved, jnp.array([u0, start]))
    assert float(u[1]) == pytest.approx(0.3, abs=1e-13)
    assert -1e-12 <= float(c) <= 0.0 and float(f) == pytest.approx(0.3, abs=1e-13)


def test_minimise_finds_the_closed_form_optimum(form):
    solution = minimise(form, default_starts(2))
    k = int(solution.best)
    assert bool(solution.feasible[k])
    assert float(solution.x[k, 0]) == pytest.approx(U0, abs=1e-4)
    assert float(solution.objective[k]) == pytest.approx(F_BEST, rel=1e-7)


def test_brute_forces_find_it_too(form):
    along = grid_along_boundary(form, 41)
    assert float(along.objective) == pytest.approx(F_BEST, rel=1e-7)
    assert float(along.constraint) <= 0.0
    plain = grid_minimise(form, 41)
    assert float(plain.objective) >= F_BEST - 1e-12
    assert float(plain.objective) == pytest.approx(F_BEST, rel=1e-3)
