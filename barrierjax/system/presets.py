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


# Dimensions no source read for this project gives, estimated from typical test cars of
# each class (overall length, width, wheelbase, front overhang, c.g. aft of the front axle,
# track; m): the EN 1317 cars after the small, lower-medium and large family cars that test
# houses use for TB11, TB2x/TB31 and TB32; NCHRP 350's after the Geo Metro (820C) and the
# Chevrolet C2500 (2000P) its text names as typical.
_TYPICAL = {
    "car 900": (3.6, 1.6, 2.4, 0.65, 0.90, 1.35),
    "car 1300": (4.0, 1.7, 2.55, 0.8, 1.10, 1.40),
    "car 1500": (4.6, 1.75, 2.7, 0.9, 1.24, 1.50),
    "820C": (3.75, 1.6, 2.30, 0.75, 0.85, 1.35),
    "2000P": (5.35, 1.95, 3.35, 0.80, 1.40, 1.65),
    "1100C": (None, None, None, None, None, 1.47),
    "2270P": (None, None, None, None, None, 1.70),
}
_FIELDS = ("overall_length_m", "overall_width_m", "wheelbase_m", "front_overhang_m",
           "cg_behind_front_axle_m", "track_width_m")  # fmt: skip


def _dimension(d: sources.VehicleData, field: str, table: str) -> Value:
    given = getattr(d, field)
    if given is not None:
        unconfirmed = field in d.source.unconfirmed
        return Value(given, table + (" (unconfirmed in the corpus)" if unconfirmed else ""))
    typical = _TYPICAL[d.name][_FIELDS.index(field)]
    return Value(typical, f"estimate: a typical {d.name} test vehicle ({table} gives none)", True)


def _vehicle(name, yaw_inertia: Value, crush: tuple[Value, Value]) -> Preset:
    d = sources.VEHICLES[name]
    table = f"{d.source.document} {d.source.clause} via barrierjax.system.sources.VEHICLES"
    length, width, wheelbase, overhang, cg_aft, track = (
        _dimension(d, field, table) for field in _FIELDS
    )
    fields = {
        "mass": Value(d.mass_kg, table),
        "yaw_inertia": yaw_inertia,
        "length": length,
        "width": width,
        "front_to_cg": Value(overhang.value + cg_aft.value, "front overhang + c.g. aft of the "
                             "front axle", overhang.estimate or cg_aft.estimate),
        "cg_to_front_axle": cg_aft,
        "wheelbase": wheelbase,
        "track": track,
        "crush_stiffness": crush[0],
        "crush_strength": crush[1],
        "tyre_friction": Value(
            0.5,
            "estimate: side friction of tyres sliding on a dry road "
            "surface with the wheels free, below the ~0.7-0.8 peak",
            True,
        ),
    }  # fmt: skip
    return Preset(name, f"{d.standard.upper()} {name}", fields)


# The 2270P's yaw inertia: NCAC measured the pitch inertia of the 2007 Silverado quad cab
# (2337 kg): 6158 kg m^2 (NCAC 2007-T-006 Table 2). For a body as wide as it is tall the two
# are alike (a box: I_zz - I_yy = m (b^2 - h^2) / 12); scaled to 2270 kg: 5980 kg m^2.
_PICKUP_YAW = Value(6158.0 * 2270.0 / 2337.0, "estimate: the 2007 Silverado's measured pitch "
                    "inertia (NCAC 2007-T-006 Table 2), scaled to 2270 kg, as its yaw inertia",
                    True)  # fmt: skip
_PICKUP_LENGTH = sources.VEHICLES["2270P"].overall_length_m


def _scaled_yaw(name) -> Value:
    """The 2270P's yaw inertia scaled by mass times length squared."""
    d = sources.VEHICLES[name]
    length = d.overall_length_m or _TYPICAL[name][0]
    value = _PICKUP_YAW.value * (d.mass_kg / 2270.0) * (length / _PICKUP_LENGTH) ** 2
    return Value(value, "estimate: the 2270P's, scaled by mass times length squared", True)


# Crush: the default scene's mean frontal crush force of a 2270P, 450 kN (a 56 km/h
# rigid-wall test with about 0.6 m of crush: barrierjax/default_scene.toml), over its
# 1.98 m width: 227 kN per metre of periphery; elastic up to 50 mm of crush. The other
# vehicles' in proportion to their masses.
_PICKUP_CRUSH = (
    Value(227e3 / 0.05, "estimate: the crush strength reached at 50 mm of crush", True),
    Value(227e3, "estimate: the default scene's 2270P crush force, 450 kN, over the width", True),
)


def _scaled_crush(name) -> tuple[Value, Value]:
    share = sources.VEHICLES[name].mass_kg / 2270.0
    return tuple(Value(v.value * share, v.source + ", scaled by mass", True)
                 for v in _PICKUP_CRUSH)  # fmt: skip


VEHICLES = {
    "2270P": _vehicle("2270P", _PICKUP_YAW, _PICKUP_CRUSH),
    **{
        name: _vehicle(name, _scaled_yaw(name), _scaled_crush(name))
        for name in ("1100C", "2000P", "820C", "car 900", "car 1300", "car 1500")
    },
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

# G4(1S): the same rail on W6x9 posts at the same spacing, 6x8 in blockouts, the rail's top
# at 27.75 in with splices at the posts (sources.BARRIERS['g4_1s']). A planar model sees
# none of what sets it apart from the MGS (the rail's height, the splices' place, the
# blockouts' depth, the wheels snagging on posts): its preset is the MGS's, posts included.
G4_1S = Preset(
    "G4(1S)",
    "modified G4(1S) strong-post W-beam: 12-gauge W-beam at 27.75 in, W6x9 posts at 6 ft "
    "3 in, 6x8 in blockouts (MwRSF 2214WB-1); in plan the MGS's values",
    {key: Value(v.value, v.source + " (as the MGS: in plan the two differ by nothing the "
                "model holds)", v.estimate) for key, v in MGS.fields.items()},
)  # fmt: skip


def _scaled_rail(developed_width_in, note):
    """A 12-gauge corrugated rail's area and second moment for lateral bending from the
    W-beam's, in proportion to its developed (blank) width (the same corrugation depth)."""
    ratio = developed_width_in / 19.0  # the W-beam's: 1.99 in^2 / 0.105 in
    return {
        "rail_area": Value(1.99 * _IN**2 * ratio, f"estimate: {note}", True),
        "rail_second_moment": Value(2.31 * _IN**4 * ratio, f"estimate: {note}", True),
    }


THRIE_BEAM = Preset(
    "thrie-beam",
    "12-gauge thrie beam on W6x9 strong posts at 6 ft 3 in (no source read gives its "
    "section, posts or anchorage: sources.BARRIERS['thrie_beam'])",
    MGS.fields | _scaled_rail(29.0, "the W-beam's, scaled by the thrie beam's developed width "
                              "(about 29 in against 19 in; recalled, not read)"),
)  # fmt: skip

# Box beam (G3): a 6x6x3/16 in steel tube on S3x5.7 weak posts at 6 ft; the tube's section
# (A 3.98 in^2, I 22.3 in^4: an HSS 6x6x3/16's, recalled), the posts' (weak posts yield and
# release the rail early) all estimates: no source read gives them (sources.py).
BOX_BEAM = Preset(
    "box beam",
    "G3 box beam: a 6x6x3/16 in steel tube on S3x5.7 weak posts at 6 ft (every value an "
    "estimate: sources.BARRIERS['box_beam'])",
    MGS.fields | {
        "post_spacing": Value(6 * 12 * _IN, "estimate: G3's 6 ft (recalled, not read)", True),
        "rail_area": Value(3.98 * _IN**2, "estimate: HSS 6x6x3/16, 3.98 in^2 (recalled)", True),
        "rail_second_moment": Value(22.3 * _IN**4, "estimate: HSS 6x6x3/16, 22.3 in^4 "
                                    "(recalled)", True),
        "yield_stress": Value(46e3 * 6894.757, "estimate: ASTM A500 grade B tube, 46 ksi "
                              "(recalled)", True),
        "post_stiffness": Value(0.5e6, "estimate: an S3x5.7 weak post in soil", True),
        "post_strength": Value(10e3, "estimate: an S3x5.7 weak post bending at the ground", True),
        "post_failure": Value(0.15, "estimate: the rail's release from a weak post", True),
    },
)  # fmt: skip

BARRIERS = {
    "MGS": MGS,
    "G4(1S)": G4_1S,
    "thrie-beam": THRIE_BEAM,
    "box beam": BOX_BEAM,
    "rigid wall": Preset("rigid wall", "an immovable wall, y = 0"),
}

RAIL_FRICTION = Value(0.3, "estimate: vehicle sheet metal sliding on a galvanised W-beam", True)
