"""barrierjax.design: section properties, the sizing objective and constraint, and the
optimiser against brute force."""

import dataclasses
import json

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

from barrierjax import Impact, Scene, Vehicle, dimensionless
from barrierjax.design import (
    ImpactCases,
    SizingProblem,
    SteelTube,
    barrier,
    constraint,
    grid_search,
    objective,
    optimize_default,
    polish,
    responses,
    solve,
)

# A design where both default vehicles yield the barrier, away from the phi = 1 kink.
X_SMOOTH = jnp.array([5.5e-3, 0.11, 80e3])


@pytest.fixture(scope="module")
def problem():
    return SizingProblem()


@pytest.fixture(scope="module")
def evaluate(problem):
    """(crush, deflection) per case of one design, compiled once for the module."""
    return jax.jit(lambda v: responses(problem, v))


@pytest.fixture(scope="module")
def report():
    return optimize_default()


# --------------------------------------------------------------------------------------
# Section.


def test_section_against_hand_calculation():
    # b = 152 mm, d = 200 mm, t = 10 mm. Plastic neutral axis at mid-depth; by parts:
    # flanges 2 x (b t) x (d - t)/2 = 0.152 * 0.01 * 0.19 = 2.888e-4 m^3,
    # webs 2 x t (d - 2t)^2 / 4 = 0.01 * 0.18^2 / 2 = 1.620e-4 m^3  ->  Z = 4.508e-4 m^3.
    # A = 2 b t + 2 t (d - 2t) = 3.04e-3 + 3.6e-3 = 6.64e-3 m^2.
    # M0 = 345e6 * 4.508e-4 = 155526 N m;  m = 7850 * 6.64e-3 = 52.124 kg/m.
    tube = SteelTube()
    assert tube.width == 0.152 and tube.yield_strength == 345e6 and tube.density == 7850.0
    assert float(tube.plastic_modulus(0.01, 0.2)) == pytest.approx(4.508e-4, rel=1e-12)
    assert float(tube.area(0.01, 0.2)) == pytest.approx(6.64e-3, rel=1e-12)
    assert float(tube.plastic_moment(0.01, 0.2)) == pytest.approx(155526.0, rel=1e-12)
    assert float(tube.mass_per_length(0.01, 0.2)) == pytest.approx(52.124, rel=1e-12)
    # A solid bar (t = d/2 = b/2 would be degenerate): thin-wall limit Z ~ t d (b + d/2).
    z = float(tube.plastic_modulus(1e-5, 0.2))
    assert z == pytest.approx(1e-5 * 0.2 * (0.152 + 0.1), rel=1e-3)


def test_default_box_is_compact(problem):
    tube = problem.section
    for t in np.asarray(problem.thickness_bounds):
        for d in np.asarray(problem.depth_bounds):
            flange, web = tube.compactness(float(t), float(d))
            assert float(flange) <= 1.0 and float(web) <= 1.0
    flange, _ = tube.compactness(3.2e-3, 0.102)  # 1/8 in wall: slender flange
    assert float(flange) > 1.0


@pytest.mark.parametrize(
    "call, field",
    [
        (lambda: SteelTube().plastic_moment(-1e-3, 0.1), r"t \(wall thickness\)"),
        (lambda: SteelTube().plastic_moment(0.0, 0.1), r"t \(wall thickness\)"),
        (lambda: SteelTube().mass_per_length(0.08, 0.2), r"t \(wall thickness\)"),  # t >= b/2
        (lambda: SteelTube().plastic_moment(0.01, 0.02), r"d \(depth\)"),  # d <= 2t
        (lambda: SteelTube().area(0.01, -0.1), r"d \(depth\)"),
        (lambda: SteelTube(yield_strength=-1.0), r"SteelTube\.yield_strength"),
        (lambda: SteelTube(width=0.0), r"SteelTube\.width"),
        (lambda: SteelTube(density=float("nan")), r"SteelTube\.density"),
        (lambda: SizingProblem(deflection_limit=0.0), r"SizingProblem\.deflection_limit"),
        (lambda: SizingProblem(thickness_bounds=(0.01, 0.005)), r"SizingProblem\.thickness_bounds"),
        (lambda: SizingProblem(backing_bounds=(0.0, 1e5)), r"SizingProblem\.backing_bounds"),
        (lambda: SizingProblem(depth_bounds=(0.1, 0.2, 0.3)), r"SizingProblem\.depth_bounds"),
        (lambda: SizingProblem(thickness_bounds=(0.005, 0.08)), r"SizingProblem\.thickness_bounds"),
        (lambda: SizingProblem(depth_bounds=(0.02, 0.3)), r"SizingProblem\.depth_bounds"),
        (lambda: SizingProblem(rtol=2.0), r"SizingProblem\.rtol"),
        (lambda: ImpactCases((1100.0, -1.0), (2e5, 3e5), (10.0, 10.0)), r"ImpactCases\.mass"),
        (lambda: ImpactCases((1100.0,), (2e5, 3e5), (10.0, 10.0)), r"ImpactCases\.crush_force"),
        (lambda: ImpactCases((1100.0,), (2e5,), (0.0,)), r"ImpactCases\.speed"),
    ],
)
def test_bad_input_names_the_field(call, field):
    with pytest.raises(ValueError, match=field):
        call()


def test_traced_bad_input_fails_at_run_time():
    with pytest.raises(Exception, match=r"t \(wall thickness\)"):
        jax.block_until_ready(
            eqx.filter_jit(SteelTube().plastic_moment)(jnp.asarray(-1e-3), jnp.asarray(0.1))
        )


# --------------------------------------------------------------------------------------
# Objective and constraint.


def test_design_point_is_in_the_yielding_regime(problem):
    b = barrier(problem, X_SMOOTH)
    c = problem.cases
    for mass, force, speed in zip(c.mass, c.crush_force, c.speed):
        phi = float(dimensionless(Scene(b, Vehicle(mass, force), Impact(speed))).force_ratio)
        assert 1.05 < phi < 3.0


def _central_difference(f, x, h=1e-5):
    columns = []
    for i in range(x.shape[0]):
        step = h * x[i]
        columns.append((f(x.at[i].add(step)) - f(x.at[i].add(-step))) / (2.0 * step))
    return jnp.stack(columns, axis=-1)


@pytest.mark.parametrize("x", [X_SMOOTH, jnp.array([5.2e-3, 0.102, 98282.35])])
def test_objective_gradient_matches_finite_differences(problem, evaluate, x):
    f = lambda v: jnp.mean(evaluate(v)[0])
    grad = jax.jit(jax.grad(lambda v: objective(problem, v)))(x)
    np.testing.assert_allclose(grad, _central_difference(f, x), rtol=1e-5)
    assert np.all(np.asarray(grad) > 0.0)  # a stronger or heavier barrier: more crush


def test_deflection_jacobian_matches_finite_differences(problem, evaluate):
    # Forward mode, as the optimiser uses it.
    w = lambda v: evaluate(v)[1]
    jac = jax.jit(jax.jacfwd(lambda v: responses(problem, v)[1]))(X_SMOOTH)
    np.testing.assert_allclose(jac, _central_difference(w, X_SMOOTH), rtol=1e-5)
    assert np.all(np.asarray(jac) < 0.0)  # a stronger barrier deflects less


def test_vmap_equals_loop(problem, evaluate):
    xs = jnp.array(
        [
            [5.5e-3, 0.11, 80e3],
            [8e-3, 0.2, 20e3],
            [12e-3, 0.3, 300e3],  # rigid for both vehicles
            [5.2e-3, 0.102, 5e3],
        ]
    )
    batched_f, batched_c = jax.jit(
        jax.vmap(lambda v: (objective(problem, v), constraint(problem, v)))
    )(xs)
    for k in range(xs.shape[0]):
        damage, deflection = evaluate(xs[k])
        assert float(batched_f[k]) == pytest.approx(float(jnp.mean(damage)), rel=1e-12)
        limit = float(problem.deflection_limit)
        assert float(batched_c[k]) + limit == pytest.approx(
            float(jnp.max(deflection)), rel=1e-12, abs=1e-15
        )
    # Rigid barrier: each vehicle crushes M v^2 / (2 P0), nothing deflects.
    c = problem.cases
    rigid = float(np.mean(0.5 * np.asarray(c.mass * c.speed**2 / c.crush_force)))
    assert float(batched_f[2]) == pytest.approx(rigid, rel=1e-12)
    assert float(batched_c[2]) == pytest.approx(-float(problem.deflection_limit))


def test_polish_restores_feasibility(problem, evaluate):
    limit = float(problem.deflection_limit)
    soft = jnp.array([5.2e-3, 0.102, 20e3])  # the pickup deflects far past the limit
    assert float(jnp.max(evaluate(soft)[1])) > limit
    fixed = eqx.filter_jit(polish)(problem, soft)
    w = float(jnp.max(evaluate(fixed)[1]))
    assert limit - 1e-9 < w <= limit  # onto the boundary, from the feasible side
    np.testing.assert_allclose(fixed[:2], soft[:2], rtol=1e-12)


# --------------------------------------------------------------------------------------
# The optimum against brute force.


def test_optimum_within_one_percent_of_grid_and_feasible(report):
    assert report.feasible and report.constraint <= 0.0
    assert report.max_deflection <= report.deflection_limit
    # The deflection limit is active (the physics says so: softer is better).
    assert report.constraint > -1e-6 * report.deflection_limit
    # Not worse than the refined grid's best by more than 1 % (and the refined grid is a
    # real check: close to the gradient optimum, unlike the coarse one).
    assert report.relative_difference <= 0.01
    assert abs(report.relative_difference) < 0.01
    assert report.coarse_grid_objective >= report.grid_objective
    assert report.grid_constraint <= 0.0
    # Inside the box.
    p = SizingProblem()
    lo, hi = np.asarray(p.lower), np.asarray(p.upper)
    x = np.array([report.t, report.d, report.q0])
    assert np.all(x >= lo * (1 - 1e-12)) and np.all(x <= hi * (1 + 1e-12))
    assert report.plastic_moment == pytest.approx(
        float(p.section.plastic_moment(report.t, report.d))
    )


def test_report_renders(report):
    text = report.summary()
    for unit in ("mm", "kN*m", "kg/m", "kN/m", "mm of crush", " m"):
        assert unit in text
    data = json.loads(json.dumps(report.as_dict()))
    assert data["feasible"] is True
    assert data["objective"] == pytest.approx(report.objective)
    assert isinstance(data["damages"], list) and len(data["damages"]) == 2
    # A grid without a feasible point: no relative difference, and still plain JSON.
    empty = dataclasses.replace(
        report, grid_objective=float("inf"), relative_difference=float("nan")
    )
    data = json.loads(json.dumps(empty.as_dict(), allow_nan=False))
    assert data["grid_objective"] is None and data["relative_difference"] is None
    assert "n/a" in empty.summary()


def test_other_limit_against_grid(report, evaluate):
    # Same compiled solver and grid (the limit is a traced leaf), a looser limit.
    problem = SizingProblem(deflection_limit=0.7)
    sol = solve(problem)
    k = int(sol.best)
    f, c = float(sol.objective[k]), float(sol.constraint[k])
    grid = grid_search(problem)
    assert -1e-6 < c <= 0.0 and float(grid.constraint) <= 0.0
    assert f <= 1.01 * float(grid.objective)
    assert f < report.objective  # a looser limit allows less crush
    damage, deflection = evaluate(sol.x[k])  # `evaluate` has the 0.6 m problem: same model
    assert f == pytest.approx(float(jnp.mean(damage)), rel=1e-12)
    assert float(jnp.max(deflection)) <= 0.7
