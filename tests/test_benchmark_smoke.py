"""Smoke tests of the benchmark scripts: `--quick` runs, exits 0 and writes its JSON.

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


def run_quick(name, out, timeout):
    """Run benchmarks/<name>.py --quick into `out`; it must succeed and print its summary.
    Returns the JSON it wrote."""
    proc = subprocess.run(
        [sys.executable, str(BENCHMARKS / f"{name}.py"), "--quick", "--out", str(out)],
        check=False,
        capture_output=True,
        text=True,
        timeout=timeout,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "SUMMARY" in proc.stdout
    return json.loads((out / f"{name}.json").read_text())


def assert_quick_report(data, sections, targets):
    """The JSON holds every section, says it is a quick run, and gives each of `targets` (a
    subset where a section may be skipped) a verdict."""
    for section in sections:
        assert section in data, section
    assert data["meta"]["quick"] is True
    assert set(data["targets"]) <= set(targets)
    for target in data["targets"].values():
        assert target["verdict"] in ("PASS", "FAIL")


def test_normal_impact_benchmark_quick(tmp_path):
    out = tmp_path / "results"
    data = run_quick("normal_impact", out, timeout=120)
    for section in (
        "meta",
        "scenarios",
        "error_vs_time",
        "throughput",
        "gradient",
        "scipy",
        "targets",
        "surprises",
    ):
        assert section in data, section
    assert data["meta"]["quick"] is True
    assert set(data["targets"]) == {"scipy_ratio", "closed_form_throughput", "gradient_ratio"}
    for target in data["targets"].values():
        assert target["verdict"] in ("PASS", "FAIL")

    rows = data["error_vs_time"]["rows"]
    assert {r["method"] for r in rows} == {"closed_form", "ode"}
    # The closed form at rtol 1e-8 agrees with the mpmath reference (a correctness check on
    # the benchmark's own reference, not a speed check).
    closed = [r for r in rows if r["method"] == "closed_form" and r["rtol"] == 1e-8]
    assert closed and closed[0]["ok"] and closed[0]["error"] < 1e-7
    assert data["throughput"]["rows"]["closed_form"]
    assert data["gradient"]["rows"]["closed_form"]
    assert data["scipy"]["rows"]
    for name in (
        "normal_impact_error_vs_time.png",
        "normal_impact_throughput.png",
        "normal_impact_gradient.png",
    ):
        assert (out / name).stat().st_size > 0


@pytest.mark.slow
def test_oblique_impact_benchmark_quick(tmp_path):
    # Two oblique compilations (30-75 s each on 2 shared cores) dominate; the gradient section
    # only exercises its guarded child process, which the quick run stops after 15 s.
    out = tmp_path / "results"
    data = run_quick("oblique_impact", out, timeout=600)
    sections = ("meta", "scenarios", "error_vs_time", "throughput", "gradient", "stability")
    targets = {"throughput_ratio", "energy_balance"}
    assert_quick_report(data, (*sections, "targets", "surprises"), targets)
    assert set(data["targets"]) == targets

    # The reference (the model at rtol 1e-9) is usable for every quick scenario, and rtol 1e-6
    # agrees with it: a check on the benchmark's plumbing, not on speed.
    assert data["scenarios"]["reference_failures"] == {}
    rows = data["error_vs_time"]["rows"]
    assert rows and rows[0]["ok"] and rows[0]["error"] < 1e-4
    throughput = data["throughput"]["rows"]
    assert throughput["oblique"][0]["ok"] and throughput["normal_ode"][0]["ok"]
    assert data["gradient"]["rows"]
    assert data["stability"]["sections"][0]["results"]
    for name in (
        "oblique_impact_error_vs_time.png",
        "oblique_impact_throughput.png",
        "oblique_impact_gradient.png",
        "oblique_impact_stability.png",
    ):
        assert (out / name).stat().st_size > 0


@pytest.mark.slow
def test_axial_force_benchmark_quick(tmp_path):
    out = tmp_path / "results"
    data = run_quick("axial_force", out, timeout=300)
    for section in ("meta", "example", "error_vs_time", "throughput", "gradient"):
        assert section in data, section
    ours, *report = data["example"]
    # The report's scheme converges towards the model as its step falls (a correctness check
    # of the benchmark's own transcription of the scheme, not a speed check).
    gaps = [abs(r["reduction_eta0_5"] - ours["reduction_eta0_5"]) for r in report]
    assert gaps == sorted(gaps, reverse=True)
    assert data["error_vs_time"]["rows"][-1]["error"] < 1e-4  # rtol 1e-6
    assert (out / "axial_force.png").stat().st_size > 0


def test_materials_benchmark_quick(tmp_path):
    data = run_quick("materials", tmp_path / "results", timeout=300)
    assert {"meta", "error_vs_time", "throughput", "summary"} <= set(data)
    methods = {row["method"] for row in data["error_vs_time"]}
    assert methods == {"implicit", "report", "explicit", "diffrax", "scipy Radau"}
    # The closed-form references make every stable error small at the finest setting; the
    # NumPy baseline computes the same update (a check of the benchmark's plumbing).
    finest = [r for r in data["error_vs_time"] if r["method"] == "implicit" and r["steps"] == 64]
    assert finest and all(r["stable"] and r["error"] < 0.1 for r in finest)
    assert all(row["max_stress_difference"] < 1e-8 for row in data["throughput"])


@pytest.mark.slow
def test_beam_fe_benchmark_quick(tmp_path):
    # About 2-3 minutes on 2 shared cores, nearly all of it some 15 compilations; OpenSees is
    # compared when openseespy imports, and skipped by the script otherwise.
    out = tmp_path / "results"
    data = run_quick("beam_fe", out, timeout=600)
    sections = ("meta", "opensees", "convergence", "speed", "vmap", "errors", "stability")
    assert_quick_report(data, (*sections, "targets"), {"agreement", "speed", "vmap"})
    # Checks of the benchmark's plumbing, not of speed: the vmapped batch computes what one
    # call does, "report" is linear acceleration on a rate-independent law, the matched model
    # agrees with OpenSees where both ran, and the report's own steps blow its scheme up.
    assert data["vmap"]["vmap_vs_single"] < 1e-10
    assert data["errors"]["rate_independent"]["report_equals_linear_acceleration"]
    for row in data["opensees"]:
        if "opensees" in row and "barrierjax" in row and row["barrierjax"]["converged"]:
            assert abs(row["rest_difference"]) < 0.02
    assert data["stability"][0]["report_run_blown_up"]
    assert data["stability"][0]["bracketed"]
    assert (out / "beam_fe_error_vs_time.png").stat().st_size > 0
