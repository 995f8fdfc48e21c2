"""Scene files: a `Scene` described in TOML, with units on every quantity.

A scene file has three sections whose keys are named as the constructors' arguments:

```toml
[barrier]
plastic_moment   = "105.5 kN*m"     # M0, force x length
mass_per_length  = "34.2 kg/m"      # m
backing_strength = "60 kN/m"        # q0, force per length
# axial_capacity = "1.5 MN"         # N0 (report 3.4), optional

[vehicle]
mass        = "2270 kg"             # M
crush_force = "450 kN"              # P0

[impact]
speed    = "40 km/h"
angle    = "90 deg"                 # optional, default 90 deg (normal impact)
friction = 0.0                      # optional, dimensionless, default 0
```

Quantities are strings parsed by pint, in any units of the right kind ("1e6 lbf*in",
"0.2 lbf*s**2/in**2", "25 mph" as in the report's inch-pound-second units); each is
converted once to SI (N*m, kg/m, N/m, N, kg, m/s; the angle to degrees). A bare number
is refused: the file must say its units. Every error is a `SceneFileError` (a
`ValueError`) whose one-line message starts with the offending key, e.g.

    [barrier] plastic_moment: expected a moment (force*length), got '100 kg'

The default scene
-----------------
`default_scene()` loads `barrierjax/default_scene.toml`: a steel-tube barrier on a foam
backing struck normally by a MASH 2270P pickup. Its parameters and their sources (the
same notes are comments in the file):

- Beam: HSS 203x152x6.4 (8x6x1/4 in) tube, ASTM A500 Grade C, Fy = 345 MPa (50 ksi,
  A500 Grade C for shaped tubes). Bent about its strong axis (203 mm deep in the
  direction of the impact, the 152 mm face towards the traffic and the foam). Nominal wall
  t = 6.35 mm, sharp corners:
  Z = (152.4 x 203.2^2 - 139.7 x 190.5^2) / 4 = 3.057e5 mm^3 = 3.057e-4 m^3, so
  M0 = Fy Z = 345 MPa x 3.057e-4 m^3 = 105.5 kN*m. (The AISC design wall 0.93 t and the
  rounded corners give a somewhat smaller Z; the nominal value is kept.)
  Area A = 152.4 x 203.2 - 139.7 x 190.5 = 4355 mm^2, m = 7850 kg/m^3 x A = 34.2 kg/m
  (AISC lists 22.37 lb/ft = 33.3 kg/m with the design wall).
- Backing: rigid closed-cell polyurethane foam of about 48 kg/m^3 (3 lb/ft^3), whose
  crushing plateau is of order 0.4 MPa in manufacturers' data, over the 0.152 m face:
  q0 = 0.4 MPa x 0.152 m = 61 kN/m, taken as 60 kN/m. (The same q0 is 0.3 MPa over a
  0.2 m bearing height.)
- Vehicle: the MASH 2270P pickup (AASHTO Manual for Assessing Safety Hardware), M =
  2270 kg. Mean crush force P0 = kinetic energy / crush of a full-frontal rigid-wall test
  at 56 km/h (35 mph, as in NCAP) with about 0.6 m of crush:
  0.5 x 2270 kg x (15.56 m/s)^2 / 0.6 m = 275 kJ / 0.6 m = 458 kN, taken as 450 kN.
- Impact: MASH test level 3 strikes at 100 km/h and 25 degrees; its normal component is
  100 sin 25 deg = 42.3 km/h, taken as 40 km/h, normal (90 deg), no friction.

Scales and groups: L = 2 (M0/q0)^(1/2) = 2.652 m, P_b = 4 (M0 q0)^(1/2) = 318.2 kN,
t0 = m^(1/2) M0^(1/4) / q0^(3/4) = 27.5 ms; mu = M/(m L) = 25.0, phi = P0/P_b = 1.414,
V0 = v t0 / L = 0.115. `barrierjax run` gives a deflection of about 0.41 m.
"""

from __future__ import annotations

import importlib.resources
import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from . import units
from .scene import Barrier, Impact, Scene, Vehicle

__all__ = [
    "FIELDS",
    "SceneFileError",
    "default_scene",
    "default_scene_path",
    "field_key",
    "load_scene",
    "parse_quantity",
    "parse_scene",
]


@dataclass(frozen=True)
class Field:
    """One key of a scene file: where it goes and what it must be.

    `dimension` is a pint dimensionality ("[force]*[length]"), "angle", or None for a
    dimensionless number; `unit` is the unit the value is converted to (SI, or degrees);
    `parameter` is the constructor's argument; `kind` and `example` word the errors."""

    section: str
    key: str
    parameter: str
    kind: str
    dimension: str | None
    unit: str
    example: str
    required: bool = True

    @property
    def constructor_name(self) -> str:
        """How the constructors name this field in their errors: "Barrier.plastic_moment"."""
        return f"{self.section.capitalize()}.{self.parameter}"


FIELDS: dict[str, dict[str, Field]] = {
    "barrier": {
        "plastic_moment": Field(
            "barrier",
            "plastic_moment",
            "plastic_moment",
            "a moment (force*length)",
            "[force]*[length]",
            "N*m",
            "100 kN*m",
        ),
        "mass_per_length": Field(
            "barrier",
            "mass_per_length",
            "mass_per_length",
            "a mass per length",
            "[mass]/[length]",
            "kg/m",
            "60 kg/m",
        ),
        "backing_strength": Field(
            "barrier",
            "backing_strength",
            "backing_strength",
            "a force per length",
            "[force]/[length]",
            "N/m",
            "60 kN/m",
        ),
        "axial_capacity": Field(
            "barrier",
            "axial_capacity",
            "axial_capacity",
            "a force",
            "[force]",
            "N",
            "1.5 MN",
            required=False,
        ),
    },
    "vehicle": {
        "mass": Field("vehicle", "mass", "mass", "a mass", "[mass]", "kg", "2270 kg"),
        "crush_force": Field(
            "vehicle", "crush_force", "crush_force", "a force", "[force]", "N", "450 kN"
        ),
    },
    "impact": {
        "speed": Field(
            "impact",
            "speed",
            "speed",
            "a speed (length/time)",
            "[length]/[time]",
            "m/s",
            "40 km/h",
        ),
        "angle": Field(
            "impact",
            "angle",
            "angle_deg",
            "an angle",
            "angle",
            "deg",
            "90 deg",
            required=False,
        ),
        "friction": Field(
            "impact",
            "friction",
            "friction",
            "a dimensionless number",
            None,
            "",
            "0.1",
            required=False,
        ),
    },
}

# "Barrier.plastic_moment" (as the constructors and `simulate` name a field) -> Field.
_BY_CONSTRUCTOR_NAME = {
    field.constructor_name: field for section in FIELDS.values() for field in section.values()
}


class SceneFileError(ValueError):
    """A scene file that cannot be read; `section` and `key` name the culprit (either may
    be None), and the message is one line that starts with them."""

    def __init__(self, section: str | None, key: str | None, message: str):
        self.section, self.key = section, key
        where = ""
        if section is not None:
            where = f"[{section}]" + (f" {key}" if key is not None else "")
        elif key is not None:
            where = key
        text = " ".join(str(message).split())  # one line, whatever the message held
        super().__init__(f"{where}: {text}" if where else text)


def field_key(message: str) -> Field | None:
    """The scene-file `Field` that a library error message names ("Impact.angle_deg ...",
    as the constructors and `simulate` name their fields), or None."""
    for name, field in _BY_CONSTRUCTOR_NAME.items():
        if re.search(rf"\b{re.escape(name)}\b", message):
            return field
    return None


def _is_angle(quantity) -> bool:
    """Angles are dimensionless in pint; accept only units that reduce to the radian."""
    root = units.registry().get_root_units(quantity.units)[1]
    return str(root) == "radian"


def parse_quantity(value, field: Field) -> float:
    """The number `value` (a string with units, or for a dimensionless field a number)
    stands for, in `field.unit`. Raises `SceneFileError` naming the field."""

    def fail(message):
        return SceneFileError(field.section, field.key, message)

    expected = f"expected {field.kind}"
    if isinstance(value, bool) or not isinstance(value, (str, int, float)):
        form = "a number" if field.dimension is None else f"a string like '{field.example}'"
        raise fail(f"{expected} as {form}, got a TOML {type(value).__name__} {value!r}")
    if isinstance(value, (int, float)):
        if field.dimension is not None:
            raise fail(
                f"{expected} with units (e.g. '{field.example}'), got a bare number {value!r}"
            )
        return float(value)
    try:
        quantity = units.registry().Quantity(value)
        float(quantity.magnitude)  # complex or array magnitudes fail here
    except Exception:  # pint raises many kinds (UndefinedUnitError, AssertionError, ...)
        raise fail(
            f"{expected}, got '{value}', which is not a quantity (write e.g. '{field.example}')"
        ) from None
    if field.dimension is None:
        # A dimensionless number; an angle is dimensionless to pint but not a friction.
        if not quantity.dimensionless or (not quantity.unitless and _is_angle(quantity)):
            raise fail(f"{expected}, got '{value}'")
        return float(quantity.to("dimensionless").magnitude)
    if quantity.unitless:
        raise fail(f"{expected} with units (e.g. '{field.example}'), got a bare number '{value}'")
    if field.dimension == "angle":
        ok = quantity.dimensionless and _is_angle(quantity)
    else:
        ok = quantity.check(field.dimension)
    if not ok:
        raise fail(f"{expected}, got '{value}'")
    magnitude = float(quantity.to(field.unit).magnitude)
    if math.isnan(magnitude):
        raise fail(f"{expected}, got '{value}', which is not a number")
    return magnitude


def parse_scene(data: Mapping) -> Scene:
    """Build a `Scene` from a scene file's tables (as `tomllib` reads them), converting
    every quantity to SI. Raises `SceneFileError` naming the first bad section or key:
    missing, unknown, of the wrong kind or dimension, or refused by the constructor."""
    if not isinstance(data, Mapping):
        got = type(data).__name__
        raise SceneFileError(None, None, f"a scene is a table of sections, got {got}")
    for section in data:
        if section not in FIELDS:
            raise SceneFileError(section, None, f"unknown section (expected {_names(FIELDS)})")
    values: dict[str, dict[str, float]] = {}
    raw: dict[tuple[str, str], object] = {}
    for section, fields in FIELDS.items():
        if section not in data:
            raise SceneFileError(section, None, "missing section")
        table = data[section]
        if not isinstance(table, Mapping):
            raise SceneFileError(section, None, f"expected a table, got {table!r}")
        for key in table:
            if key not in fields:
                raise SceneFileError(
                    section, key, f"unknown key (expected one of {_names(fields)})"
                )
        values[section] = {}
        for key, field in fields.items():
            if key not in table:
                if field.required:
                    raise SceneFileError(
                        section, key, f"missing (expected {field.kind}, e.g. '{field.example}')"
                    )
                continue
            raw[section, key] = table[key]
            values[section][field.parameter] = parse_quantity(table[key], field)
    parts = {}
    for section, cls in (("barrier", Barrier), ("vehicle", Vehicle), ("impact", Impact)):
        try:
            parts[section] = cls(**values[section])
        except ValueError as error:
            field = field_key(str(error))
            if field is None:
                raise SceneFileError(section, None, str(error)) from None
            # "Barrier.plastic_moment must be ..." -> "must be ..."
            rest = str(error).removeprefix(field.constructor_name).strip()
            given = raw.get((field.section, field.key))
            if isinstance(given, str):
                rest += f" ({field.unit or 'dimensionless'}; from '{given}')"
            raise SceneFileError(field.section, field.key, rest) from None
    return Scene(parts["barrier"], parts["vehicle"], parts["impact"])


def read_toml(path) -> Mapping:
    """The tables of the TOML file at `path`. Raises `SceneFileError` for an unreadable
    file or invalid TOML."""
    path = Path(path)
    try:
        with path.open("rb") as file:
            return tomllib.load(file)
    except FileNotFoundError:
        raise SceneFileError(None, str(path), "no such file") from None
    except OSError as error:
        raise SceneFileError(None, str(path), error.strerror or str(error)) from None
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as error:
        raise SceneFileError(None, str(path), f"invalid TOML: {error}") from None


def load_scene(path) -> Scene:
    """Read the TOML scene file at `path` (see the module docstring) as a `Scene` in SI
    units. Raises `SceneFileError` for an unreadable file, invalid TOML or a bad key."""
    return parse_scene(read_toml(path))


def default_scene_path():
    """The packaged default scene file (a `Traversable`; see the module docstring)."""
    return importlib.resources.files("barrierjax") / "default_scene.toml"


def default_scene() -> Scene:
    """The default scene: a steel tube on foam struck normally by a 2270 kg pickup at
    40 km/h (parameters and sources in the module docstring)."""
    with importlib.resources.as_file(default_scene_path()) as path:
        return load_scene(path)


def _names(mapping) -> str:
    return ", ".join(mapping)
