"""Smoke tests of the benchmark scripts: `--quick` runs, exits 0, prints its tables and
writes its JSON.

This checks that the benchmark script works, never how fast anything is (a benchmark is
never a timed test: tests assert correctness, benchmarks report speed).
"""

import json
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("mpmath")
pytest.importorskip("scipy")

BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"


def run_quick(name, out, timeout, sections, extra=()):
    """Run benchmarks/<name>.py --quick into `out` (and `extra` options); it must succeed and
    print its tables. Returns the JSON it wrote, checked for the harness's common layout and
    `sections`."""
    proc = subprocess.run(
        [sys.executable, str(BENCHMARKS / f"{name}.py"), "--quick", "--out", str(out), *extra],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "SUMMARY" in proc.stdout
    assert "| " in proc.stdout and "First call in a fresh process" in proc.stdout
    data = json.loads((out / f"{name}.json").read_text())
    for section in ("meta", "first_call", *sections):
        assert section in data, section
    meta = data["meta"]
    assert meta["quick"] is True
    assert {"jax", "diffrax", "barrierjax", "numpy"} <= set(meta["versions"])
    assert {"cpu_count", "load_average_start"} <= set(meta["machine"])
    # The first call in a fresh process: at least the first case (a forward call) ran there.
    first = data["first_call"][0]
    assert first["ok"], first
    assert first["first_call_s"] > 0 and first["import_s"] > 0 and first["peak_rss_mb"] > 50
    return data


def test_normal_impact_benchmark_quick(tmp_path):
    out = tmp_path / "results"
    data = run_quick("normal_impact", out, 120, ("accuracy", "throughput", "gradient", "summary"))
    rows = data["accuracy"]
    ours = [r for r in rows if r["model"] == "barrierjax"]
    assert {r["method"] for r in ours} == {"closed_form", "ode"}
    assert all(r["ok"] for r in ours)
    # The closed form at rtol 1e-8 agrees with the mpmath reference (a correctness check on
    # the benchmark's own reference, not a speed check); the ODE and scipy come close.
    closed = [r for r in ours if r["method"] == "closed_form" and r["rtol"] == 1e-8]
    assert closed and closed[0]["error"] < 1e-7
    assert next(r for r in ours if r["method"] == "ode")["error"] < 1e-5
    scipy = [r for r in rows if r["model"] == "scipy solve_ivp"]
    assert scipy and all(r["failed"] < r["n"] and r["error"] < 1e-3 for r in scipy)
    assert data["meta"]["reference_self_check"] < 1e-15
    assert {r["method"] for r in data["throughput"]} == {"closed_form", "ode"}
    assert data["gradient"] and all(r["ratio"] > 0 for r in data["gradient"])
    assert data["summary"]
    for name in ("normal_impact_error_vs_time.png", "normal_impact_throughput.png"):
        assert (out / name).stat().st_size > 0


@pytest.mark.slow
def test_oblique_impact_benchmark_quick(tmp_path):
    # One oblique compilation here and one in the fresh process (30-75 s each on 2 shared
    # cores); the gradient's fresh process is stopped after 15 s in the quick run.
    out = tmp_path / "results"
    data = run_quick("oblique_impact", out, 600, ("accuracy", "cost", "gradient", "scenarios"))
    # The reference (the model at rtol 1e-9) and rtol 1e-6 agree: the benchmark's plumbing,
    # not its speed; the energy balance closes.
    row = data["accuracy"][0]
    assert row["ok"] and row["error"] < 1e-4 and row["energy"] < 1e-4, row
    assert data["cost"][0]["ok"] and data["cost"][0]["ratio"] > 0
    assert len(data["first_call"]) == 2
    assert (out / "oblique_impact_error_vs_time.png").stat().st_size > 0


@pytest.mark.slow
def test_axial_force_benchmark_quick(tmp_path):
    out = tmp_path / "results"
    data = run_quick("axial_force", out, 300, ("example", "error_vs_time", "throughput", "string", "gradient"))
    ours, *report = data["example"]
    # The report's scheme converges towards the model as its step falls (a correctness check
    # of the benchmark's own transcription of the scheme, not a speed check).
    gaps = [abs(r["reduction_eta0_5"] - ours["reduction_eta0_5"]) for r in report]
    assert gaps == sorted(gaps, reverse=True)
    assert data["error_vs_time"]["rows"][-1]["error"] < 1e-4  # rtol 1e-6
    assert data["string"]["refinement"][0]["energy"] < 1e-2
    assert all(r["reached_string"] > 0 for r in data["string"]["throughput"])
    assert (out / "axial_force.png").stat().st_size > 0


def test_materials_benchmark_quick(tmp_path):
    data = run_quick("materials", tmp_path / "results", 300, ("error_vs_time", "throughput", "summary"))
    methods = {row["method"] for row in data["error_vs_time"]}
    assert methods == {"implicit", "report", "explicit", "diffrax", "scipy Radau"}
    # The closed-form references make every stable error small at the finest setting; the
    # NumPy baseline computes the same update (a check of the benchmark's plumbing).
    finest = [r for r in data["error_vs_time"] if r["method"] == "implicit" and r["steps"] == 64]
    assert finest and all(r["stable"] and r["error"] < 0.1 for r in finest)
    assert all(row["max_stress_difference"] < 1e-8 for row in data["throughput"])


@pytest.mark.slow
def test_beam_fe_benchmark_quick(tmp_path):
    # A few minutes on 2 shared cores, nearly all of it compilations; OpenSees is compared
    # when openseespy imports, and skipped by the script (saying so) otherwise.
    out = tmp_path / "results"
    data = run_quick("beam_fe", out, 600, ("opensees", "errors", "vmap"))
    # Checks of the benchmark's plumbing, not of speed: the vmapped batch computes what one
    # call does, "report" is linear acceleration on a rate-independent law, and the matched
    # model agrees with OpenSees where both ran.
    assert data["vmap"]["vmap_vs_single"] < 1e-10
    assert data["errors"]["report_equals_linear_acceleration"]
    for row in data["opensees"]:
        assert row["barrierjax"]["converged"]
        if "opensees" in row:
            assert abs(row["rest_difference"]) < 0.02
    assert (data["opensees_skipped"] is None) == all("opensees" in r for r in data["opensees"])
    assert (out / "beam_fe_error_vs_time.png").stat().st_size > 0


def test_parts_benchmark_quick(tmp_path):
    # Beside an earlier run's figures: one as fast as no run can be (so this one is flagged
    # slower), one case the earlier run did not have (left out).
    earlier = tmp_path / "earlier.json"
    case = {"model": "normal, ODE", "n": 2048, "ok": True, "one_us": 1e-9, "parts_us": 1e-9}
    other = dict(case, n=10_000)
    earlier.write_text(json.dumps({"parts": [case, other]}))
    out = tmp_path / "results"
    data = run_quick("parts", out, 120, ("parts", "compared"), ("--compare", str(earlier)))
    (row,) = data["parts"]
    assert row["ok"] and row["model"] == "normal, ODE" and row["n"] == 2048
    assert row["one_us"] > 0 and row["parts_us"] > 0
    (beside,) = data["compared"]
    assert beside["n"] == 2048 and beside["slower"] is True
    assert beside["parts_ratio"] == row["parts_us"] / 1e-9
