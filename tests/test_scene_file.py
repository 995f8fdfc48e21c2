"""Scene files: unit conversion to SI, the default scene, and one-line errors naming the key."""

import math
import textwrap

import jax
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

import barrierjax as bj
from barrierjax.scene_file import (
    FIELDS,
    SceneFileError,
    default_scene,
    field_key,
    load_scene,
    parse_quantity,
    parse_scene,
)

INCH, LBF = 0.0254, 4.4482216152605


def tables(**changes):
    """A valid scene as TOML tables; `changes` maps "section.key" to a value, or to None
    to drop the key (or the section)."""
    data = {
        "barrier": {
            "plastic_moment": "100 kN*m",
            "mass_per_length": "60 kg/m",
            "backing_strength": "60 kN/m",
        },
        "vehicle": {"mass": "2000 kg", "crush_force": "400 kN"},
        "impact": {"speed": "40 km/h"},
    }
    for name, value in changes.items():
        section, _, key = name.partition(".")
        if not key:
            if value is None:
                data.pop(section, None)
            else:
                data[section] = value
        elif value is None:
            data[section].pop(key, None)
        else:
            data.setdefault(section, {})[key] = value
    return data


@pytest.mark.parametrize(
    "section, key, text, expected",
    [
        ("impact", "speed", "40 km/h", 40 / 3.6),
        ("impact", "speed", "25 mph", 25 * 0.44704),
        ("impact", "speed", "600 in/s", 600 * INCH),
        ("impact", "speed", "3 ft / (0.5 s)", 6 * 0.3048),
        ("barrier", "plastic_moment", "100 kN*m", 1e5),
        ("barrier", "plastic_moment", "100 kN m", 1e5),
        ("barrier", "plastic_moment", "1e6 lbf*in", 1e6 * LBF * INCH),
        ("barrier", "plastic_moment", "345 MPa * 3.057e-4 m**3", 345e6 * 3.057e-4),
        ("barrier", "mass_per_length", "60 kg/m", 60.0),
        ("barrier", "mass_per_length", "22.37 lb/ft", 22.37 * 0.45359237 / 0.3048),
        ("barrier", "mass_per_length", "0.01 lbf*s**2/in**2", 0.01 * LBF / INCH**2),
        ("barrier", "backing_strength", "60 kN/m", 6e4),
        ("barrier", "backing_strength", "300 lbf/in", 300 * LBF / INCH),
        ("barrier", "axial_capacity", "1.5 MN", 1.5e6),
        ("vehicle", "mass", "2270 kg", 2270.0),
        ("vehicle", "mass", "5000 lb", 5000 * 0.45359237),
        ("vehicle", "mass", "13 lbf*s**2/in", 13 * LBF / INCH),
        ("vehicle", "crush_force", "450 kN", 4.5e5),
        ("vehicle", "crush_force", "100 kip", 1e5 * LBF),
        ("impact", "angle", "90 deg", 90.0),
        ("impact", "angle", "90 degree", 90.0),
        ("impact", "angle", f"{math.pi / 2} rad", 90.0),
        ("impact", "friction", 0.25, 0.25),
        ("impact", "friction", 0, 0.0),
        ("impact", "friction", "0.25", 0.25),
    ],
)
def test_quantities_convert_to_si(section, key, text, expected):
    assert parse_quantity(text, FIELDS[section][key]) == pytest.approx(expected, rel=1e-12)


def test_scene_in_si():
    scene = parse_scene(tables(**{"impact.angle": "90 deg", "impact.friction": 0.1}))
    assert isinstance(scene, bj.Scene)
    b, v, i = scene.barrier, scene.vehicle, scene.impact
    assert float(b.plastic_moment) == 1e5
    assert float(b.mass_per_length) == 60.0
    assert float(b.backing_strength) == 6e4
    assert b.axial_capacity is None
    assert float(v.mass) == 2000.0 and float(v.crush_force) == 4e5
    assert float(i.speed) == pytest.approx(11.11111111111111, rel=1e-14)
    assert float(i.angle_deg) == 90.0 and float(i.friction) == pytest.approx(0.1)
    assert b.plastic_moment.dtype == np.float64


def test_optional_keys_default():
    scene = parse_scene(tables())
    assert float(scene.impact.angle_deg) == 90.0
    assert float(scene.impact.friction) == 0.0
    assert scene.barrier.axial_capacity is None
    axial = parse_scene(tables(**{"barrier.axial_capacity": "2 MN"}))
    assert float(axial.barrier.axial_capacity) == 2e6


def test_inch_pound_file_equals_si(tmp_path):
    """The report's units (inch, lbf, second) give the same scene as SI."""
    path = tmp_path / "report_units.toml"
    path.write_text(
        textwrap.dedent(
            """
            [barrier]
            plastic_moment = "1e6 lbf*in"
            mass_per_length = "0.003 lbf*s**2/in**2"
            backing_strength = "500 lbf/in"
            [vehicle]
            mass = "10 lbf*s**2/in"
            crush_force = "40000 lbf"
            [impact]
            speed = "30 mph"
            """
        )
    )
    scene = load_scene(path)
    si = bj.Scene(
        bj.Barrier(1e6 * LBF * INCH, 0.003 * LBF / INCH**2, 500 * LBF / INCH),
        bj.Vehicle(10 * LBF / INCH, 40000 * LBF),
        bj.Impact(30 * 0.44704),
    )
    for a, b in zip(jax.tree.leaves(scene), jax.tree.leaves(si)):
        assert float(a) == pytest.approx(float(b), rel=1e-12)
    # and the dimensionless groups do not depend on the units
    ga, gb = bj.dimensionless(scene), bj.dimensionless(si)
    assert float(ga.mass_ratio) == pytest.approx(float(gb.mass_ratio), rel=1e-12)


def test_default_scene_documented_values():
    """The default scene: HSS 203x152x6.4 tube on foam, 2270 kg pickup at 40 km/h."""
    scene = default_scene()
    assert float(scene.barrier.plastic_moment) == pytest.approx(345e6 * 3.057e-4, rel=1e-3)
    assert float(scene.barrier.mass_per_length) == pytest.approx(34.2)
    assert float(scene.barrier.backing_strength) == pytest.approx(6e4)
    assert float(scene.vehicle.mass) == 2270.0
    assert float(scene.vehicle.crush_force) == pytest.approx(4.5e5)
    assert float(scene.impact.speed) == pytest.approx(40 / 3.6)
    g = bj.dimensionless(scene)
    assert float(g.mass_ratio) == pytest.approx(25.0, abs=0.1)
    assert float(g.force_ratio) == pytest.approx(1.414, abs=0.01)


def _error(data) -> SceneFileError:
    with pytest.raises(SceneFileError) as info:
        parse_scene(data)
    message = str(info.value)
    assert "\n" not in message
    return info.value


@pytest.mark.parametrize(
    "changes, prefix, words",
    [
        ({"barrier.plastic_moment": "100 kg"}, "[barrier] plastic_moment:",
         "expected a moment (force*length), got '100 kg'"),
        ({"barrier.plastic_moment": 100}, "[barrier] plastic_moment:", "bare number"),
        ({"barrier.plastic_moment": 1e5}, "[barrier] plastic_moment:", "with units"),
        ({"barrier.plastic_moment": "100"}, "[barrier] plastic_moment:", "bare number"),
        ({"barrier.plastic_moment": "100 kN*"}, "[barrier] plastic_moment:", "not a quantity"),
        ({"barrier.plastic_moment": "abc"}, "[barrier] plastic_moment:", "not a quantity"),
        ({"barrier.plastic_moment": ""}, "[barrier] plastic_moment:", "not a quantity"),
        ({"barrier.plastic_moment": True}, "[barrier] plastic_moment:", "TOML bool"),
        ({"barrier.plastic_moment": "nan kN*m"}, "[barrier] plastic_moment:", "not a number"),
        ({"barrier.plastic_moment": "-5 kN*m"}, "[barrier] plastic_moment:", "positive"),
        ({"barrier.mass_per_length": "60 kg"}, "[barrier] mass_per_length:", "mass per length"),
        ({"barrier.backing_strength": "0.3 MPa"}, "[barrier] backing_strength:", "force per"),
        ({"barrier.backing_strength": "0 kN/m"}, "[barrier] backing_strength:", "positive"),
        ({"barrier.axial_capacity": "3 m"}, "[barrier] axial_capacity:", "a force"),
        ({"vehicle.mass": "2 kN"}, "[vehicle] mass:", "a mass"),
        ({"vehicle.mass": "inf kg"}, "[vehicle] mass:", "finite"),
        ({"vehicle.crush_force": "450 kN/m"}, "[vehicle] crush_force:", "a force"),
        ({"impact.speed": "40 km"}, "[impact] speed:", "a speed"),
        ({"impact.speed": 11.1}, "[impact] speed:", "bare number"),
        ({"impact.angle": 90}, "[impact] angle:", "bare number"),
        ({"impact.angle": "90"}, "[impact] angle:", "bare number"),
        ({"impact.angle": "90 m"}, "[impact] angle:", "an angle"),
        ({"impact.angle": "90 percent"}, "[impact] angle:", "an angle"),
        ({"impact.angle": "120 deg"}, "[impact] angle:", "in (0, 90]"),
        ({"impact.friction": "0.3 deg"}, "[impact] friction:", "dimensionless"),
        ({"impact.friction": "0.3 N"}, "[impact] friction:", "dimensionless"),
        ({"impact.friction": -0.1}, "[impact] friction:", "non-negative"),
        ({"impact.friction": [0.1]}, "[impact] friction:", "TOML list"),
        ({"barrier.plastic_moment": None}, "[barrier] plastic_moment:", "missing"),
        ({"vehicle.crush_force": None}, "[vehicle] crush_force:", "missing"),
        ({"impact.speed": None}, "[impact] speed:", "missing"),
        ({"barrier.plastic_modulus": "1 m**3"}, "[barrier] plastic_modulus:", "unknown key"),
        ({"impact.velocity": "40 km/h"}, "[impact] velocity:", "unknown key"),
        ({"vehicle": None}, "[vehicle]:", "missing section"),
        ({"impact": None}, "[impact]:", "missing section"),
        ({"backing": {"strength": "1 kN/m"}}, "[backing]:", "unknown section"),
        ({"vehicle": "pickup"}, "[vehicle]:", "expected a table"),
    ],
)
def test_errors_name_the_key(changes, prefix, words):
    error = _error(tables(**changes))
    message = str(error)
    assert message.startswith(prefix), message
    assert words in message, message


def test_error_carries_section_and_key():
    error = _error(tables(**{"vehicle.mass": "2 kN"}))
    assert (error.section, error.key) == ("vehicle", "mass")
    assert isinstance(error, ValueError)


def test_invalid_value_error_shows_the_input():
    message = str(_error(tables(**{"barrier.plastic_moment": "-5 kN*m"})))
    assert "'-5 kN*m'" in message and "-5000" in message


def test_load_scene_file_errors(tmp_path):
    with pytest.raises(SceneFileError, match="no such file"):
        load_scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[barrier\nplastic_moment = 1\n")
    with pytest.raises(SceneFileError, match="invalid TOML") as info:
        load_scene(bad)
    assert "\n" not in str(info.value)


def test_field_key_finds_constructor_names():
    assert field_key("Impact.angle_deg < 90: not implemented").key == "angle"
    assert field_key("Barrier.axial_capacity is set").key == "axial_capacity"
    assert field_key("nothing here") is None
