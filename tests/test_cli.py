"""The `barrierjax` command: run (summary, JSON, plots), figures, optimize, and errors."""

import json
import math
import shutil
import subprocess
import sys
import textwrap
import types

import jax
import pytest

jax.config.update("jax_enable_x64", True)

import barrierjax as bj
from barrierjax import cli
from barrierjax.scene_file import default_scene

G = 9.80665
REQUIRED = (
    "damage_m",
    "max_deflection_m",
    "duration_s",
    "peak_deceleration_g",
    "exit_speed_m_s",  # zero for the default (normal) scene
    "exit_angle_deg",
)
POSITIVE = REQUIRED[:4] + (
    "peak_force_N",
    "peak_deceleration_m_s2",
    "hinge_extent_m",
    "mass_ratio",
    "force_ratio",
    "speed_dimensionless",
    "kinetic_energy_J",
    "crush_work_J",
    "backing_work_J",
    "hinge_work_J",
)

SCENE = """
[barrier]
plastic_moment = "1e6 lbf*in"
mass_per_length = "40 kg/m"
backing_strength = "50 kN/m"
[vehicle]
mass = "1100 kg"
crush_force = "400 kN"
[impact]
speed = "35 mph"
"""


def run(capsys, *argv):
    status = cli.main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def write(tmp_path, text, name="scene.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text))
    return path


def check_against_simulate(data, scene):
    result = bj.simulate(scene)
    expected = {
        "damage_m": result.damage,
        "max_deflection_m": result.max_deflection,
        "duration_s": result.duration,
        "peak_force_N": result.peak_force,
        "peak_deceleration_g": result.peak_deceleration / G,
        "hinge_extent_m": result.hinge_extent,
        "mass_ratio": result.groups.mass_ratio,
        "force_ratio": result.groups.force_ratio,
        "speed_dimensionless": result.groups.normal_speed,
        "kinetic_energy_J": result.kinetic_energy,
        "crush_work_J": result.crush_work,
        "backing_work_J": result.backing_work,
        "hinge_work_J": result.hinge_work,
    }
    for key, value in expected.items():
        assert data[key] == pytest.approx(float(value), rel=1e-12), key
    for key in POSITIVE:
        assert math.isfinite(data[key]) and data[key] > 0, key
    energy = data["crush_work_J"] + data["backing_work_J"] + data["hinge_work_J"]
    assert energy == pytest.approx(data["kinetic_energy_J"], rel=1e-8)


def test_run_json_default_scene(capsys, tmp_path):
    status, out, err = run(capsys, "run", "--json", "--out", str(tmp_path))
    assert status == 0
    data = json.loads(out)  # exactly one JSON object and nothing else
    assert isinstance(data, dict)
    for key in REQUIRED:
        assert key in data
    check_against_simulate(data, default_scene())
    assert data["inputs"]["speed_m_s"] == pytest.approx(40 / 3.6)
    assert 0.3 < data["max_deflection_m"] < 0.5  # the documented ~0.4 m
    assert "compiling" in err  # progress goes to stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deflected_shape.png", "histories.png"]


def test_run_summary_and_plots(capsys, tmp_path):
    out_dir = tmp_path / "plots"
    status, out, err = run(capsys, "run", "--out", str(out_dir))
    assert status == 0
    for words in (
        "default scene", "mu", "phi", "V0", "kN*m", "vehicle damage", "mm",
        "max barrier deflection", "duration", "ms", "peak contact force", " g ",
        "hinge extent", "Energy partition", "kJ", "%",
    ):
        assert words in out, words
    for name in ("histories.png", "deflected_shape.png"):
        path = out_dir / name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert path.stat().st_size > 10_000
        assert f"writing {path}" in err


def test_run_scene_file_in_report_units(capsys, tmp_path):
    path = write(tmp_path, SCENE)
    status, out, err = run(capsys, "run", str(path), "--json", "--no-plots")
    assert status == 0, err
    data = json.loads(out)
    assert data["scene"] == str(path)
    assert data["plots"] == []
    from barrierjax.scene_file import load_scene

    check_against_simulate(data, load_scene(path))
    assert data["inputs"]["plastic_moment_N_m"] == pytest.approx(1e6 * 4.4482216152605 * 0.0254)


BAD = [
    ('plastic_moment = "1e6 lbf*in"', 'plastic_moment = "100 kg"', "[barrier] plastic_moment"),
    ('plastic_moment = "1e6 lbf*in"', "plastic_moment = 100", "[barrier] plastic_moment"),
    ('plastic_moment = "1e6 lbf*in"', 'plastic_moment = "1e6 lbf*"', "[barrier] plastic_moment"),
    ('plastic_moment = "1e6 lbf*in"', 'plastic_moment = "-1 kN*m"', "[barrier] plastic_moment"),
    ('plastic_moment = "1e6 lbf*in"', "", "[barrier] plastic_moment"),
    ('plastic_moment = "1e6 lbf*in"', 'plastic_moment = "1e6 lbf*in"\ncolour = "red"',
     "[barrier] colour"),
    ('mass = "1100 kg"', 'mass = "1100"', "[vehicle] mass"),
    ('speed = "35 mph"', 'speed = "35 mph"\nangle = "120 deg"', "[impact] angle"),
    ('speed = "35 mph"', 'speed = "35 mph"\nangle = 60', "[impact] angle"),
    ('speed = "35 mph"', 'speed = "35 mph"\nfriction = -1', "[impact] friction"),
    ("[vehicle]", "[lorry]", "[lorry]"),
    ('speed = "35 mph"', 'speed = "35 mph"\n[extra]\nx = 1', "[extra]"),
    # Valid files for models not implemented yet: one line naming the key, status 2.
    ('plastic_moment = "1e6 lbf*in"', 'plastic_moment = "1e6 lbf*in"\naxial_capacity = "1 MN"',
     "[barrier] axial_capacity"),
]


@pytest.mark.parametrize("old, new, key", BAD)
def test_bad_scene_exits_2_with_one_line(capsys, tmp_path, old, new, key):
    assert old in SCENE
    path = write(tmp_path, SCENE.replace(old, new, 1))
    status, out, err = run(capsys, "run", str(path), "--no-plots")
    assert status == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"error: {key}"), err
    assert "Traceback" not in err


def test_unreadable_files_exit_2(capsys, tmp_path):
    status, out, err = run(capsys, "run", str(tmp_path / "nope.toml"))
    assert status == 2 and "no such file" in err and len(err.splitlines()) == 1
    path = write(tmp_path, "[barrier\n")
    status, out, err = run(capsys, "run", str(path))
    assert status == 2 and "invalid TOML" in err and len(err.splitlines()) == 1


def test_usage(capsys):
    status, out, err = run(capsys, "--help")
    assert status == 0 and "run" in out and "figures" in out and "optimize" in out
    status, out, err = run(capsys, "run", "--help")
    assert status == 0 and "--json" in out and "SCENE.toml" in out
    status, out, err = run(capsys)
    assert status == 2
    status, out, err = run(capsys, "run", "--bogus")
    assert status == 2


def test_figures_writes_the_three_files(capsys, tmp_path):
    status, out, err = run(capsys, "figures", "--out", str(tmp_path))
    assert status == 0
    names = ["fig_3_2_2.png", "fig_3_2_3.png", "fig_3_2_4.png"]
    assert out.split() == [str(tmp_path / name) for name in names]
    for name in names:
        path = tmp_path / name
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and path.stat().st_size > 10_000
        assert f"writing {path}" in err


def test_figures_registry_and_unknown_number(capsys, tmp_path):
    from barrierjax import figures

    assert list(figures.FIGURES)[:3] == ["3.2.2", "3.2.3", "3.2.4"]
    assert "Vehicle Damage" in figures.FIGURES["3.2.4"].caption
    status, out, err = run(capsys, "figures", "--out", str(tmp_path), "--only", "9.9.9")
    assert status == 2 and err.startswith("error: --only") and not list(tmp_path.iterdir())


def test_damage_bound_is_the_large_mass_limit():
    from barrierjax.figures import damage_bound

    for phi in (1.25, 2.0, 10.0):
        damage = bj.hinge.normal_impact(1e8, phi, 1.0).damage
        assert float(damage) == pytest.approx(float(damage_bound(phi)), rel=1e-6)


class _FakeReport:
    def summary(self):
        return "fake design summary"

    def as_dict(self):
        import numpy as np

        return {"objective_m": np.float64(0.02), "thickness": np.array([1.0, 2.0])}


def test_optimize_plumbing(capsys, monkeypatch):
    fake = types.ModuleType("barrierjax.design")
    fake.optimize_default = lambda: _FakeReport()
    monkeypatch.setitem(sys.modules, "barrierjax.design", fake)
    status, out, err = run(capsys, "optimize")
    assert status == 0 and out.strip() == "fake design summary"
    status, out, err = run(capsys, "optimize", "--json")
    assert status == 0 and json.loads(out) == {"objective_m": 0.02, "thickness": [1.0, 2.0]}
    monkeypatch.setitem(sys.modules, "barrierjax.design", types.ModuleType("barrierjax.design"))
    status, out, err = run(capsys, "optimize")
    assert status == 1 and err.startswith("error: optimize:") and len(err.splitlines()) == 1


def test_optimize_real(capsys):
    """The real design optimisation through the command line (about 30 s on 2 cores)."""
    status, out, err = run(capsys, "optimize", "--json")
    assert status == 0, err
    report = json.loads(out)
    assert report["feasible"] and report["constraint"] <= 0.0
    assert abs(report["relative_difference"]) <= 0.01


@pytest.mark.skipif(shutil.which("barrierjax") is None, reason="console script not installed")
def test_console_script_json(tmp_path):
    """The installed `barrierjax` script, in a fresh process: one JSON object on stdout."""
    completed = subprocess.run(
        ["barrierjax", "run", "--json", "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
    )
    assert completed.returncode == 0, completed.stderr
    data = json.loads(completed.stdout)
    check_against_simulate(data, default_scene())
    assert "Traceback" not in completed.stderr
