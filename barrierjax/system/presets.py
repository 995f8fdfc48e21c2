"""Presets of the system model: test vehicles and barriers, each value with where it comes
from. The published data (`sources.py`) fix the masses, the MASH vehicles' dimensions, the
MGS layout and the W-beam's thickness and strength; what no source read for this project
gives (yaw inertias, the W-beam's section properties, the posts' force-deflection in soil,
the vehicles' crush springs, the friction) is an estimate, derived in its note and flagged
`estimate`. Compare the model with full-scale tests only with these flags in mind.
"""

from dataclasses import dataclass, field

from . import sources

_IN = 0.0254


@dataclass(frozen=True)
class Value:
    """A preset's number (SI) and where it comes from; `estimate`: no source gives it."""

    value: float
    source: str
    estimate: bool = False


@dataclass(frozen=True)
class Preset:
    name: str
    description: str
    fields: dict = field(default_factory=dict)  # key -> Value

    def values(self) -> dict:
        """The constructor's keyword arguments, SI."""
        return {key: v.value for key, v in self.fields.items()}

    def estimates(self) -> list[str]:
        return [key for key, v in self.fields.items() if v.estimate]


def _mash(name) -> sources.VehicleData:
    return sources.VEHICLES[name]


def _vehicle(name, yaw_inertia: Value, track: Value, crush: tuple[Value, Value]) -> Preset:
    d = _mash(name)
    table = f"MASH 2016 Table 4-1 via barrierjax.system.sources.VEHICLES[{name!r}]"
    front_to_cg = d.front_overhang_m + d.cg_behind_front_axle_m
    fields = {
        "mass": Value(d.mass_kg, table),
        "yaw_inertia": yaw_inertia,
        "length": Value(d.overall_length_m, table + " (length unconfirmed in the corpus)"),
        "width": Value(d.overall_width_m, table + " (width unconfirmed in the corpus)"),
        "front_to_cg": Value(
            front_to_cg,
            table + ": front overhang + c.g. aft of the front "
            "axle (both unconfirmed in the corpus)",
        ),
        "cg_to_front_axle": Value(d.cg_behind_front_axle_m, table + " (unconfirmed)"),
        "wheelbase": Value(d.wheelbase_m, table),
        "track": track,
        "crush_stiffness": crush[0],
        "crush_strength": crush[1],
        "tyre_friction": Value(
            0.5,
            "estimate: side friction of tyres sliding on a dry road "
            "surface with the wheels free, below the ~0.7-0.8 peak",
            True,
        ),
    }
    return Preset(name, f"MASH {name}", fields)


# The 2270P's yaw inertia: NCAC measured the pitch inertia of the 2007 Silverado quad cab
# (2337 kg): 6158 kg m^2 (NCAC 2007-T-006 Table 2). For a body as wide as it is tall the two
# are alike (a box: I_zz - I_yy = m (b^2 - h^2) / 12); scaled to 2270 kg: 5980 kg m^2.
_PICKUP_YAW = Value(6158.0 * 2270.0 / 2337.0, "estimate: the 2007 Silverado's measured pitch "
                    "inertia (NCAC 2007-T-006 Table 2), scaled to 2270 kg, as its yaw inertia",
                    True)  # fmt: skip
# The 1100C's: the 2270P's scaled by M L^2 (169 / 237 in long): 1480 kg m^2.
_CAR_YAW = Value(_PICKUP_YAW.value * (1100 / 2270) * (169 / 237) ** 2, "estimate: the "
                 "2270P's, scaled by mass times length squared", True)  # fmt: skip
# Crush: the default scene's mean frontal crush force of a 2270P, 450 kN (a 56 km/h
# rigid-wall test with about 0.6 m of crush: barrierjax/default_scene.toml), over its
# 1.98 m width: 227 kN per metre of periphery; elastic up to 50 mm of crush. The 1100C's
# in proportion to its mass.
_PICKUP_CRUSH = (
    Value(227e3 / 0.05, "estimate: the crush strength reached at 50 mm of crush", True),
    Value(227e3, "estimate: the default scene's 2270P crush force, 450 kN, over the width", True),
)
_CAR_CRUSH = tuple(Value(v.value * 1100 / 2270, v.source + ", scaled by mass", True)
                   for v in _PICKUP_CRUSH)  # fmt: skip

VEHICLES = {
    "2270P": _vehicle(
        "2270P",
        _PICKUP_YAW,
        Value(1.70, "estimate: a full-size pickup's track (MASH lists none)", True),
        _PICKUP_CRUSH,
    ),
    "1100C": _vehicle(
        "1100C", _CAR_YAW, Value(1.47, "estimate: a small sedan's track", True), _CAR_CRUSH
    ),
}

# 12-gauge W-beam (AASHTO M180 Class A): 2.67 mm, yield 345 MPa (confirmed, sources.py).
# Its area and second moment about the vertical axis (lateral bending) are the figures
# commonly tabulated for it, 1.99 in^2 and 2.31 in^4, recalled, not read in the corpus.
_W_BEAM = sources.BARRIERS["mgs"].rail
_POST_NOTE = ("estimate: W6x8.5/W6x9 strong posts in strong soil, 40 in embedment: bogie tests "
              "of such posts are reported at roughly 40-50 kN of resistance (not read in the "
              "corpus: MwRSF post reports 10, 217, 244 hold the curves)")  # fmt: skip

MGS = Preset(
    "MGS",
    "Midwest Guardrail System: 12-gauge W-beam at 31 in, W6x8.5 posts at 6 ft 3 in, 12 in "
    "blockouts (MwRSF TRP-03-235-11)",
    {
        "post_spacing": Value(75 * _IN, "MwRSF TRP-03-235-11 (sources.BARRIERS['mgs'])"),
        "rail_area": Value(1.99 * _IN**2, "estimate: 12-gauge W-beam, 1.99 in^2 (tabulated "
                           "value, recalled, not read in the corpus)", True),
        "rail_second_moment": Value(2.31 * _IN**4, "estimate: 12-gauge W-beam, 2.31 in^4 "
                                    "(recalled, not read in the corpus)", True),
        "elastic_modulus": Value(200e9, "steel"),
        "yield_stress": Value(_W_BEAM.yield_pa, "AASHTO M180 Class A, 50 ksi (sources.py)"),
        "density": Value(7850.0, "steel"),
        "post_stiffness": Value(1.5e6, _POST_NOTE + "; the peak at about 30 mm", True),
        "post_strength": Value(45e3, _POST_NOTE, True),
        "post_failure": Value(0.4, "estimate: the rail's release from a post pushed over "
                              "about 0.4 m (bolt pull-through)", True),
        "post_longitudinal_stiffness": Value(0.5e6, "estimate: weak-axis bending", True),
        "post_longitudinal_strength": Value(15e3, "estimate: weak-axis bending", True),
        "anchor_stiffness": Value(1e7, "estimate: an end anchorage of a few mm under tens of "
                                  "kN", True),
    },
)  # fmt: skip

BARRIERS = {"MGS": MGS, "rigid wall": Preset("rigid wall", "an immovable wall, y = 0")}

RAIL_FRICTION = Value(0.3, "estimate: vehicle sheet metal sliding on a galvanised W-beam", True)
