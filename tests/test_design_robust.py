"""barrierjax.design robust sizing: real-world impact distributions, the expected crush,
the crash tests' criteria, the optimum against the grid, and the `optimize --level` CLI."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

from barrierjax import Barrier
from barrierjax.cli import main
from barrierjax.design import (
    RobustSizing,
    crash_test_responses,
    damages,
    expected_damage,
    optimize_robust,
    rail_barrier,
    robust_formulation,
)
from barrierjax.design.impacts import (
    IMPACT_SEVERITY,
    VEHICLE_MASS,
    Lognormal,
    impact_severity,
    real_world_impacts,
    vehicle_mass,
)

G = 9.80665
CRUSH_PER_MASS = 450e3 / 2270.0
# A design where every real-world vehicle and both test vehicles yield the barrier.
X_SOFT = jnp.array([6.0e-3, 20e3])


@pytest.fixture(scope="module")
def problem():
    return RobustSizing(n_severity=8, n_mass=4)


@pytest.fixture(scope="module")
def measure(problem):
    form = robust_formulation(problem)
    return jax.jit(lambda u: form.measure(form.problem, u))


# --------------------------------------------------------------------------------------
# The distributions.


def test_lognormal_fits_pass_through_their_percentiles_and_say_how_far_the_rest_are():
    severity = impact_severity("Interstate")
    row = IMPACT_SEVERITY["Interstate"]
    assert severity.quantile(0.5) == pytest.approx(row.median, rel=1e-12)
    assert severity.quantile(0.95) == pytest.approx(row.p95, rel=1e-12)
    checks = {name: (published, fitted) for name, published, fitted in severity.check()}
    assert checks["mean"][0] == row.mean and checks["mean"][1] == pytest.approx(51711.18, rel=1e-5)
    assert checks["90th percentile"][1] / checks["90th percentile"][0] - 1 == pytest.approx(
        -0.0891, abs=1e-3
    )
    mass = vehicle_mass()
    assert mass.quantile(0.05) == pytest.approx(VEHICLE_MASS[0.05], rel=1e-12)
    assert mass.quantile(0.95) == pytest.approx(VEHICLE_MASS[0.95], rel=1e-12)
    assert mass.check()[0][2] / VEHICLE_MASS[0.925] - 1 == pytest.approx(0.0346, abs=1e-3)


@pytest.mark.parametrize("n", [1, 3, 32])
def test_nodes_are_slice_means(n):
    """The nodes' average is the lognormal's mean exactly; each node is its slice's
    conditional mean (checked against a fine quadrature of the slice)."""
    dist = Lognormal(math.log(30e3), 0.9, "test")
    nodes = dist.nodes(n)
    assert np.mean(nodes) == pytest.approx(dist.mean, rel=1e-12)
    k = n // 2
    p = (k + (np.arange(200_000) + 0.5) / 200_000) / n
    assert nodes[k] == pytest.approx(np.mean(dist.quantile(p)), rel=1e-4)
    assert np.all(np.diff(nodes) > 0)


def test_impacts_and_their_bad_inputs():
    impacts = real_world_impacts("County Road", 4, 3)
    assert impacts.mass.shape == impacts.severity.shape == (12,)
    np.testing.assert_allclose(0.5 * impacts.mass * impacts.normal_speed**2, impacts.severity)
    with pytest.raises(ValueError, match="road_class must be one of"):
        real_world_impacts("Autobahn")
    with pytest.raises(ValueError, match="n_mass must be a positive integer"):
        real_world_impacts(n_mass=0)
    with pytest.raises(ValueError, match="Lognormal.through needs"):
        Lognormal.through(0.5, 30e3, 0.95, 20e3, "falling percentiles")
    with pytest.raises(ValueError, match="Lognormal.through needs"):
        Lognormal.through(0.95, 20e3, 0.5, 30e3, "probabilities out of order")


# --------------------------------------------------------------------------------------
# The model.


def test_rigid_barrier_expected_crush_is_the_severity_over_the_crush_force(problem):
    """A barrier no vehicle can yield (P_b = 4 (M0 q0)^1/2 above every P0) is a rigid
    wall: D = IS / P0 in every impact, so E[D] = mean(IS / (c M))."""
    x = jnp.array([12.7e-3, 300e3])
    barrier = rail_barrier(problem, x)
    collapse = 4.0 * math.sqrt(float(barrier.plastic_moment) * float(barrier.backing_strength))
    assert collapse > CRUSH_PER_MASS * float(np.max(problem.impacts.mass))
    expected = np.mean(problem.impacts.severity / (CRUSH_PER_MASS * problem.impacts.mass))
    assert float(expected_damage(problem, x)) == pytest.approx(expected, rel=1e-12)
    assert float(jnp.max(damages(problem, barrier)[1])) == 0.0


def test_energy_balance_in_every_real_world_impact(problem):
    """Crush, backing and hinge work add up to each impact's severity (report 3.2)."""
    from barrierjax import Impact, Scene, Vehicle, simulate

    barrier = rail_barrier(problem, X_SOFT)
    mass, speed = problem.impact_mass, problem.impact_speed
    scene = Scene(barrier, Vehicle(mass, CRUSH_PER_MASS * mass), Impact(speed))
    r = simulate(scene, n_history=0)
    work = r.crush_work + r.backing_work + r.hinge_work
    np.testing.assert_allclose(work, problem.impacts.severity, rtol=1e-7)
    np.testing.assert_allclose(r.damage, damages(problem, barrier)[0], rtol=1e-12)


def test_crash_test_against_a_rigid_barrier_matches_the_flail_space_closed_form(problem):
    """MASH 3-10 against a barrier the car cannot yield: the car decelerates at c normal
    to the barrier, c cos 25 deg on its lateral axis, until its normal speed is spent; the
    occupant crosses 0.3 m laterally first, at t = (0.6 / a_y)^1/2, with OIV = a_y t; the
    ridedown is the rest of the stop averaged over 10 ms."""
    values = np.asarray(
        crash_test_responses(problem, rail_barrier(problem, jnp.array([12.7e-3, 300e3])))
    )
    angle = math.radians(25.0)
    a_y = CRUSH_PER_MASS * math.cos(angle)
    t_impact = math.sqrt(0.6 / a_y)
    t_stop = 100 / 3.6 * math.sin(angle) / CRUSH_PER_MASS
    assert t_impact < t_stop
    deflection, oiv, ora = values[0]
    assert deflection == 0.0
    assert oiv == pytest.approx(a_y * t_impact, rel=2e-3)
    assert ora == pytest.approx(a_y * (t_stop - t_impact) / 0.010, rel=2e-2)


def test_vmap_equals_loop(problem, measure):
    form = robust_formulation(problem)
    u = jnp.array([[0.1, 0.2], [0.5, 0.5], [0.9, 0.3], [0.3, 0.9]])
    batched = jax.jit(jax.vmap(lambda v: form.measure(form.problem, v)))(u)
    for k in range(u.shape[0]):
        f, g = measure(u[k])
        assert float(f) == pytest.approx(float(batched[0][k]), rel=1e-10)
        np.testing.assert_allclose(g, batched[1][k], rtol=1e-9, atol=1e-12)


def test_gradients_match_finite_differences(problem, measure):
    form = robust_formulation(problem)
    u = jnp.array([0.3, 0.35])
    jac = jax.jit(jax.jacfwd(lambda v: form.measure(form.problem, v)))(u)
    h = 1e-6
    for k in range(2):
        step = jnp.zeros(2).at[k].set(h)
        (f1, g1), (f0, g0) = measure(u + step), measure(u - step)
        fd_f = (float(f1) - float(f0)) / (2 * h)
        assert float(jac[0][k]) == pytest.approx(fd_f, rel=1e-4)
        deflection_rows = slice(0, None, 3)  # the deflections, smooth in the design
        np.testing.assert_allclose(
            jac[1][deflection_rows, k], ((g1 - g0) / (2 * h))[deflection_rows], rtol=1e-4, atol=1e-9
        )


def test_bad_inputs_name_the_field():
    with pytest.raises(ValueError, match="RobustSizing.level must be a MASH test level"):
        RobustSizing("EN 1317 N2")
    with pytest.raises(ValueError, match="unknown test level"):
        RobustSizing("MASH TL-9")
    with pytest.raises(ValueError, match="RobustSizing.deflection_limit must be positive"):
        RobustSizing(deflection_limit=-0.1)
    with pytest.raises(ValueError, match="RobustSizing.backing_bounds must satisfy"):
        RobustSizing(backing_bounds=(300e3, 5e3))
    with pytest.raises(ValueError, match="RobustSizing.thickness_bounds: the upper thickness"):
        RobustSizing(thickness_bounds=(5e-3, 0.09))
    with pytest.raises(ValueError, match=r"RobustSizing.rtol must be in \(0, 1\)"):
        RobustSizing(rtol=0.0)
    with pytest.raises(ValueError, match="road_class must be one of"):
        RobustSizing(road_class="Autobahn")


def test_a_crash_test_longer_than_its_risk_window_is_an_error(monkeypatch):
    from barrierjax.design import robust

    # The window a fifth of the softest design's longest test (not 1.25 times it).
    monkeypatch.setattr(robust, "_WINDOW_MARGIN", 0.2)
    short = RobustSizing(n_severity=2, n_mass=2)
    softest = rail_barrier(short, short.lower)
    with pytest.raises(Exception, match="a crash test's impact lasts longer than the 0.1 s"):
        jax.block_until_ready(crash_test_responses(short, softest))


# --------------------------------------------------------------------------------------
# The optimum.


def test_optimum_within_0p1_percent_of_the_grid_and_feasible(problem):
    baseline = Barrier(105.5e3, 34.2, 60e3)
    report = optimize_robust(problem, baseline, baseline_name="default scene", grid_n=41)
    assert report.optimum.feasible and report.baseline.feasible
    assert abs(report.relative_difference) <= 1e-3
    # The optimum uses its freedom: the 3-11 deflection sits on the limit, and the
    # expected crush is below the baseline's.
    assert report.optimum.margins["MASH 3-11"]["deflection"] == pytest.approx(0.0, abs=1e-8)
    assert report.optimum.expected_damage < report.baseline.expected_damage
    assert 0.0 <= report.optimum.exceedance <= 1.0
    text = report.summary()
    assert "MASH 3-11" in text and "grid's best - 1" in text and "all criteria met" in text
    assert report.as_dict()["optimum"]["margins"]["MASH 3-10"]["OIV"] > 0


# --------------------------------------------------------------------------------------
# The command line (its bad inputs; the full run is the test above, through the library).


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["optimize", "--level", "MASH-TL9"], "unknown test level"),
        (["optimize", "--level", "EN1317-N2"], "must be a MASH test level"),
        (["optimize", "--level", "MASH-TL3", "--deflection-limit", "3 kg"], "expected a length"),
        (["optimize", "barrierjax/default_scene.toml"], "pass --level"),
    ],
)
def test_optimize_bad_input_is_one_line(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1
