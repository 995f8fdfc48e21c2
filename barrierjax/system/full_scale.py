"""Published full-scale crash tests of guardrails to compare the system model with
(`FULL_SCALE_TESTS`), and the published cost of finite-element runs (`SIMULATION_COST`), each
value with its source, confirmed as `sources.py` says (the keys of `confirmed_by` are those of
`sources.REFERENCES`). Fields held as None were not found."""

from dataclasses import dataclass

from ..assess.matrices import Source
from .sources import source

_IN = 0.0254  # m per in
_MPH = 0.44704  # m/s per mi/h


# --- Full-scale tests -------------------------------------------------------------------


@dataclass(frozen=True)
class CrashTestRecord:
    """A published full-scale test: impact `speed_m_s` and `angle_deg`, `result`
    ("redirected", "failed", ...), `dynamic_deflection_m`, `working_width_m`, exit speed and
    angle, occupant impact velocities (`oiv_*`, m/s) and ridedown accelerations (`ora_*`, g);
    None where not read."""

    test_id: str
    barrier: str
    report: str
    vehicle: str
    test: str
    speed_m_s: float | None
    angle_deg: float | None
    result: str
    dynamic_deflection_m: float | None
    working_width_m: float | None
    exit_speed_m_s: float | None
    exit_angle_deg: float | None
    oiv_long_m_s: float | None
    oiv_lat_m_s: float | None
    ora_long_g: float | None
    ora_lat_g: float | None
    post_spacing_m: float | None
    rail_height_m: float | None
    printed: str
    source: Source
    notes: str = ""


_NONE_KIN = {
    "exit_speed_m_s": None,
    "exit_angle_deg": None,
    "oiv_long_m_s": None,
    "oiv_lat_m_s": None,
    "ora_long_g": None,
    "ora_lat_g": None,
}
_KIN_FIELDS = "exit_speed_m_s exit_angle_deg oiv_long_m_s oiv_lat_m_s ora_long_g ora_lat_g"

FULL_SCALE_TESTS = {
    "2214MG-1": CrashTestRecord(
        test_id="2214MG-1",
        barrier="mgs",
        report="MwRSF, NCHRP 22-14(2) MGS testing",
        vehicle="2270P (3/4-ton two-door pickup)",
        test="NCHRP 350 Update 3-11 (pre-MASH)",
        speed_m_s=None,
        angle_deg=None,
        result="redirected",
        dynamic_deflection_m=57.0 * _IN,
        working_width_m=57.3 * _IN,
        post_spacing_m=75 * _IN,
        rail_height_m=31 * _IN,
        printed="working width 57.3 in, dynamic deflection 57.0 in",
        source=source(
            "MwRSF Q&A 280; Faller et al. TRR 2025 (2007)",
            "answer; abstract",
            confirmed_by="mwrsf_qa_280 faller_2007",
            unconfirmed="vehicle speed_m_s angle_deg " + _KIN_FIELDS,
        ),
        notes="Which 2214MG test used which pickup is not printed in what was read; the Q&A "
        "calls it a W6x9 standard-spacing MASH test. A 1.45 m deflection is large for MGS.",
        **_NONE_KIN,
    ),
    "2214MG-2": CrashTestRecord(
        test_id="2214MG-2",
        barrier="mgs",
        report="MwRSF, NCHRP 22-14(2) MGS testing",
        vehicle="2270P (1/2-ton four-door pickup)",
        test="NCHRP 350 Update 3-11 (pre-MASH)",
        speed_m_s=None,
        angle_deg=None,
        result="redirected",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=75 * _IN,
        rail_height_m=31 * _IN,
        printed="MGS met 3-11 with both pickups",
        source=source(
            "Faller et al. TRR 2025 (2007)",
            "abstract",
            confirmed_by="faller_2007",
            unconfirmed="test_id speed_m_s angle_deg dynamic_deflection_m "
            "working_width_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "2214WB-1": CrashTestRecord(
        test_id="2214WB-1",
        barrier="g4_1s",
        report="MwRSF 2214WB-1",
        vehicle="2270P (3/4-ton two-door pickup)",
        test="NCHRP 350 Update 3-11 (pre-MASH)",
        speed_m_s=None,
        angle_deg=None,
        result="failed (unacceptable)",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=75 * _IN,
        rail_height_m=0.706,
        printed="706 mm (27.75 in); unacceptable safety performance",
        source=source(
            "MwRSF report 140",
            "abstract",
            confirmed_by="mwrsf_140 faller_2007",
            unconfirmed="post_spacing_m speed_m_s angle_deg dynamic_deflection_m "
            "working_width_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "2214WB-2": CrashTestRecord(
        test_id="2214WB-2",
        barrier="g4_1s",
        report="MwRSF, NCHRP 22-14(2)",
        vehicle="2270P (1/2-ton four-door pickup)",
        test="NCHRP 350 Update 3-11 (pre-MASH)",
        speed_m_s=None,
        angle_deg=None,
        result="redirected",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=75 * _IN,
        rail_height_m=0.706,
        printed="706 mm; acceptable with the 1/2-ton four-door pickup",
        source=source(
            "Faller et al. TRR 2025 (2007)",
            "abstract",
            confirmed_by="faller_2007",
            unconfirmed="test_id post_spacing_m speed_m_s angle_deg "
            "dynamic_deflection_m working_width_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "MGS7S-2": CrashTestRecord(
        test_id="MGS7S-2",
        barrier="mgs (1/2 post spacing, 7-ft W6x9 posts, 2H:1V slope)",
        report="MwRSF TRP-03-452-24",
        vehicle="2270P quad cab",
        test="MASH 2016 3-11",
        speed_m_s=62.6 * _MPH,
        angle_deg=25.4,
        result="redirected",
        dynamic_deflection_m=27.2 * _IN,
        working_width_m=47.7 * _IN,
        post_spacing_m=37.5 * _IN,
        rail_height_m=31 * _IN,
        printed="62.6 mi/h, 25.4 deg; dynamic deflection 27.2 in, working width 47.7 in",
        source=source(
            "MwRSF TRP-03-452-24; MwRSF Q&A 32949",
            "abstract; answer",
            confirmed_by="mwrsf_499 mwrsf_qa_32949",
            unconfirmed="post_spacing_m rail_height_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "MGS7S-1": CrashTestRecord(
        test_id="MGS7S-1",
        barrier="mgs (1/2 post spacing, 7-ft W6x9 posts, 2H:1V slope)",
        report="MwRSF TRP-03-452-24",
        vehicle="1100C",
        test="MASH 2016 3-10",
        speed_m_s=62.8 * _MPH,
        angle_deg=25.2,
        result="redirected",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=37.5 * _IN,
        rail_height_m=31 * _IN,
        printed="62.8 mi/h, 25.2 deg",
        source=source(
            "MwRSF TRP-03-452-24",
            "abstract",
            confirmed_by="mwrsf_499",
            unconfirmed="post_spacing_m rail_height_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "MGS quarter spacing (NCHRP 350)": CrashTestRecord(
        test_id="unknown",
        barrier="mgs (1/4 post spacing)",
        report="MwRSF MGS development",
        vehicle="2000P",
        test="NCHRP 350 3-11",
        speed_m_s=None,
        angle_deg=None,
        result="redirected",
        dynamic_deflection_m=17.6 * _IN,
        working_width_m=36.7 * _IN,
        post_spacing_m=18.75 * _IN,
        rail_height_m=31 * _IN,
        printed="dynamic deflection 17.6 in, working width 36.7 in",
        source=source(
            "MwRSF Q&A 1105",
            "answer",
            confirmed_by="mwrsf_qa_1105",
            unconfirmed="test_id vehicle speed_m_s angle_deg post_spacing_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "MGS non-blocked 3-11": CrashTestRecord(
        test_id="unknown",
        barrier="mgs (no blockout, backup plates)",
        report="MwRSF TRP-03-262-12 (FHWA B-243)",
        vehicle="2270P",
        test="MASH 3-11",
        speed_m_s=None,
        angle_deg=None,
        result="redirected",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=75 * _IN,
        rail_height_m=31 * _IN,
        printed="MASH 3-10, 3-11 pass; 75 in spacing",
        source=source(
            "Roadside Pooled Fund; MwRSF report 9",
            "summary",
            confirmed_by="rpf_262",
            unconfirmed="test_id speed_m_s angle_deg dynamic_deflection_m "
            "working_width_m " + _KIN_FIELDS,
        ),
        notes="Pooled-fund page prints height 32 in; MwRSF abstract says 31 in nominal.",
        **_NONE_KIN,
    ),
    "MGS curb omitted post 3-11": CrashTestRecord(
        test_id="unknown",
        barrier="mgs (6-in curb, one post omitted, nested rail)",
        report="MwRSF TRP-03-433-21",
        vehicle="2270P",
        test="MASH 2016 3-11",
        speed_m_s=None,
        angle_deg=None,
        result="redirected",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=75 * _IN,
        rail_height_m=31 * _IN,
        printed="pass; W6x8.5; 75 in; 31 in",
        source=source(
            "Roadside Pooled Fund",
            "summary",
            confirmed_by="rpf_433",
            unconfirmed="test_id speed_m_s angle_deg dynamic_deflection_m "
            "working_width_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "MGS flared (TTI)": CrashTestRecord(
        test_id="unknown",
        barrier="mgs (critical flare)",
        report="TTI 609971",
        vehicle="2270P / 1100C",
        test="MASH 3-10, 3-11",
        speed_m_s=None,
        angle_deg=None,
        result="failed MASH TL-3",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=None,
        rail_height_m=None,
        printed="did not meet the performance criteria for MASH TL-3",
        source=source(
            "Roadside Pooled Fund / TTI 609971",
            "abstract",
            confirmed_by="rpf_flare",
            unconfirmed="test_id speed_m_s angle_deg dynamic_deflection_m "
            "working_width_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
    "MGS 8:1 slope pickup": CrashTestRecord(
        test_id="unknown",
        barrier="mgs (8H:1V approach slope)",
        report="Reid (2009)",
        vehicle="2000P",
        test="NCHRP 350 3-11",
        speed_m_s=100.4 / 3.6,
        angle_deg=25.9,
        result="redirected",
        dynamic_deflection_m=None,
        working_width_m=None,
        post_spacing_m=75 * _IN,
        rail_height_m=31 * _IN,
        printed="100.4 km/h, 25.9 deg; passed",
        source=source(
            "Reid, J. Transp. Safety & Security 1(1) (2009)",
            "abstract",
            confirmed_by="reid_2009",
            unconfirmed="test_id vehicle post_spacing_m rail_height_m "
            "dynamic_deflection_m working_width_m " + _KIN_FIELDS,
        ),
        **_NONE_KIN,
    ),
}


# --- Simulation cost --------------------------------------------------------------------


@dataclass(frozen=True)
class CostRecord:
    """A published run cost: `wall_hours` on `cores`, `simulated_s` of event time; None
    where not printed."""

    name: str
    code: str
    model: str
    wall_hours: float | None
    cores: int | None
    simulated_s: float | None
    printed: str
    source: Source
    notes: str = ""


SIMULATION_COST = {
    "roadside_event_duration": CostRecord(
        name="Roadside hardware impact duration",
        code="LS-DYNA",
        model="NCAC C-1500",
        wall_hours=None,
        cores=None,
        simulated_s=1.0,
        printed="simulations that could last as long as 1 second (vs <= 150 ms frontal)",
        source=source(
            "Zaouk et al., NCAC C-1500 validation",
            "abstract",
            confirmed_by="zaouk_c1500",
            unconfirmed="wall_hours cores",
        ),
    ),
    "fujitsu_10m": CostRecord(
        name="10M-element car crash on up to 512 processors",
        code="LS-DYNA MPP",
        model="10-million-element car",
        wall_hours=None,
        cores=512,
        simulated_s=None,
        printed="highly parallel execution with up to 512 processors",
        source=source(
            "Kondo & Makino, Fujitsu Sci. Tech. J. 44(4) (2008)",
            "abstract",
            confirmed_by="kondo_2008",
            unconfirmed="wall_hours simulated_s",
        ),
        notes="Not a guardrail model; shows the scale of parallel crash runs.",
    ),
    "npac_weeks": CostRecord(
        name="Several seconds of crash = several weeks of workstation time",
        code="LS-DYNA",
        model="automobile",
        wall_hours=None,
        cores=1,
        simulated_s=None,
        printed="simulation for several seconds of car crash may take several weeks of "
        "workstation time",
        source=source(
            "NPAC crash-simulation chapter (c. 1999)",
            "text",
            confirmed_by="npac_crash",
            unconfirmed="wall_hours cores",
        ),
    ),
    "barrier_vii": CostRecord(
        name="BARRIER VII run",
        code="BARRIER VII (Powell 1973)",
        model="2-D vehicle, rail",
        wall_hours=None,
        cores=1,
        simulated_s=None,
        printed="described as a relatively inexpensive alternative to crash testing",
        source=source(
            "Bligh & Sicking, TRR 1233 (1989)",
            "abstract",
            confirmed_by="bligh_sicking_1989",
            unconfirmed="wall_hours simulated_s",
        ),
        notes="No published BARRIER VII run time found.",
    ),
}
