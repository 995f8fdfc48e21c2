"""System scene files: a crash test of a barrier system in TOML, with units on every
quantity (as `barrierjax.scene_file`, whose quantity parser and errors it shares).

```toml
test = "MASH 3-11"            # optional: the vehicle, speed and angle of a crash test

[vehicle]
preset = "2270P"              # `presets.VEHICLES`; any key below overrides it
# mass = "2270 kg", yaw_inertia = "4400 kg*m**2", length = "5.8 m", ...

[barrier]
preset = "MGS"                # `presets.BARRIERS` (or "rigid wall")
length = "53.34 m"            # a whole number of post spacings
# post_spacing = "1.905 m", post_strength = "40 kN", ...

[impact]
point = "16.2 m"              # where the vehicle's left front corner meets the rail
# speed = "100 km/h", angle = "25 deg" (from the test), friction = 0.3
duration = "0.6 s"
```

Every error is a `SceneFileError` whose one-line message starts with the key.
"""

from collections.abc import Mapping
from dataclasses import dataclass

import jax.numpy as jnp

from ..assess.matrices import crash_test
from ..beam.layered import LayeredSection
from ..materials.plasticity import RateIndependentPlasticity
from ..scene_file import Field, SceneFileError, parse_quantity, read_toml
from . import presets
from .barrier import Guardrail, RigidWall, guardrail, post_springs, rail_section
from .vehicle import Vehicle, vehicle


def _field(section, key, kind, dimension, unit, example, required=False):
    return Field(section, key, key, kind, dimension, unit, example, required)


_LENGTH = ("a length", "[length]", "m", "1.5 m")
_FORCE = ("a force", "[force]", "N", "40 kN")
_STIFFNESS = ("a stiffness (force/length)", "[force]/[length]", "N/m", "1.5 MN/m")
_NUMBER = ("a dimensionless number", None, "", "0.3")

FIELDS: dict[str, dict[str, Field]] = {
    "vehicle": {
        key: _field("vehicle", key, *kind)
        for key, kind in {
            "mass": ("a mass", "[mass]", "kg", "2270 kg"),
            "yaw_inertia": ("a moment of inertia", "[mass]*[length]**2", "kg*m**2", "4400 kg*m**2"),
            "length": _LENGTH,
            "width": _LENGTH,
            "front_to_cg": _LENGTH,
            "cg_to_front_axle": _LENGTH,
            "wheelbase": _LENGTH,
            "track": _LENGTH,
            "crush_stiffness": (
                "a stiffness per length",
                "[force]/[length]**2",
                "N/m**2",
                "1.5 MN/m/m",
            ),
            "crush_strength": ("a force per length", "[force]/[length]", "N/m", "250 kN/m"),
            "tyre_friction": _NUMBER,
        }.items()
    },
    "barrier": {
        key: _field("barrier", key, *kind)
        for key, kind in {
            "length": _LENGTH,
            "post_spacing": _LENGTH,
            "rail_area": ("an area", "[length]**2", "m**2", "1290 mm**2"),
            "rail_second_moment": ("a second moment of area", "[length]**4", "m**4", "1.4e6 mm**4"),
            "elastic_modulus": ("a stress", "[pressure]", "Pa", "200 GPa"),
            "yield_stress": ("a stress", "[pressure]", "Pa", "345 MPa"),
            "density": ("a density", "[mass]/[length]**3", "kg/m**3", "7850 kg/m**3"),
            "post_stiffness": _STIFFNESS,
            "post_strength": _FORCE,
            "post_failure": _LENGTH,
            "post_longitudinal_stiffness": _STIFFNESS,
            "post_longitudinal_strength": _FORCE,
            "anchor_stiffness": _STIFFNESS,
        }.items()
    },
    "impact": {
        "point": _field("impact", "point", *_LENGTH, required=True),
        "speed": _field("impact", "speed", "a speed", "[length]/[time]", "m/s", "100 km/h"),
        "angle": _field("impact", "angle", "an angle", "angle", "deg", "25 deg"),
        "friction": _field("impact", "friction", *_NUMBER),
        "duration": _field("impact", "duration", "a time", "[time]", "s", "0.6 s"),
    },
}
_WORDS = {"vehicle": ("preset",), "barrier": ("preset", "elements_per_span"), "impact": ()}


@dataclass(frozen=True)
class SystemScene:
    """A parsed system scene: the model's parts and the impact, in SI."""

    vehicle: Vehicle
    barrier: Guardrail | RigidWall
    speed: float
    angle_deg: float
    impact_point: float
    duration: float
    friction: float
    test: str | None
    vehicle_name: str
    barrier_name: str


def is_system_scene(data: Mapping) -> bool:
    """A table with a `test`, or a barrier or vehicle given by a preset, is a system scene."""
    if not isinstance(data, Mapping):
        return False
    sections = [data.get(name) for name in ("barrier", "vehicle")]
    return "test" in data or any(isinstance(s, Mapping) and "preset" in s for s in sections)


def _table(data, section):
    table = data.get(section, {})
    if not isinstance(table, Mapping):
        raise SceneFileError(section, None, f"expected a table, got {table!r}")
    for key in table:
        if key not in FIELDS[section] and key not in _WORDS[section]:
            names = ", ".join([*_WORDS[section], *FIELDS[section]])
            raise SceneFileError(section, key, f"unknown key (expected one of {names})")
    return table


def _values(table, section, base: dict) -> dict:
    values = dict(base)
    for key, field in FIELDS[section].items():
        if key in table:
            values[key] = parse_quantity(table[key], field)
    return values


def _preset(table, section, choices: dict, default=None):
    name = table.get("preset", default)
    if name is None:
        return None, {}
    if not isinstance(name, str) or name not in choices:
        raise SceneFileError(section, "preset", f"unknown preset {name!r} (expected one of "
                             f"{', '.join(map(repr, choices))})")  # fmt: skip
    return name, choices[name].values()


def parse_system_scene(data: Mapping) -> SystemScene:
    """Build a `SystemScene` from a scene file's tables. Raises `SceneFileError`."""
    for section in data:
        if section not in (*FIELDS, "test"):
            raise SceneFileError(section, None, "unknown section (expected test, vehicle, "
                                 "barrier, impact)")  # fmt: skip
    test = data.get("test")
    if test is not None:
        try:
            test = crash_test(str(test))
        except ValueError as error:
            raise SceneFileError(None, "test", str(error)) from None
    v_table, b_table, i_table = (_table(data, s) for s in ("vehicle", "barrier", "impact"))
    default_vehicle = test.vehicle if test is not None else None
    v_name, v_base = _preset(v_table, "vehicle", presets.VEHICLES, default_vehicle)
    v_values = _values(v_table, "vehicle", v_base)
    b_name, b_base = _preset(b_table, "barrier", presets.BARRIERS)
    b_values = _values(b_table, "barrier", b_base)
    i_values = _values(i_table, "impact", {"friction": presets.RAIL_FRICTION.value,
                                           "duration": 0.6})  # fmt: skip
    if test is not None:
        i_values.setdefault("speed", test.speed)
        i_values.setdefault("angle", test.angle_deg)
    for key in ("point", "speed", "angle"):
        if key not in i_values:
            field = FIELDS["impact"][key]
            raise SceneFileError("impact", key, f"missing (expected {field.kind}, e.g. "
                                 f"'{field.example}', or a test)")  # fmt: skip
    try:
        car = vehicle(**v_values)
    except (TypeError, ValueError) as error:
        raise SceneFileError("vehicle", None, _missing(error, "vehicle")) from None
    try:
        barrier = _barrier(b_name, b_values, b_table)
    except (TypeError, ValueError) as error:
        raise SceneFileError("barrier", None, _missing(error, "barrier")) from None
    return SystemScene(
        car,
        barrier,
        *(float(i_values[k]) for k in ("speed", "angle", "point", "duration", "friction")),
        None if test is None else test.label,
        v_name or "vehicle",
        b_name or "barrier",
    )


def _missing(error, section) -> str:
    """A constructor's complaint, worded for the scene file."""
    text = " ".join(str(error).split())
    if "missing" in text and "argument" in text:
        return f"{text.split('(')[0].strip()}: give a preset or every key ({section})"
    return text


def _barrier(name, values, table):
    if name == "rigid wall":  # from 100 m upstream of the impact to `length`
        return RigidWall(jnp.asarray(-100.0), jnp.asarray(values.get("length", 100.0)))
    law = RateIndependentPlasticity(values["elastic_modulus"], values["yield_stress"])
    section: LayeredSection = rail_section(values["rail_area"], values["rail_second_moment"], law)
    posts = post_springs(values["post_stiffness"], values["post_strength"],
                         values["post_failure"], values["post_longitudinal_stiffness"],
                         values["post_longitudinal_strength"])  # fmt: skip
    return guardrail(values["length"], values["post_spacing"], section=section,
                     density=values["density"], posts=posts,
                     anchor_stiffness=values["anchor_stiffness"],
                     elements_per_span=int(table.get("elements_per_span", 8)))  # fmt: skip


def load_system_scene(path) -> SystemScene:
    """Read the system scene file at `path`."""
    return parse_system_scene(read_toml(path))
