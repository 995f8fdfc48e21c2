"""Scenes and the report's dimensionless groups."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import barrierjax as bj


def scene(**impact):
    return bj.Scene(
        bj.Barrier(plastic_moment=105e3, mass_per_length=34.0, backing_strength=60e3),
        bj.Vehicle(mass=2270.0, crush_force=450e3),
        bj.Impact(**({"speed": 40 / 3.6} | impact)),
    )


def test_groups_match_hand_calculation():
    g = bj.dimensionless(scene())
    moment, m, q0, mass, crush, v = 105e3, 34.0, 60e3, 2270.0, 450e3, 40 / 3.6
    length = 2 * math.sqrt(moment / q0)
    force = 4 * math.sqrt(moment * q0)
    time = math.sqrt(m) * moment**0.25 / q0**0.75
    assert float(g.scales.length) == pytest.approx(length, rel=1e-14)
    assert float(g.scales.force) == pytest.approx(force, rel=1e-14)
    assert float(g.scales.time) == pytest.approx(time, rel=1e-14)
    # docs/errata.md, 3.3.14: velocity scale 2 M0^(1/4) q0^(1/4) / m^(1/2), L/t0^2 = 2 q0/m.
    assert float(g.scales.velocity) == pytest.approx(2 * moment**0.25 * q0**0.25 / math.sqrt(m), rel=1e-14)
    assert float(g.scales.acceleration) == pytest.approx(length / time**2, rel=1e-14)
    assert float(g.mass_ratio) == pytest.approx(mass / (m * length), rel=1e-14)
    assert float(g.force_ratio) == pytest.approx(crush / force, rel=1e-14)
    assert float(g.normal_speed) == pytest.approx(v * time / length, rel=1e-14)
    assert float(g.tangential_speed) == 0.0
    assert g.axial_ratio is None


def test_angle_splits_the_speed():
    g = bj.dimensionless(scene(angle_deg=30.0))
    total = math.hypot(float(g.normal_speed), float(g.tangential_speed))
    assert float(g.normal_speed) == pytest.approx(0.5 * total, rel=1e-14)


def test_a_small_angle_gives_a_small_positive_normal_speed_in_float32():
    # Through the complement's cosine it came out -1.3e-8, refused later as a normal speed.
    with jax.enable_x64(False):
        g = bj.dimensionless(scene(angle_deg=1e-6))
        assert 0.0 < float(g.normal_speed) < 1e-7 * float(g.tangential_speed)
        assert float(bj.dimensionless(scene(angle_deg=90.0)).tangential_speed) == 0.0


def test_a_value_beyond_float32_is_refused_there_naming_its_field():
    # It was checked in float64 and stored as inf: `simulate` then blamed a mass ratio of 0.
    with jax.enable_x64(False):
        with pytest.raises(ValueError, match=r"Barrier.plastic_moment must be .* in float32"):
            bj.Barrier(1e39, 34.0, 60e3)
    assert float(bj.Barrier(1e39, 34.0, 60e3).plastic_moment) == 1e39


def test_axial_ratio():
    s = bj.Scene(bj.Barrier(1.0, 1.0, 4.0, axial_capacity=8.0), bj.Vehicle(1.0, 1.0), bj.Impact(1.0))
    assert float(bj.dimensionless(s).axial_ratio) == pytest.approx(8.0 / (4 * math.sqrt(4.0)))


@pytest.mark.parametrize(
    "build, field",
    [
        (lambda: bj.Barrier(-1.0, 34.0, 60e3), "Barrier.plastic_moment"),
        (lambda: bj.Barrier(1.0, 0.0, 60e3), "Barrier.mass_per_length"),
        (lambda: bj.Barrier(1.0, 1.0, float("nan")), "Barrier.backing_strength"),
        (lambda: bj.Barrier(1.0, 1.0, 1.0, axial_capacity=-2.0), "Barrier.axial_capacity"),
        (lambda: bj.Vehicle(0.0, 1.0), "Vehicle.mass"),
        (lambda: bj.Vehicle(1.0, float("inf")), "Vehicle.crush_force"),
        (lambda: bj.Impact(-3.0), "Impact.speed"),
        (lambda: bj.Impact(1.0, angle_deg=0.0), "Impact.angle_deg"),
        (lambda: bj.Impact(1.0, angle_deg=90.5), "Impact.angle_deg"),
        (lambda: bj.Impact(1.0, friction=-0.1), "Impact.friction"),
        (lambda: bj.Impact(np.array([1.0, -1.0])), "Impact.speed"),
        # Not a number: NumPy's conversion error named no field.
        (lambda: bj.Barrier("105 kN*m", 34.0, 60e3), "Barrier.plastic_moment"),
        (lambda: bj.Vehicle(1.0, {}), "Vehicle.crush_force"),
        (lambda: bj.Scene(bj.Vehicle(1.0, 1.0), bj.Vehicle(1.0, 1.0), bj.Impact(1.0)), "Scene.barrier"),
    ],
)
def test_bad_input_names_the_field(build, field):
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        build()


def test_scene_is_a_pytree_for_vmap():
    speeds = jnp.array([5.0, 10.0, 20.0])
    batch = scene(speed=speeds)
    groups = jax.vmap(bj.dimensionless)(bj.broadcast_scene(batch))
    for i, v in enumerate(speeds):
        assert float(groups.normal_speed[i]) == pytest.approx(float(bj.dimensionless(scene(speed=float(v))).normal_speed))


def test_top_level_names_a_newcomer_reaches_for():
    for name in ("Scene", "Barrier", "Vehicle", "Impact", "simulate", "load_scene", "Result"):
        assert name in bj.__all__ and callable(getattr(bj, name)), name
    for package in ("hinge", "materials", "beam", "design"):
        assert getattr(bj, package).__name__ == f"barrierjax.{package}"
    assert bj.load_scene(bj.scene_file.default_scene_path()) == bj.scene_file.default_scene()
