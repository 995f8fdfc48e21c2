"""Published data for the vehicle-guardrail system model (BARRIER VII's problem), each value
with its source: test vehicles (`VEHICLES`), the crushable periphery BARRIER VII and later
work used (`VEHICLE_CRUSH`), rails and posts (`BARRIERS`); the full-scale crash tests to
compare with and the published cost of finite-element runs are in `full_scale.py`.

How confirmed. Every record carries a `Source` (from `assess.matrices`): the document and
table or page, the keys of `REFERENCES` where the value was read (`confirmed_by`), and the
fields that no page read for this module repeats (`unconfirmed`). The pages were read as
stored excerpts (search results), not as whole reports: a value is "confirmed" only where the
excerpt itself printed it. Fields held as None were not found; they are not guesses. Values
recalled from the standards but not seen in an excerpt are kept (so the model has a nominal
figure) and are listed in `unconfirmed`; check them against the standard before relying on
them. In particular no measured yaw inertia was confirmed for any test vehicle (only the
2007 Silverado's pitch inertia), no W-beam section property beyond thickness and strength,
and no post force-deflection number: see the notes on each record.

Units: SI (kg, m, s, N, Pa, J); the printed value and its unit are kept in `printed` or in a
comment. Angles in degrees in fields named `..._deg`.
"""

from dataclasses import dataclass

from ..assess.matrices import Source

_IN = 0.0254  # m per in
_FT = 0.3048  # m per ft
_LB = 0.45359237  # kg per lb
_MPH = 0.44704  # m/s per mi/h
_KSI = 6.894757e6  # Pa per ksi
_SLUG_FT2 = 1.3558179  # kg m^2 per (lbf ft s^2) = slug ft^2


def source(document: str, clause: str, confirmed_by: str = "", unconfirmed: str = "") -> Source:
    return Source(document, clause, tuple(confirmed_by.split()), tuple(unconfirmed.split()))


# Where values were read. Each entry: what it is, and its address.
REFERENCES = {
    "ncac_2007_t006": "NCAC (2007), Technical Summary NCAC 2007-T-006, NCAC Vehicle Model "
    "Development Update: Pick-up Truck Modeling, Tables 1-2 (2007 Chevrolet Silverado quad cab: "
    "2337 kg, wheelbase 144 in, CG 27.96 in; pitch inertia 4542 ft-lb-s^2; the yaw value is cut "
    "off in the stored copy). https://zh.scribd.com/document/263062128/NCAC-2007-T-006",
    "ncac_2009_w005": "Mohan, Ritter, Marzougui, Brown, Kan, Opiela (2009), Modeling, Testing, "
    "and Validation of the 2007 Chevy Silverado Finite Element Model, NCAC 2009-W-005 (abstract "
    "only read). https://pt.scribd.com/document/52739681/Suspension-tests",
    "nap27896": "National Academies (2024), Development of a MASH Barrier to Shield Pedestrians, "
    "Bicyclists, and Other Vulnerable Users from Motor Vehicles, doi:10.17226/27896, ch. 11, "
    "Table 65 (MASH 2270P: inertial weight 5000 +-110 lb, wheelbase 148 +-12 in). "
    "https://www.nationalacademies.org/read/27896/chapter/13",
    "m180": "AASHTO M 180-00, Corrugated Sheet Steel Beams for Highway Guardrail, 3.1 (Class A "
    "2.67 mm (0.105 in); Type II zinc 1100 g/m^2). "
    "https://www.scribd.com/document/445080626/AASHTO-M-180-pdf",
    "m180_mech": "guardrailbarrier.org, Guardrail Barrier Complies with AASHTO M-180 (beams: "
    "yield min 345 MPa (50 ksi), tensile min 483 MPa (70 ksi), elongation in 50 mm min 12 %). "
    "https://www.guardrailbarrier.org/guardrail-barrier/guardrail-barrier.html",
    "nchrp_26811": "NCHRP (2023), Investigation of Material Requirements for Highway Guardrail "
    "Systems (nap 26811), p. 43: proposed steel-post yield min 36 ksi (250 MPa), A36. "
    "https://nap.nationalacademies.org/skim.php?record_id=26811&chap=39-69",
    "mwrsf_qa_280": "MwRSF Q&A 280 (2010), MGS Working Width and Dynamic Deflection: test "
    "2214MG-1 working width 57.3 in, dynamic deflection 57.0 in. "
    "http://mwrsf-qa.unl.edu/view.php?id=280",
    "mwrsf_qa_1105": "MwRSF Q&A 1105 (2016), MGS Deflection Reduction: NCHRP 350 TL-3 MGS at "
    "1/4 post spacing, dynamic deflection 17.6 in, working width 36.7 in. "
    "http://mwrsf-qa.unl.edu/view.php?id=1105",
    "mwrsf_qa_32949": "MwRSF Q&A 32949 (2025): MGS on 2:1 slope, 1/2 post spacing, 7-ft posts: "
    "dynamic deflection 27.2 in, working width 47.7 in; strong-post culvert MGS at 1/2 spacing: "
    "29.6 in and 50.8 in. https://mwrsf.unl.edu/q&a/view.php?id=32949",
    "mwrsf_499": "MwRSF, Evaluation of the MGS with Half Post Spacing and 7-ft Posts Adjacent to "
    "Slope, TRP-03-452-24 (abstract): MGS7S-1 1100C 62.8 mi/h 25.2 deg; MGS7S-2 2270P 62.6 mi/h "
    "25.4 deg; both contained and redirected, MASH 2016 TL-3 met. "
    "https://dev-mwrsf.unl.edu/reportResult.php?reportId=499",
    "mwrsf_140": "Lechtenberg, Faller, Sicking, Rohde, Bielenberg, Reid, Performance Evaluation "
    "of the Modified G4(1S) Guardrail - Update to NCHRP 350 Test No. 3-11 (2214WB-1) (abstract): "
    "3/4-ton two-door 2270P, top rail height 706 mm (27.75 in), unacceptable. "
    "https://mwrsf.unl.edu/reportResult.php?reportId=140",
    "faller_2007": "Faller, Sicking, Bielenberg, Rohde, Polivka, Reid, Performance of Steel-Post, "
    "W-Beam Guardrail Systems, TRR 2025 (2007) (abstract): modified G4(1S) at 706 mm passed "
    "with the 1/2-ton four-door 2270P, failed with the 3/4-ton two-door; MGS passed 3-10 and "
    "3-11 with both pickups. https://nebraska.pure.elsevier.com/en/publications/"
    "performance-of-steel-post-w-beam-guardrail-systems",
    "mwrsf_26": "McGhee, Faller, Rohde, Lechtenberg, Sicking, Reid (2012), Development of an "
    "Economical Guardrail System for use on Wire-Faced, MSE Walls, TRP-03-235-11 (abstract): "
    "standard MGS has 6-ft (1.8-m) W6x8.5 (W152x12.6) posts, mid-span splices, 31-in (787-mm) "
    "top height, 75-in (1,905-mm) spacing, 12-in (305-mm) blockouts. "
    "https://mwrsf.unl.edu/reportResult.php?reportId=26",
    "mwrsf_10": "Schmidt, Mongiardini, Bielenberg, Lechtenberg, Reid, Faller, Dynamic Testing of "
    "MGS W6x8.5 Posts at Decreased Embedment (abstract): standard embedment 40 in (1,016 mm), "
    "load height 24 7/8 in (632 mm); W6x9 = W152x13.4. "
    "http://mwrsf.unl.edu/reportResult.php?reportId=10",
    "mwrsf_217": "Coon, Reid, Rohde, Dynamic Impact Testing of Guardrail Posts Embedded in Soil "
    "(abstract): W6x9 and W6x16 steel and 6x8 in wood posts, bogie at 5.5, 8.9, 13.4 m/s; no "
    "measurable rate effect between 8.9 and 13.4 m/s. "
    "https://mwrsf.unl.edu/reportResult.php?reportId=217",
    "mwrsf_244": "Kuipers, Reid, Testing of W152x23.8 (W6x16) Steel Posts - Soil Embedment Depth "
    "Study for the MGS (abstract): 40-in embedment chosen; posts at 37 in or less pulled out. "
    "http://mwrsf.unl.edu/reportResult.php?reportId=244",
    "rpf_262": "Roadside Pooled Fund, 31-inch Non-Blocked MGS, TRP-03-262-12 (MASH 3-10, 3-11, "
    "pass; 181 ft-3 in (55.25 m) of 12-gauge (2.66-mm) W-beam; 75-in spacing). "
    "https://www.roadsidepooledfund.org/longitudinal-barrier/31-inch-non-blocked-midwest-"
    "guardrail-system-mgs/",
    "rpf_433": "Roadside Pooled Fund, MGS with Curb and Omitted Post, TRP-03-433-21 (MASH 2016 "
    "3-11, pass; W6x8.5 posts, 75-in spacing, 31 in). https://www.roadsidepooledfund.org/"
    "longitudinal-barrier/mgs-with-curb-and-omitted-post-evaluation-to-mash-2016-test-no-3-11/",
    "rpf_flare": "Roadside Pooled Fund / TTI 609971, Testing and Evaluation of Flared MGS System "
    "at MASH TL-3 Conditions (did not meet MASH TL-3). https://www.roadsidepooledfund.org/"
    "testing-and-evaluation-of-flared-mgs-system-at-mash-test-level-3-conditions-609971-t4541-cv/",
    "reid_2009": "Reid (2009), Approach Slopes for Midwest Guardrail System, J. Transp. Safety & "
    "Security 1(1) 32-45, doi:10.1080/19439960902735212 (abstract): NCHRP 350 pickup 100.4 km/h "
    "25.9 deg, small car 99.6 km/h 21.6 deg, both passed. https://safetylit.org/unapi/"
    "conversion.php?export=bib&id=ct%2Acitjournalarticle_96794_19",
    "bligh_sicking_1989": "Bligh, Sicking, Applications of BARRIER VII in Design of Flexible "
    "Barriers, TRR 1233 (1989) 117-123 (abstract and opening read; no input numbers seen). "
    "https://documents.pub/document/applications-of-barrier-vii-in-design-of-flexible-research-"
    "record-1233-117-applications.html",
    "kansas_b7": "Development of Kansas Guardrail to Bridgerail Transition Designs Using BARRIER "
    "VII, TRR 1233 (1989) 145-154 (TRID 308833 abstract): 4,500-lb 1977 Plymouth, 60 mi/h, 25 "
    "deg; vehicle crush and post stiffness calibrated on crash tests. "
    "http://trid.trb.org/view.aspx?id=308833",
    "zaouk_c1500": "Zaouk, Bedewi, Kan, Marzougui, Validation of a Non-Linear Finite Element "
    "Vehicle Model Using Multiple Impact Data (NCAC, 1994 C-1500 model): roadside-hardware "
    "impacts need simulations lasting as long as 1 s versus <=150 ms for frontal crashes. "
    "https://deploy.doczz.net/doc/438517/validation-of-a-non-linear-finite-element-vehicle-model",
    "kondo_2008": "Kondo, Makino (2008), Crash Simulation of Large-Number-of-Elements Car Model "
    "by LS-DYNA on Highly Parallel Computers, Fujitsu Sci. Tech. J. 44(4) 467-474 (abstract): "
    "10-million-element model on up to 512 processors. https://dokumen.tips/documents/crash-"
    "simulation-of-large-number-of-elements-car-crash-simulation-of-large-number-of-elements.html",
    "npac_crash": "NPAC/Fox et al. (c. 1999), Applications of Parallel High Performance Computing "
    "in Car Crash Simulation: several seconds of car crash may take several weeks of workstation "
    "time. https://infomall.org/sites/dsc/storage1/c3/shared/project/fox/foxport3dec24-00/"
    "My%20Documents/marylandedit/crpcbook/wupccaoct2899.txt",
}


# --- Vehicles ---------------------------------------------------------------------------


@dataclass(frozen=True)
class VehicleData:
    """A test vehicle's planar properties for the system model. `mass_kg` is the test inertia
    mass (no dummy); lengths in m; `cg_behind_front_axle_m` is the centre of mass aft of the
    front axle; None where no source was found. `notes` says what is known beyond the fields
    (e.g. the pitch inertia where yaw is missing)."""

    name: str
    standard: str
    mass_kg: float
    yaw_inertia_kg_m2: float | None
    wheelbase_m: float | None
    track_width_m: float | None
    overall_length_m: float | None
    overall_width_m: float | None
    cg_behind_front_axle_m: float | None
    front_overhang_m: float | None
    cg_height_m: float | None
    printed: str
    source: Source
    notes: str = ""


# MASH 2016 Table 4-1 nominal properties. Mass, wheelbase (NAP 27896 Table 65) confirmed; the
# other nominal dimensions are as recalled from MASH and appear unconfirmed in the source.
VEHICLES = {
    "2270P": VehicleData(
        name="2270P",
        standard="mash",
        mass_kg=2270.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=148 * _IN,
        track_width_m=None,
        overall_length_m=237 * _IN,
        overall_width_m=78 * _IN,
        cg_behind_front_axle_m=63 * _IN,
        front_overhang_m=39 * _IN,
        cg_height_m=28 * _IN,
        printed="5000 +-110 lb; wheelbase 148 +-12 in; length 237 +-13 in; width 78 +-2 in; "
        "CG aft of front axle 63 +-4 in; front overhang 39 +-3 in; CG height >= 28 in",
        source=source(
            "AASHTO MASH 2016",
            "Table 4-1; NAP 27896 Table 65",
            confirmed_by="nap27896",
            unconfirmed="overall_length_m overall_width_m cg_behind_front_axle_m "
            "front_overhang_m cg_height_m yaw_inertia_kg_m2 track_width_m",
        ),
        notes="Yaw inertia not found. Nearest measured datum: NCAC 2007-T-006 Table 2, 2007 "
        "Chevrolet Silverado quad cab (2337 kg = 5152 lb, wheelbase 144 in = 3.658 m, CG 27.96 "
        "in = 0.710 m): pitch inertia 4542 ft-lb-s^2 = 6158 kg m^2; the yaw row is truncated "
        "in the stored copy. The same table lists the NCHRP 22-14(2) 2002 Dodge Ram 1500 quad "
        "cab (2452 kg = 5356 lb?, wheelbase 160 in?, CG 27.4 in?) - column alignment not certain.",
    ),
    "1100C": VehicleData(
        name="1100C",
        standard="mash",
        mass_kg=1100.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=98 * _IN,
        track_width_m=None,
        overall_length_m=169 * _IN,
        overall_width_m=65 * _IN,
        cg_behind_front_axle_m=39 * _IN,
        front_overhang_m=35 * _IN,
        cg_height_m=None,
        printed="2420 +-55 lb; wheelbase 98 +-5 in; length 169 +-8 in; width 65 +-3 in; "
        "CG aft of front axle 39 +-4 in; front overhang 35 +-4 in",
        source=source(
            "AASHTO MASH 2016",
            "Table 4-1",
            unconfirmed="wheelbase_m overall_length_m overall_width_m "
            "cg_behind_front_axle_m front_overhang_m yaw_inertia_kg_m2",
        ),
        notes="NCAC 2010 Toyota Yaris FE model (Marzougui et al., Extended Validation of the FE "
        "Model for the 2010 Toyota Yaris Passenger Sedan) is the usual 1100C surrogate; its "
        "inertia table was not reached in the stored copy.",
    ),
    "2000P": VehicleData(
        name="2000P",
        standard="nchrp350",
        mass_kg=2000.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=3.35,
        track_width_m=1.65,
        overall_length_m=5.35,
        overall_width_m=None,
        cg_behind_front_axle_m=None,
        front_overhang_m=0.80,
        cg_height_m=0.70,
        printed="2000 +-45 kg; wheelbase 3350 +-250 mm; track 1650 +-100 mm; length 5350 +-250 "
        "mm; front overhang 800 +-100 mm; CG height 700 +-50 mm",
        source=source(
            "NCHRP Report 350 (1993)",
            "Table 2.1 (clause unseen)",
            unconfirmed="clause wheelbase_m track_width_m overall_length_m "
            "front_overhang_m cg_height_m yaw_inertia_kg_m2",
        ),
        notes="Typical 2000P: 3/4-ton Chevrolet C2500; NCAC C2500 and C1500 FE models exist "
        "(Zaouk et al.); no inertia read.",
    ),
    "820C": VehicleData(
        name="820C",
        standard="nchrp350",
        mass_kg=820.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=2.30,
        track_width_m=1.35,
        overall_length_m=3.75,
        overall_width_m=None,
        cg_behind_front_axle_m=None,
        front_overhang_m=0.75,
        cg_height_m=0.55,
        printed="820 +-25 kg; wheelbase 2300 +-100 mm; track 1350 +-100 mm; length 3750 +-200 "
        "mm; front overhang 750 +-100 mm; CG height 550 +-50 mm",
        source=source(
            "NCHRP Report 350 (1993)",
            "Table 2.1 (clause unseen)",
            unconfirmed="clause wheelbase_m track_width_m overall_length_m "
            "front_overhang_m cg_height_m yaw_inertia_kg_m2",
        ),
        notes="Typical 820C: Geo Metro (NCAC FE model); no inertia read.",
    ),
    "car 900": VehicleData(
        name="car 900",
        standard="en1317",
        mass_kg=900.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=None,
        track_width_m=1.35,
        overall_length_m=None,
        overall_width_m=None,
        cg_behind_front_axle_m=0.90,
        front_overhang_m=None,
        cg_height_m=0.49,
        printed="900 +-40 kg; track 1.35 +-0.1 m; CG 0.90 +-0.09 m aft of front axle; CG "
        "height 0.49 +-0.05 m",
        source=source(
            "EN 1317-1:2010",
            "Table 2 (clause unseen)",
            unconfirmed="clause track_width_m cg_behind_front_axle_m cg_height_m",
        ),
    ),
    "car 1300": VehicleData(
        name="car 1300",
        standard="en1317",
        mass_kg=1300.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=None,
        track_width_m=1.40,
        overall_length_m=None,
        overall_width_m=None,
        cg_behind_front_axle_m=1.10,
        front_overhang_m=None,
        cg_height_m=0.53,
        printed="1300 +-65 kg; track 1.40 +-0.1 m; CG 1.10 +-0.11 m aft of front axle; CG "
        "height 0.53 +-0.05 m",
        source=source(
            "EN 1317-1:2010",
            "Table 2 (clause unseen)",
            unconfirmed="clause track_width_m cg_behind_front_axle_m cg_height_m",
        ),
    ),
    "car 1500": VehicleData(
        name="car 1500",
        standard="en1317",
        mass_kg=1500.0,
        yaw_inertia_kg_m2=None,
        wheelbase_m=None,
        track_width_m=1.50,
        overall_length_m=None,
        overall_width_m=None,
        cg_behind_front_axle_m=1.24,
        front_overhang_m=None,
        cg_height_m=0.53,
        printed="1500 +-75 kg; track 1.50 +-0.1 m; CG 1.24 +-0.12 m aft of front axle; CG "
        "height 0.53 +-0.05 m",
        source=source(
            "EN 1317-1:2010",
            "Table 2 (clause unseen)",
            unconfirmed="clause track_width_m cg_behind_front_axle_m cg_height_m",
        ),
    ),
}

# The one measured inertia read: 2007 Silverado (the NCAC 2270P FE model's donor vehicle).
SILVERADO_2007_MEASURED = {
    "mass_kg": 2337.0,  # 5152 lb
    "wheelbase_m": 144 * _IN,
    "cg_height_m": 27.96 * _IN,  # "CG, in 27.96"; taken as height (the row is unlabelled)
    "pitch_inertia_kg_m2": 4542 * _SLUG_FT2,  # 4542 ft-lb-sec^2
    "yaw_inertia_kg_m2": None,  # truncated in the stored copy
    "source": source(
        "NCAC 2007-T-006",
        "Tables 1-2",
        confirmed_by="ncac_2007_t006",
        unconfirmed="cg_height_m yaw_inertia_kg_m2",
    ),
}


# --- Vehicle crush ----------------------------------------------------------------------


@dataclass(frozen=True)
class CrushData:
    """A vehicle-periphery crush model as published: `stiffness_n_per_m2` (force per unit
    crush per unit contact length) or a force-crush curve `curve` ((crush m, force N), ...);
    None where the record only documents that such a calibration was made."""

    name: str
    vehicle: str
    stiffness_n_per_m2: float | None
    curve: tuple[tuple[float, float], ...] | None
    printed: str
    source: Source
    notes: str = ""


VEHICLE_CRUSH = {
    "barrier_vii_kansas": CrushData(
        name="BARRIER VII, Kansas transitions",
        vehicle="4,500-lb 1977 Plymouth",
        stiffness_n_per_m2=None,
        curve=None,
        printed="vehicle-crushing properties and guardrail-post stiffness validated using "
        "full-scale crash test data",
        source=source(
            "TRR 1233 (1989) 145-154",
            "abstract",
            confirmed_by="kansas_b7",
            unconfirmed="stiffness_n_per_m2 curve",
        ),
        notes="Numbers not in the abstract; the paper's tables hold them.",
    ),
    "barrier_vii_bligh_sicking": CrushData(
        name="BARRIER VII input requirements",
        vehicle="various",
        stiffness_n_per_m2=None,
        curve=None,
        printed="discusses input requirements, design loads, snagging prediction",
        source=source(
            "Bligh & Sicking, TRR 1233 (1989) 117-123",
            "abstract",
            confirmed_by="bligh_sicking_1989",
            unconfirmed="stiffness_n_per_m2 curve",
        ),
        notes="Powell (1973) FHWA-RD-73-51 models the periphery as crushable points with a "
        "bilinear force-deformation law and a contact length; its default values were not "
        "found in any stored page.",
    ),
}


# --- Barriers ---------------------------------------------------------------------------


@dataclass(frozen=True)
class RailData:
    """A rail: `thickness_m` (base metal), section `area_m2`, `inertia_m4` about the axis of
    lateral bending, `plastic_moment_n_m`, `yield_pa`, `ultimate_pa`, `elongation`,
    `mass_per_m_kg`; `top_height_m` and `post_spacing_m` of the system it belongs to."""

    name: str
    thickness_m: float | None
    area_m2: float | None
    inertia_m4: float | None
    plastic_moment_n_m: float | None
    yield_pa: float | None
    ultimate_pa: float | None
    elongation: float | None
    mass_per_m_kg: float | None
    top_height_m: float | None
    post_spacing_m: float | None
    printed: str
    source: Source
    notes: str = ""


@dataclass(frozen=True)
class PostData:
    """A post in soil: section, `length_m`, `embedment_m`, `load_height_m` (bogie), the bogie
    force-deflection summary (`peak_force_n`, `average_force_n` over `average_over_m`,
    `energy_j`), post `yield_pa`, `mass_per_m_kg`; None where not found."""

    name: str
    section: str
    length_m: float | None
    embedment_m: float | None
    load_height_m: float | None
    peak_force_n: float | None
    average_force_n: float | None
    average_over_m: float | None
    energy_j: float | None
    yield_pa: float | None
    mass_per_m_kg: float | None
    blockout_depth_m: float | None
    printed: str
    source: Source
    notes: str = ""


@dataclass(frozen=True)
class BarrierData:
    """A barrier system: its `rail`, `posts` (None for a wall), end anchorage notes."""

    name: str
    rail: RailData | None
    posts: PostData | None
    rigid: bool
    anchorage: str
    source: Source


_W_BEAM_12GA = {
    "thickness_m": 2.67e-3,
    "area_m2": None,
    "inertia_m4": None,
    "plastic_moment_n_m": None,
    "yield_pa": 50 * _KSI,
    "ultimate_pa": 70 * _KSI,
    "elongation": 0.12,
    "mass_per_m_kg": None,
}
_W_BEAM_PRINTED = (
    "Class A 2.67 mm (0.105 in); yield min 345 MPa (50 ksi); tensile min 483 MPa "
    "(70 ksi); elongation in 50 mm min 12 %"
)
_W_BEAM_NOTE = (
    "Section area, inertia and plastic moment not read in any source; MwRSF quotes "
    "12-gauge as 2.66 mm (rpf_262) against M 180's 2.67 mm."
)

BARRIERS = {
    "mgs": BarrierData(
        name="Midwest Guardrail System",
        rail=RailData(
            name="12-gauge W-beam (MGS)",
            top_height_m=31 * _IN,
            post_spacing_m=75 * _IN,
            printed=_W_BEAM_PRINTED + "; 31 in; 75 in",
            source=source(
                "AASHTO M 180; MwRSF TRP-03-235-11",
                "3.1; abstract",
                confirmed_by="m180 m180_mech mwrsf_26 rpf_262",
                unconfirmed="area_m2 inertia_m4 plastic_moment_n_m mass_per_m_kg",
            ),
            notes=_W_BEAM_NOTE + " Splices at mid-span (mwrsf_26).",
            **_W_BEAM_12GA,
        ),
        posts=PostData(
            name="MGS W6x8.5 steel post",
            section="W6x8.5 (W152x12.6)",
            length_m=6 * _FT,
            embedment_m=40 * _IN,
            load_height_m=24.875 * _IN,
            peak_force_n=None,
            average_force_n=None,
            average_over_m=None,
            energy_j=None,
            yield_pa=36 * _KSI,
            mass_per_m_kg=12.6,
            blockout_depth_m=12 * _IN,
            printed="6 ft (1.8 m); embedment 40 in (1,016 mm); bogie load height 24 7/8 in "
            "(632 mm); 12-in (305-mm) blockout; A36 yield 36 ksi",
            source=source(
                "MwRSF TRP-03-235-11; MwRSF post embedment study; NCHRP 26811",
                "abstracts; p. 43",
                confirmed_by="mwrsf_26 mwrsf_10 nchrp_26811",
                unconfirmed="peak_force_n average_force_n average_over_m energy_j",
            ),
            notes="W6x9 (W152x13.4) is the alternative post. Bogie force-deflection and "
            "energy values are in MwRSF post reports (mwrsf_10, mwrsf_217, mwrsf_244) but "
            "were not in the abstracts read. Rate effect: none measurable between 8.9 and 13.4 "
            "m/s (mwrsf_217). Post-rail bolt release and end-anchor stiffness not found.",
        ),
        rigid=False,
        anchorage="Tangent-terminal-like anchorages at both ends of a 181 ft-3 in (55.25 m) "
        "installation (rpf_262); strength/stiffness not found.",
        source=source("MwRSF", "see rail/posts", confirmed_by="mwrsf_26 rpf_262"),
    ),
    "g4_1s": BarrierData(
        name="Modified G4(1S) strong-post W-beam",
        rail=RailData(
            name="12-gauge W-beam (G4(1S))",
            top_height_m=0.706,
            post_spacing_m=75 * _IN,
            printed=_W_BEAM_PRINTED + "; 706 mm (27.75 in); 75 in",
            source=source(
                "AASHTO M 180; MwRSF 2214WB-1",
                "3.1; abstract",
                confirmed_by="m180 m180_mech mwrsf_140 faller_2007",
                unconfirmed="post_spacing_m area_m2 inertia_m4 plastic_moment_n_m mass_per_m_kg",
            ),
            notes=_W_BEAM_NOTE + " Splices at posts in G4(1S) (unconfirmed).",
            **_W_BEAM_12GA,
        ),
        posts=PostData(
            name="G4(1S) W6x9 steel post",
            section="W6x9 (W152x13.4)",
            length_m=6 * _FT,
            embedment_m=None,
            load_height_m=None,
            peak_force_n=None,
            average_force_n=None,
            average_over_m=None,
            energy_j=None,
            yield_pa=36 * _KSI,
            mass_per_m_kg=13.4,
            blockout_depth_m=None,
            printed="W6x9 (W152x13.4); A36",
            source=source(
                "MwRSF reports",
                "abstracts",
                confirmed_by="mwrsf_10 nchrp_26811",
                unconfirmed="length_m embedment_m",
            ),
            notes="Modified G4(1S) uses routed wood/plastic 6x8 in blockouts (not confirmed "
            "here); MwRSF (mwrsf_244) compares the MGS 40-in embedment with the W-beam "
            "standard 43 in (109.2 cm).",
        ),
        rigid=False,
        anchorage="not found",
        source=source("MwRSF", "see rail/posts", confirmed_by="mwrsf_140 faller_2007"),
    ),
    "thrie_beam": BarrierData(
        name="Thrie-beam guardrail",
        rail=None,
        posts=None,
        rigid=False,
        anchorage="not found",
        source=source("none found", "", unconfirmed="rail posts"),
    ),
    "box_beam": BarrierData(
        name="Box beam (G3) weak-post",
        rail=None,
        posts=None,
        rigid=False,
        anchorage="not found",
        source=source("none found", "", unconfirmed="rail posts"),
    ),
    "rigid_wall": BarrierData(
        name="Rigid concrete wall",
        rail=None,
        posts=None,
        rigid=True,
        anchorage="n/a",
        source=source("modelling idealisation", ""),
    ),
}
