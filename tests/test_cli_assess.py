"""`barrierjax assess RECORD.csv` and the record reader: units, verdicts, JSON, plots, and
malformed records (fuzzed) that each end with one line, never a traceback."""

import json

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from barrierjax import cli
from barrierjax.assess import occupant_risk
from barrierjax.assess.matrices import G
from barrierjax.assess.record import RecordError, read_record

DT = 1e-4
T = np.arange(0.0, 0.3, DT)
PULSE = np.where(T < 0.1, np.sin(np.pi * T / 0.1), 0.0)
AX, AY, YAW = -180.0 * PULSE, 60.0 * PULSE, 0.7 * PULSE  # m/s^2, m/s^2, rad/s


def write_record(path, header, columns, fmt="{:.17g}"):
    lines = [",".join(header)] + [",".join(fmt.format(v) for v in row) for row in zip(*columns)]
    path.write_text("\n".join(lines) + "\n")
    return path


def si_record(tmp_path):
    return write_record(tmp_path / "si.csv", ["t", "ax", "ay", "yaw_rate"], [T, AX, AY, YAW])


def run(capsys, *argv):
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def test_record_in_g_and_ms_gives_the_numbers_in_si(tmp_path):
    si = read_record(si_record(tmp_path))
    other = read_record(
        write_record(
            tmp_path / "g.csv",
            ["t [ms]", "ax [g]", "ay [ft/s^2]", "yaw_rate [deg/s]", "channel 7 [V]"],
            [T * 1e3, AX / G, AY / 0.3048, np.degrees(YAW), np.ones_like(T)],
            fmt="{:.15g}",
        )
    )
    assert other.units == {"t": "ms", "ax": "g", "ay": "ft/s^2", "yaw_rate": "deg/s"}
    a = occupant_risk(si.t, si.ax, si.ay, si.yaw_rate)
    b = occupant_risk(other.t, other.ax, other.ay, other.yaw_rate)
    for name in ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi"):
        assert float(getattr(b, name)) == pytest.approx(float(getattr(a, name)), rel=1e-9), name


def test_assess_json_is_si_and_equals_the_library(capsys, tmp_path):
    status, out, err = run(
        capsys, "assess", si_record(tmp_path), "--json", "--cfc", "0", "--no-plots"
    )
    data = json.loads(out)
    risk = occupant_risk(T, AX, AY, YAW)
    for name in ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi"):
        assert data[name] == pytest.approx(float(getattr(risk, name)), rel=1e-12), name
    assert [c["name"] for c in data["criteria"]] == ["OIV x", "OIV y", "ORA x", "ORA y"]
    # 180 m/s^2 peak over 0.1 s: |OIV x| = 11.3 m/s, between MASH's 9.144 and 12.192.
    assert data["criteria"][0]["verdict"] == "pass" and data["passed"] and status == 0


def test_assess_summary_plots_and_failing_verdict(capsys, tmp_path):
    strong = write_record(tmp_path / "strong.csv", ["t", "ax", "ay"], [T, 2 * AX, AY])
    status, out, err = run(
        capsys, "assess", strong, "--standard", "en1317", "--out", tmp_path / "plots"
    )
    assert status == 1  # ASI 3.0 > 1.9 and THIV > 33 km/h
    assert "EN 1317: FAIL" in out and "ASI" in out and "THIV" in out and "informative" in out
    for name in ("accelerations.png", "flail_space.png", "asi.png"):
        assert (tmp_path / "plots" / name).stat().st_size > 10_000


def test_record_too_short_for_the_occupant_impact(capsys, tmp_path):
    short = write_record(tmp_path / "short.csv", ["t", "ax", "ay"], [T[:500], AX[:500], AY[:500]])
    status, out, err = run(capsys, "assess", short)
    assert status == 2 and out == ""
    assert (
        err.startswith("error: ") and "OIV undefined" in err and len(err.strip().splitlines()) == 1
    )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "the file is empty"),
        ("t,ax\n0,1\n", "missing column 'ay'"),
        ("t [furlongs],ax,ay\n0,0,0\n1,0,0\n2,0,0\n", "column 't': unit 'furlongs' is not"),
        (
            "t [parsec],ax,ay\n0,0,0\n1,0,0\n2,0,0\n",
            "column 't': unit 'parsec' is not a unit of time",
        ),
        ("t,ax [furlongs],ay\n0,0,0\n1,0,0\n2,0,0\n", "is not a unit of acceleration"),
        ("t,ax [blorg],ay\n0,0,0\n1,0,0\n2,0,0\n", "column 'ax': unknown unit 'blorg'"),
        ("t,ax,ay\n0,0,0\n1,nan,0\n2,0,0\n", "row 3, column 'ax': nan is not finite"),
        ("t,ax,ay\n0,0,0\n1,x,0\n2,0,0\n", "row 3, column 'ax': 'x' is not a number"),
        ("t,ax,ay\n0,0,0\n0,0,0\n2,0,0\n", "strictly increasing"),
        ("t,ax,ay\n0,0,0\n1,0,0\n3,0,0\n4,0,0\n", "uniformly sampled"),
        ("t,ax,ay\n0,0,0\n1,0\n", "no value for column 'ay'"),
        ("t,ax,ay,ax\n0,0,0,0\n", "column 'ax' appears twice"),
        ("t,ax,ay\n0,0,0\n1,0,0\n", "a record needs at least 3"),
        # Accepted before: a row with a field too many; a value that overflows in SI units
        # (a traceback of the occupant-risk check).
        ("t,ax,ay\n0,0,0\n1,-8.5,18.3,5\n2,0,0\n", "row 3: 4 fields under a header of 3"),
        (
            "t,ax [g],ay\n0,0,0\n1,1e308,0\n2,0,0\n",
            "row 3, column 'ax': too large once in SI units",
        ),
    ],
)
def test_malformed_records_name_the_column_and_the_rule(tmp_path, capsys, text, message):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(RecordError, match=message):
        read_record(path)
    status, out, err = run(capsys, "assess", path)
    assert status == 2 and out == "" and err.count("\n") == 1 and "Traceback" not in err


def test_binary_and_missing_files(tmp_path, capsys):
    binary = tmp_path / "record.csv"
    binary.write_bytes(bytes(range(256)) * 4)
    status, _, err = run(capsys, "assess", binary)
    assert status == 2 and "not a text CSV file" in err
    status, _, err = run(capsys, "assess", tmp_path / "absent.csv")
    assert status == 2 and "cannot be read" in err


_CELLS = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.integers(-5, 5).map(str),
    st.sampled_from(["", "abc", "1e309", "-", "[g]", '"', "0x10", "1,2"]),
    st.text(max_size=6),
)
_HEADERS = st.lists(
    st.sampled_from(
        [
            "t",
            "ax",
            "ay",
            "az",
            "yaw_rate",
            "t [ms]",
            "ax [g]",
            "ay [zz]",
            "t [m]",
            "x",
            "",
            "ax [",
            "t [s]",
        ]
    ),
    min_size=0,
    max_size=6,
)


@settings(
    max_examples=150, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    header=_HEADERS,
    rows=st.lists(st.lists(_CELLS, max_size=6), max_size=8),
    raw=st.binary(max_size=40),
)
def test_fuzzed_records_give_one_line_never_a_traceback(tmp_path, header, rows, raw):
    """Random headers, cells and bytes: the reader either reads the record or raises
    RecordError with one line; nothing else escapes."""
    path = tmp_path / "fuzz.csv"
    text = "\n".join([",".join(header)] + [",".join(row) for row in rows])
    for content in (
        text.encode("utf-8", "surrogatepass"),
        raw,
        text.encode("utf-8", "surrogatepass") + raw,
    ):
        path.write_bytes(content)
        try:
            record = read_record(path)
        except RecordError as error:
            assert "\n" not in str(error) and str(error)
        else:
            assert np.all(np.isfinite(record.ax)) and np.all(np.diff(record.t) > 0)


def test_example_record_of_the_oblique_model_reads_back_as_the_model(capsys):
    """examples/oblique_scene_record.csv (examples/model_record.py: the oblique scene's
    vehicle accelerations in g and ms, 9 digits) assessed by the command equals `assess`
    on the model's result."""
    from pathlib import Path

    import barrierjax as bj
    from barrierjax.assess import assess

    examples = Path(__file__).resolve().parents[1] / "examples"
    status, out, _ = run(
        capsys,
        "assess",
        examples / "oblique_scene_record.csv",
        "--cfc",
        "0",
        "--json",
        "--no-plots",
    )
    data = json.loads(out)
    risk = assess(bj.simulate(bj.load_scene(examples / "oblique_scene.toml")))
    assert status == 0
    for name in ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi"):
        assert data[name] == pytest.approx(float(getattr(risk, name)), rel=1e-6), name
