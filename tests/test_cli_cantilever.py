"""`barrierjax run cantilever-N` (the report's Examples of 4.3), their plots, and figures
4.3.2-4.3.7, on short runs of coarse meshes (the full runs take 10-40 s each)."""

import json
import types

import jax
import numpy as np
import pytest

jax.config.update("jax_enable_x64", True)

from barrierjax import cli, figures
from barrierjax.beam import report_example, tip_rest
from barrierjax.beam.examples import plastic_moment
from barrierjax.beam.plots import deformed_shape
from barrierjax.figures import chapter4

SHORT = ("--t-end", "0.016", "--dt", "2e-4", "--elements", "3")
PNG = b"\x89PNG\r\n\x1a\n"


def run(capsys, *argv):
    status = cli.main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture(scope="module")
def short_runs():
    """Example 3 over 16 ms on 3 elements, with both laws (the tip comes to rest at ~13 ms)."""
    return {
        "Cowper-Symonds": report_example(3, t_end=0.016, dt=2e-4, n_elements=3),
        "rate-independent": report_example(
            3, rate_dependent=False, t_end=0.016, dt=2e-4, n_elements=3
        ),
    }


def test_run_cantilever_json_matches_report_example(capsys, tmp_path, short_runs):
    status, out, err = run(capsys, "run", "cantilever-3", *SHORT, "--json", "--out", str(tmp_path))
    assert status == 0, err
    data = json.loads(out)
    result = short_runs["Cowper-Symonds"]
    rest = tip_rest(result)
    assert 0 < rest.index < len(result.times) - 1
    assert data["example"] == 3 and data["scheme"] == "damped-newmark"
    assert data["n_elements"] == 3 and data["saved_steps"] == 85
    assert data["end_time_s"] == pytest.approx(0.016, rel=1e-12)
    np.testing.assert_allclose(
        data["final_tip_displacement_in"], np.asarray(result.tip_displacement[-1]), rtol=1e-12
    )
    assert data["final_root_rotation_rad"] == pytest.approx(float(result.root_rotation[-1]))
    assert data["tip_rest_time_s"] == pytest.approx(rest.time)
    np.testing.assert_allclose(data["tip_rest_displacement_in"], rest.tip_displacement)
    M0 = 29000.0 * 0.644 * 0.177**2 / 4
    assert data["plastic_moment_lb_in"] == pytest.approx(M0)
    # rate-dependent: the root moment exceeds the static plastic moment
    assert data["peak_root_moment_lb_in"] > M0
    assert data["max_newton_residual"] < 1e-8
    assert data["inputs"]["impulse_lb_s"] == 0.075 and data["inputs"]["tip_mass_lb_s2_in"] == 0
    assert "did not converge" not in cli.format_cantilever_summary(data)
    unconverged = dict(data, max_newton_residual=1e-3)
    assert "warning: Newton did not converge" in cli.format_cantilever_summary(unconverged)
    names = ["deformed_shape.png", "tip_histories.png", "root_histories.png"]
    assert data["plots"] == [str(tmp_path / name) for name in names]
    for name in names:
        assert (tmp_path / name).read_bytes()[:8] == PNG
        assert f"writing {tmp_path / name}" in err


def test_run_cantilever_summary_rate_independent(capsys, tmp_path, short_runs):
    status, out, err = run(
        capsys,
        "run",
        "cantilever-3",
        *SHORT,
        "--rate-independent",
        "--no-plots",
        "--out",
        str(tmp_path),
    )
    assert status == 0, err
    assert "elastic-perfectly plastic" in out and "Example 3 of report 4.3" in out
    result = short_runs["rate-independent"]
    final = np.asarray(result.tip_displacement[-1])
    assert f"at the end   {final[1]:10.3f} in transverse, {final[0]:.3f} in axial" in out
    assert ("has not come to rest" in out) == (tip_rest(result).index < 0)
    assert "Plots" not in out and not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    "argv, message",
    [
        (("cantilever-4",), "error: cantilever-4: n must be one of (1, 2, 3)"),
        (("cantilever-3", "--dt=-1e-3"), "error: --dt must be positive and finite"),
        (("cantilever-3", "--t-end", "nan"), "error: --t-end must be positive and finite"),
        (("cantilever-3", "--elements", "0"), "error: --elements must be a positive integer"),
        (("--dt", "1e-3"), "error: --dt applies to 'run cantilever-N' only"),
        (("--rate-independent",), "error: --rate-independent applies to"),
    ],
)
def test_bad_cantilever_options_exit_2_with_one_line(capsys, argv, message):
    status, out, err = run(capsys, "run", *argv, "--no-plots")
    assert status == 2 and out == ""
    assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_unknown_scheme_is_a_usage_error(capsys):
    status, _, err = run(capsys, "run", "cantilever-1", "--scheme", "euler")
    assert status == 2 and "invalid choice: 'euler'" in err


def test_tip_rest_is_the_zero_of_velocity_at_the_largest_deflection():
    times = np.linspace(0.0, 1.0, 11)
    velocity = np.array([0.0, 5.0, 4.0, 3.0, 2.0, 1.0, -1.0, -2.0, -1.0, 0.5, -0.5])
    # the trapezoidal integral of the velocity: largest at indices 5 and 6 (1.45)
    deflection = np.concatenate([[0.0], np.cumsum(0.05 * (velocity[1:] + velocity[:-1]))])
    fake = types.SimpleNamespace(
        times=times,
        tip_velocity=np.stack([np.zeros(11), velocity], axis=1),
        tip_displacement=np.stack([-times, deflection], axis=1),
        root_rotation=times**2,
    )
    rest = tip_rest(fake)
    assert rest.index == 6 and rest.time == pytest.approx(0.55)
    np.testing.assert_allclose(rest.tip_displacement, [-0.55, 1.45])
    assert rest.root_rotation == pytest.approx((0.25 + 0.36) / 2)
    fake.tip_displacement = np.stack([-times, times], axis=1)  # still rising at the end
    assert tip_rest(fake).index == -1 and np.isnan(tip_rest(fake).time)


def test_deformed_shape_passes_through_the_nodes(short_runs):
    result = short_runs["Cowper-Symonds"]
    straight = deformed_shape(result, 0)
    np.testing.assert_allclose(straight[:, 1], 0.0, atol=1e-15)
    np.testing.assert_allclose(straight[[0, -1], 0], [0.0, 14.0])
    k = len(result.times) - 1
    shape = deformed_shape(result, k, points_per_element=5)
    nodes = np.asarray(result.node_coordinates[k])
    np.testing.assert_allclose(shape[::4], nodes, atol=1e-12)
    # between the nodes the curve bends the way the nodes' rotations say (tip deflected up)
    assert shape[-1, 1] > 0 and np.all(np.diff(shape[:, 0]) > 0)


def test_figures_4_3_registered_and_drawn(capsys, tmp_path, monkeypatch, short_runs):
    numbers = ["4.3.2", "4.3.3", "4.3.4", "4.3.5", "4.3.6", "4.3.7"]
    assert list(figures.FIGURES)[-6:] == numbers
    assert figures.FIGURES["4.3.2"].printed and not figures.FIGURES["4.3.7"].printed
    assert "Free End" in figures.FIGURES["4.3.7"].caption
    # the full examples take minutes; the drawing is checked on the short runs
    monkeypatch.setattr(chapter4, "example_runs", lambda n: short_runs)
    status, _, err = run(capsys, "figures", "--out", str(tmp_path), "--only", *numbers)
    assert status == 0, err
    for number in numbers:
        path = tmp_path / f"fig_{number.replace('.', '_')}.png"
        assert path.read_bytes()[:8] == PNG and path.stat().st_size > 10_000


def test_plastic_moment():
    assert plastic_moment(2) == pytest.approx(44000.0 * 0.312 * 0.053**2 / 4)
    assert plastic_moment(1, sigma0=1.0) == pytest.approx(0.644 * 0.177**2 / 4)
