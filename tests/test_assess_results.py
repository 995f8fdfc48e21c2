"""`barrierjax.assess.assess` on the project's own impact results (normal, oblique, axial),
and `barrierjax run`'s occupant-risk summary."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import barrierjax as bj
from barrierjax import scene_file
from barrierjax.assess import assess, judge

BARRIER = bj.Barrier(plastic_moment=105e3, mass_per_length=34.0, backing_strength=60e3)


def crushing_scene(crush_force=150e3, speed=40 / 3.6):
    """A crush force below the barrier's collapse load: the barrier stays put and the
    vehicle decelerates at P0 / M throughout (report 3.2's rigid-barrier limit)."""
    return bj.Scene(
        BARRIER, bj.Vehicle(mass=2270.0, crush_force=crush_force), bj.Impact(speed=speed)
    )


def test_rigid_barrier_limit_is_the_constant_deceleration_closed_form():
    scene = crushing_scene()
    result = bj.simulate(scene)
    assert float(result.max_deflection) == 0.0
    a = 150e3 / 2270.0
    risk = assess(result)
    assert float(risk.ora_x) == pytest.approx(a, rel=1e-9)
    assert float(risk.oiv_x) == pytest.approx(np.sqrt(2 * a * 0.6), rel=1e-9)
    assert float(risk.t_impact) == pytest.approx(np.sqrt(1.2 / a), rel=1e-9)
    assert float(risk.oiv_y) == 0.0 and bool(risk.impact_in_record)


def test_gradient_through_simulate_and_assess_matches_closed_form_and_finite_differences():
    def oiv(crush_force):
        return assess(bj.simulate(crushing_scene(crush_force)), t_end=0.2).oiv_x

    p0 = 150e3
    grad = float(jax.grad(oiv)(p0))
    assert grad == pytest.approx(0.5 * float(oiv(p0)) / p0, rel=1e-8)  # OIV ~ sqrt(P0)
    h = 1e-4 * p0
    assert grad == pytest.approx((float(oiv(p0 + h)) - float(oiv(p0 - h))) / (2 * h), rel=1e-6)


def test_vehicle_stopped_within_the_flail_space_gives_the_impact_speed():
    """The default scene stops the vehicle in 0.43 m and 79 ms, when the occupant has
    moved v0 t - 0.43 = 0.45 m relative to it: it flies on at the full impact speed and
    strikes after the history, at v0, with no ridedown."""
    scene = scene_file.default_scene()
    result = bj.simulate(scene)
    risk = assess(result)
    v0 = float(scene.impact.speed)
    stop = float(result.history.vehicle_displacement[-1])
    assert stop < 0.6 and not bool(risk.impact_in_record)
    assert float(risk.oiv_x) == pytest.approx(v0, rel=1e-9)
    moved = v0 * float(result.duration) - stop
    assert moved < 0.6
    assert float(risk.t_impact) == pytest.approx(
        float(result.duration) + (0.6 - moved) / v0, rel=1e-3
    )
    assert float(risk.ora_x) == 0.0


def test_oblique_oiv_is_the_history_velocity_change_on_the_vehicle_axes():
    """OIV is the vehicle's velocity change up to the occupant impact, on its axes (the
    vehicle's heading is the impact direction: it does not turn)."""
    scene = scene_file.load_scene("examples/oblique_scene.toml")
    result = bj.simulate(scene)
    risk = assess(result)
    h = result.history
    t = float(risk.t_impact)
    angle = np.radians(float(scene.impact.angle_deg))
    dn = float(h.vehicle_velocity[0]) - np.interp(t, h.time, h.vehicle_velocity)
    ds = float(h.vehicle_tangential_velocity[0]) - np.interp(
        t, h.time, h.vehicle_tangential_velocity
    )
    assert float(risk.oiv_x) == pytest.approx(np.sin(angle) * dn + np.cos(angle) * ds, rel=1e-3)
    assert float(risk.oiv_y) == pytest.approx(-np.cos(angle) * dn + np.sin(angle) * ds, rel=1e-3)
    assert bool(risk.impact_in_record)
    verdicts = {c.name: c.verdict for c in judge(risk, "mash")}
    assert set(verdicts) == {"OIV x", "OIV y", "ORA x", "ORA y"}


def test_batched_results_equal_each_member():
    speeds = jnp.asarray([30 / 3.6, 40 / 3.6, 50 / 3.6])
    scene = crushing_scene(crush_force=jnp.full(3, 150e3), speed=speeds)
    results = bj.simulate(bj.broadcast_scene(scene))
    batched = assess(results)
    t_end = float(jnp.max(results.history.time))  # the batch's grid: to its longest history
    for i, v in enumerate(speeds):
        single = assess(bj.simulate(crushing_scene(speed=float(v))), t_end=t_end)
        for name in ("oiv_x", "ora_x", "asi", "t_impact"):
            assert float(getattr(batched, name)[i]) == pytest.approx(
                float(getattr(single, name)), rel=1e-9
            ), name


def test_axial_result_is_assessed():
    scene = scene_file.load_scene("examples/axial_scene.toml")
    risk = assess(bj.simulate(scene))
    assert np.isfinite(float(risk.oiv_x)) and float(risk.oiv_x) > 0


def test_results_without_history_are_refused():
    with pytest.raises(ValueError, match="no history"):
        assess(bj.simulate(crushing_scene(), n_history=0))


@pytest.mark.parametrize(
    ("options", "message"),
    [
        (dict(dt=0.0), "dt must be positive and at most 0.001 s"),
        (dict(dt=float("nan")), "dt must be positive and at most 0.001 s"),
        (dict(dt=-1e-4), "dt must be positive and at most 0.001 s"),
        (dict(dt=1.0), "dt must be positive and at most 0.001 s"),
        (dict(t_end=-1.0), "t_end must be positive and finite"),
        (dict(t_end=float("inf")), "t_end must be positive and finite"),
    ],
)
def test_bad_grids_name_the_option(options, message):
    # dt = 0 divided by zero, NaN failed converting to an integer, -1e-4 blamed the grid's
    # own times, and t_end = -1 or dt = 1 s were judged as if fine.
    result = bj.simulate(crushing_scene())
    with pytest.raises(ValueError, match=message):
        assess(result, **options)


def test_run_reports_the_occupant_risk(capsys, tmp_path):
    import json

    from barrierjax import cli

    status = cli.main(["run", "--json", "--no-plots"])
    data = json.loads(capsys.readouterr().out)["occupant_risk"]
    assert status == 0
    assert data["oiv_x_m_s"] == pytest.approx(40 / 3.6, rel=1e-9)  # stopped within 0.6 m
    assert not data["impact_within_history"]
    assert data["MASH"]["criteria"]["OIV x"] == "pass"  # 11.1 m/s < 12.2 m/s
    assert data["EN 1317"]["criteria"]["THIV"] == "fail"  # 40 km/h > 33 km/h
