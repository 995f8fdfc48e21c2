"""simulate(scene): physical units, invariance of units, energy, batches, gradients, dispatch."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import barrierjax as bj
from barrierjax.hinge import oblique_impact
from barrierjax.hinge.normal.results import N_SHAPE

INCH, LBF = 0.0254, 4.4482216152605  # m, N
POUND_MASS = LBF / INCH  # kg in one lbf s^2/in (175.127 kg)


def si_scene(speed=40 / 3.6):
    return bj.Scene(
        bj.Barrier(plastic_moment=105e3, mass_per_length=34.0, backing_strength=60e3),
        bj.Vehicle(mass=2270.0, crush_force=450e3),
        bj.Impact(speed=speed),
    )


def inch_pound_scene():
    """The same scene in the report's units: inch, lbf, second (mass in lbf s^2/in)."""
    return bj.Scene(
        bj.Barrier(
            plastic_moment=105e3 / (LBF * INCH),
            mass_per_length=34.0 / (POUND_MASS / INCH),
            backing_strength=60e3 / (LBF / INCH),
        ),
        bj.Vehicle(mass=2270.0 / POUND_MASS, crush_force=450e3 / LBF),
        bj.Impact(speed=40 / 3.6 / INCH),
    )


@pytest.mark.parametrize("method", ["closed_form", "ode"])
def test_results_do_not_depend_on_units(method):
    si = bj.simulate(si_scene(), method=method, n_history=0)
    ips = bj.simulate(inch_pound_scene(), method=method, n_history=0)
    assert float(ips.damage) * INCH == pytest.approx(float(si.damage), rel=1e-12)
    assert float(ips.max_deflection) * INCH == pytest.approx(float(si.max_deflection), rel=1e-12)
    assert float(ips.duration) == pytest.approx(float(si.duration), rel=1e-12)
    assert float(ips.peak_force) * LBF == pytest.approx(float(si.peak_force), rel=1e-12)
    assert float(ips.hinge_position) * INCH == pytest.approx(float(si.hinge_position), rel=1e-12)
    assert float(ips.backing_work) * LBF * INCH == pytest.approx(float(si.backing_work), rel=1e-12)


def test_energy_balance_in_physical_units():
    r = bj.simulate(si_scene(), n_history=0)
    spent = r.crush_work + r.backing_work + r.hinge_work
    assert float(spent) == pytest.approx(float(r.kinetic_energy), rel=1e-10)


def test_histories_and_deflected_shape():
    r = bj.simulate(si_scene(), n_history=100)
    h = r.history
    assert h.deflected_shape.shape == (200, N_SHAPE)
    # Under the impact point the shape is the displacement history.
    np.testing.assert_allclose(h.deflected_shape[:, 0], h.barrier_displacement, rtol=1e-12, atol=1e-15)
    # Nothing moves beyond the hinge; the final hinge is the hinge extent.
    beyond = np.asarray(h.x)[None, :] > np.asarray(h.hinge_position)[:, None] * (1 + 1e-9)
    assert np.all(np.asarray(h.deflected_shape)[beyond] == 0.0)
    assert float(h.hinge_position[-1]) == pytest.approx(float(r.hinge_position), rel=1e-12)
    # The shape never rises with distance from the impact point, and displacement never
    # decreases in time (a rigid-plastic backing does not spring back).
    assert np.all(np.diff(np.asarray(h.deflected_shape), axis=1) <= 1e-12)
    assert np.all(np.diff(np.asarray(h.deflected_shape), axis=0) >= -1e-9)
    assert float(h.barrier_displacement[-1]) == pytest.approx(float(r.max_deflection), rel=1e-12)
    assert float(h.time[-1]) == pytest.approx(float(r.duration), rel=1e-12)


def test_vmap_over_scene_leaves_equals_loop():
    speeds = jnp.array([3.0, 8.0, 15.0, 25.0])
    batch = jax.vmap(lambda s: bj.simulate(s, n_history=0))(bj.broadcast_scene(si_scene(speed=speeds)))
    for i, v in enumerate(speeds):
        single = bj.simulate(si_scene(speed=float(v)), n_history=0)
        assert float(batch.max_deflection[i]) == pytest.approx(float(single.max_deflection), rel=1e-13)
        assert float(batch.damage[i]) == pytest.approx(float(single.damage), rel=1e-13)


@pytest.mark.parametrize("method", ["closed_form", "ode"])
def test_gradient_with_respect_to_every_scene_leaf(method):
    base = si_scene()
    leaves, treedef = jax.tree.flatten(base)
    x = jnp.stack(leaves)

    def outputs(x):
        r = bj.simulate(jax.tree.unflatten(treedef, list(x)), method=method, rtol=1e-11, n_history=0)
        return jnp.stack([r.damage, r.max_deflection, r.duration])

    jacobian = jax.jacrev(outputs)(x)
    # M0, m, q0, M, P0, speed (the angle and friction belong to the oblique model)
    for i in range(6):
        h = 1e-6 * x[i]
        fd = (outputs(x.at[i].add(h)) - outputs(x.at[i].add(-h))) / (2 * h)
        scale = jnp.maximum(jnp.abs(fd), 1e-6 * jnp.max(jnp.abs(jacobian), axis=1))
        assert float(jnp.max(jnp.abs(jacobian[:, i] - fd) / scale)) < 1e-5, i


def test_axial_capacity_runs_the_axial_model():
    barrier = bj.Barrier(1e5, 34.0, 6e4, axial_capacity=1e6)
    scene = eqx.tree_at(lambda s: s.barrier, si_scene(), barrier)
    result = bj.simulate(scene, n_history=20)
    g = bj.dimensionless(scene)
    model = bj.hinge.axial_impact(  # n_history as simulate's: its program, not another
        g.mass_ratio, g.force_ratio, g.normal_speed, axial_ratio=g.axial_ratio, n_history=20
    )
    assert float(result.max_deflection) == pytest.approx(float(model.barrier_displacement * g.scales.length))
    plain = bj.simulate(si_scene(), n_history=0)
    assert float(result.max_deflection) < float(plain.max_deflection)
    assert np.isinf(float(result.model.t_string))
    total = result.crush_work + result.backing_work + result.hinge_work
    assert float(total) == pytest.approx(float(result.kinetic_energy), rel=1e-7)


def test_axial_scene_whose_beam_locks_says_the_vehicle_crushes_to_rest():
    # A 36 t lorry whose crush force barely exceeds the barrier's collapse force (phi =
    # 1.008): the axial force stops the beam within 80 ms, and the vehicle crushes on to
    # rest against it, at its crush force, which takes M v / P. The summary said it crushed
    # "for the first" 78 ms.
    from barrierjax.cli import format_summary, result_dict

    barrier = bj.Barrier(105e3, 34.0, 60e3, axial_capacity=1.5e6)
    lorry = bj.Scene(barrier, bj.Vehicle(mass=36000.0, crush_force=320e3), bj.Impact(80 / 3.6))
    result = bj.simulate(lorry, n_history=20)
    data = result_dict(lorry, result)
    assert data["axial_ratio"] is not None and data["string_start_s"] is None
    assert data["duration_s"] == pytest.approx(36000.0 * (80 / 3.6) / 320e3, rel=1e-9)
    assert data["accelerative_phase_s"] < 0.1 * data["duration_s"]
    assert "vehicle crushes to rest; the axial force stopped the beam at" in format_summary(data)
    # Where the crushing ends first, the vehicle takes longer than M v / P to stop.
    held = bj.Barrier(1e5, 34.0, 6e4, axial_capacity=1e6)
    pickup = eqx.tree_at(lambda s: s.barrier, si_scene(), held)
    riding = result_dict(pickup, bj.simulate(pickup, n_history=20))
    assert riding["axial_ratio"] is not None and riding["string_start_s"] is None
    assert riding["duration_s"] > 1.01 * 2270.0 * (40 / 3.6) / 450e3
    assert "vehicle crushes for the first" in format_summary(riding)


def test_axial_scene_that_reaches_the_plastic_string():
    # The default barrier held against axial motion (N0 = Fy A = 1.5 MN) at 100 km/h: N
    # reaches N0 after the crushing phase, and the string stretches to rest.
    from barrierjax.cli import format_summary, result_dict

    barrier = bj.Barrier(105e3, 34.0, 60e3, axial_capacity=1.5e6)
    scene = eqx.tree_at(lambda s: s.barrier, si_scene(100 / 3.6), barrier)
    result = bj.simulate(scene, n_history=20)
    assert np.isfinite(float(result.model.t_string))
    assert float(result.string_work) > 0.0
    total = result.crush_work + result.backing_work + result.hinge_work + result.string_work
    # To the string's discretisation error (128 cells).
    assert float(total) == pytest.approx(float(result.kinetic_energy), rel=1e-5)
    data = result_dict(scene, result)
    assert data["string_start_s"] == pytest.approx(float(result.model.t_string * result.groups.scales.time))
    assert abs(data["energy_balance_error_J"]) < 1e-5 * data["kinetic_energy_J"]
    assert "plastic string from" in format_summary(data)
    # The deflected shape at rest is the string's: its centre is the final deflection, it
    # falls towards the held ends and vanishes beyond the final half-span.
    h = result.history
    final_shape = np.asarray(h.deflected_shape[-1])
    assert final_shape[0] == pytest.approx(float(result.max_deflection), rel=1e-12)
    assert np.all(np.diff(final_shape) <= 1e-12)
    beyond = np.asarray(h.x) > float(result.hinge_position)
    assert beyond.any() and np.all(final_shape[beyond] == 0.0)


def test_unimplemented_physics_is_refused_not_ignored():
    barrier = bj.Barrier(1e5, 34.0, 6e4, axial_capacity=1e6)
    axial = bj.Scene(barrier, si_scene().vehicle, bj.Impact(10.0, angle_deg=30.0))
    with pytest.raises(NotImplementedError, match="axial_capacity"):
        bj.simulate(axial)


def test_options_a_model_does_not_read_are_checked_for_every_model():
    # The oblique and axial models take no `method`, the normal one no step budget: a
    # misspelt method or a budget of -5 ran as if fine.
    oblique = bj.Scene(si_scene().barrier, si_scene().vehicle, bj.Impact(11.0, 25.0))
    for scene in (si_scene(), oblique):
        with pytest.raises(ValueError, match="method must be 'closed_form' or 'ode'"):
            bj.simulate(scene, method="bad")
        with pytest.raises(ValueError, match="max_steps must be None or an integer >= 16"):
            bj.simulate(scene, method="ode", max_steps=-5)


def test_oblique_scene_runs_the_oblique_model():
    scene = eqx.tree_at(lambda s: s.impact, si_scene(), bj.Impact(10.0, angle_deg=25.0))
    result = bj.simulate(scene, n_history=0, rtol=1e-6)
    g = bj.dimensionless(scene)
    direct = oblique_impact(g.mass_ratio, g.force_ratio, g.normal_speed, g.tangential_speed, rtol=1e-6)
    assert float(result.damage) == pytest.approx(float(direct.damage * g.scales.length), rel=1e-12)
    assert float(result.exit_angle_deg) == pytest.approx(float(direct.exit_angle_deg), rel=1e-12)
    assert 0.0 < float(result.exit_speed) < 10.0
    # Where the vehicle's kinetic energy went, the exit kinetic energy included.
    spent = (
        result.crush_work + result.backing_work + result.hinge_work + result.friction_work
        + result.slope_work + 0.5 * scene.vehicle.mass * result.exit_speed**2
    )
    assert float(spent) == pytest.approx(float(result.kinetic_energy), rel=1e-6)


def test_traced_angle_dispatch():
    def run(angle, **options):
        scene = bj.Scene(si_scene().barrier, si_scene().vehicle, bj.Impact(10.0, angle_deg=angle))
        return bj.simulate(scene, n_history=0, rtol=1e-9, **options).damage

    normal = jax.jit(run)
    assert float(normal(90.0)) == pytest.approx(float(run(90.0)), rel=1e-12)
    with pytest.raises(Exception, match="oblique=True"):
        float(normal(30.0))
    oblique = jax.jit(lambda a: run(a, oblique=True))
    assert float(oblique(90.0)) == pytest.approx(float(run(90.0)), rel=1e-7)
    assert float(oblique(30.0)) == pytest.approx(float(run(30.0)), rel=1e-9)

