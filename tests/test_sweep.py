"""`barrierjax sweep` (`barrierjax.sweep`): rows equal single runs, an interrupted sweep
resumed gives the same file, the distributions, and bad sweeps refused in one line."""

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from barrierjax import Impact, Scene, simulate
from barrierjax.cli import main
from barrierjax.scene_file import default_scene
from barrierjax.sweep import Sweep, SweepError, draw, parse_vary, parts_folder, run_sweep


_MASH_3_11 = str(Path(__file__).parents[1] / "examples" / "mash_3_11.toml")


def _varies(*texts):
    return [parse_vary(t) for t in texts]


@pytest.fixture
def normal_sweep(tmp_path):
    varies = _varies("impact.speed=20 km/h:60 km/h", "vehicle.mass=1000:2500")
    return Sweep(varies, 5, seed=3, chunk=4), tmp_path / "rows.parquet"


def test_each_row_is_the_single_run_of_its_scene(normal_sweep):
    sweep, out = normal_sweep
    columns = run_sweep(default_scene(), sweep, out)
    assert out.exists() and not parts_folder(out).exists()
    base = default_scene()
    for i in range(sweep.samples):
        speed, mass = columns["impact.speed"][i], columns["vehicle.mass"][i]
        vehicle = type(base.vehicle)(mass, base.vehicle.crush_force)
        one = simulate(Scene(base.barrier, vehicle, Impact(speed)), n_history=0)
        for name in ("damage", "max_deflection", "duration", "kinetic_energy"):
            assert columns[name][i] == pytest.approx(float(getattr(one, name)), rel=1e-12)
    assert 20 / 3.6 <= columns["impact.speed"].min() and columns["impact.speed"].max() <= 60 / 3.6


def test_an_oblique_sweep_over_angles_equals_single_runs(tmp_path):
    varies = _varies("impact.angle=20:40")
    columns = run_sweep(default_scene(), Sweep(varies, 3, seed=1, chunk=2), tmp_path / "o.csv")
    base = default_scene()
    for i, angle in enumerate(columns["impact.angle"]):
        one = simulate(Scene(base.barrier, base.vehicle, Impact(base.impact.speed, angle)),
                       n_history=0)  # fmt: skip
        assert columns["exit_angle_deg"][i] == pytest.approx(float(one.exit_angle_deg), rel=1e-9)
    assert (tmp_path / "o.csv").read_text().startswith('"impact.angle"')


def test_an_oblique_sweep_solves_at_the_tolerance_it_is_given(tmp_path):
    # (The shapes of the test above: its programs run again, at another rtol, a traced one.)
    varies = _varies("impact.angle=20:40")
    sweep = Sweep(varies, 3, seed=1, chunk=2, rtol=1e-4)
    columns = run_sweep(default_scene(), sweep, tmp_path / "o.csv")
    base = default_scene()
    for i, angle in enumerate(columns["impact.angle"]):
        scene = Scene(base.barrier, base.vehicle, Impact(base.impact.speed, angle))
        loose, fine = (float(simulate(scene, n_history=0, rtol=rtol).exit_angle_deg)
                       for rtol in (1e-4, None))  # fmt: skip
        assert columns["exit_angle_deg"][i] == pytest.approx(loose, rel=1e-9)
        assert columns["exit_angle_deg"][i] != pytest.approx(fine, rel=1e-9)
        assert columns["exit_angle_deg"][i] == pytest.approx(fine, rel=1e-3)


def test_a_second_oblique_sweep_loads_the_model_it_kept(tmp_path):
    """Two processes of `barrierjax sweep` over angles on one cache folder: the second loads
    the oblique model's batch program that the first kept (`stored_program`, with the
    batch's own XLA options), and writes the same file. A sweep that ran the model inside
    a `jit` of its own compiled it in every process: its run-time checks are host
    callbacks, and JAX's persistent cache keeps no program that holds one."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "BARRIERJAX_CACHE_DIR": str(tmp_path / "cache"), "JAX_LOG_COMPILES": "1"}

    def sweep(name):
        out = tmp_path / f"{name}.parquet"
        completed = subprocess.run(
            [sys.executable, "-c", "from barrierjax.cli import command; command()", "sweep",
             "--vary", "impact.angle=10:40", "--samples", "64", "--out", str(out), "--no-plots"],
            capture_output=True, text=True, env=env, cwd=tmp_path, timeout=300, check=False,
        )  # fmt: skip
        assert completed.returncode == 0, completed.stderr[-2000:]
        return completed.stderr, out

    (first, first_out), (second, second_out) = sweep("first"), sweep("second")
    assert "jit(stored_solved)" in first and "jit(stored_solved)" not in second
    assert "jit(solve)" not in first + second  # the sweep's own program of old
    _assert_same_rows(second_out, first_out)


def test_an_interrupted_sweep_resumed_gives_the_same_file(normal_sweep, tmp_path):
    sweep, out = normal_sweep
    finished = []

    def stop_after_one(rows):
        finished.append(rows)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep(default_scene(), sweep, out, progress=stop_after_one)
    parts = parts_folder(out)
    assert [p.name for p in sorted(parts.glob("part-*"))] == ["part-00000.parquet"]
    with pytest.raises(SweepError, match="--resume"):
        run_sweep(default_scene(), sweep, out)
    with pytest.raises(SweepError, match="different sweep"):
        run_sweep(default_scene(), Sweep(sweep.varies, 6, 3, chunk=4), out, resume=True)
    with pytest.raises(SweepError, match="different sweep"):  # another tolerance
        run_sweep(default_scene(), Sweep(sweep.varies, 5, 3, chunk=4, rtol=1e-6), out,
                  resume=True)  # fmt: skip
    run_sweep(default_scene(), sweep, out, resume=True)
    whole = tmp_path / "whole.parquet"
    run_sweep(default_scene(), sweep, whole)
    assert pq.read_table(out).equals(pq.read_table(whole))


def test_the_distributions_draw_within_the_range():
    varies = _varies("impact.speed=10:20", "vehicle.mass=1000:2000")
    lhs = draw(varies, 50, seed=0, distribution="lhs")
    for j, v in enumerate(varies):
        strata = np.floor((lhs[:, j] - v.low) / (v.high - v.low) * 50).astype(int)
        assert sorted(strata) == list(range(50))  # each stratum once
    normal = draw(varies, 20000, seed=0, distribution="normal")
    assert np.all((normal >= [10, 1000]) & (normal <= [20, 2000]))
    assert normal[:, 0].mean() == pytest.approx(15.0, abs=0.05)
    assert normal[:, 0].std() == pytest.approx(2.5 * 0.98, rel=0.05)  # clipped beyond 2 sd
    assert np.array_equal(draw(varies, 5, 7), draw(varies, 5, 7))


@pytest.mark.parametrize(
    "args, message",
    [
        (["--vary", "impact.sped=1:2"], "--vary 'impact.sped': unknown key"),
        (["--vary", "impact.speed=60 km/h:20 km/h"], "--vary impact.speed: empty range"),
        (["--vary", "impact.speed=20 kg:30 kg"], "--vary impact.speed: expected a speed"),
        (["--vary", "impact.speed"], "--vary impact.speed: expected impact.speed=LOW:HIGH"),
        (["--vary", "impact.speed=1:2", "--distribution", "beta"], "--distribution: unknown"),
        (["--vary", "impact.speed=1:2", "--samples", "0"], "--samples must be a positive"),
        (
            ["--vary", "impact.speed=1:2", "--vary", "impact.speed=3:4"],
            "--vary impact.speed: given twice",
        ),
        (["--vary", "impact.speed=1:2", "--out", "rows.txt"], "--out rows.txt: name a .parquet"),
        (["--vary", "impact.speed=1:2", "--rtol", "0"], "--rtol must be in (0, 1); got 0"),
        (["--vary", "impact.speed=1:2", "--rtol", "2"], "--rtol must be in (0, 1); got 2"),
        (
            [_MASH_3_11, "--vary", "barrier.post_spacing=1.5:2", "--rtol", "1e-6"],
            "--rtol: a barrier-system scene steps at its own fixed time step",
        ),
        # A range is put through the scene's rules at both ends before anything is drawn.
        (
            ["--vary", "impact.friction=-1:1"],
            "--vary impact.friction: LOW -1: Impact.friction must be non-negative",
        ),
        (
            ["--vary", "impact.angle=60 deg:120 deg"],
            "--vary impact.angle: HIGH 120 deg: Impact.angle_deg must be in (0, 90]",
        ),
        (
            ["--vary", "vehicle.mass=-1000:2000"],
            "--vary vehicle.mass: LOW -1000 kg: Vehicle.mass must be positive",
        ),
    ],
)
def test_bad_sweeps_exit_2_with_one_line_and_write_nothing(capsys, tmp_path, args, message):
    out = tmp_path / "rows.parquet"
    full = ["sweep", "--samples", "10", "--out", str(out), *args]
    assert main(full) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"error: {message}")
    assert not out.exists() and not parts_folder(out).exists()


def test_a_scenario_the_model_cannot_solve_exits_1_naming_its_row(capsys, tmp_path, monkeypatch):
    # The model's own error names the scenario within the chunk; the sweep names the row,
    # its values and where the finished chunks are.
    from barrierjax import sweep as sweep_module
    from barrierjax.hinge import SolveError

    calls = []

    def second_chunk_fails(batch, **options):
        calls.append(batch)
        if len(calls) % 2 == 0:
            raise SolveError(
                "model: the phase spent its step budget (scenario 1 of 3)",
                {1: "model: the phase spent its step budget"},
            )
        return simulate(batch, **options)

    monkeypatch.setattr(sweep_module, "simulate", second_chunk_fails)
    out = tmp_path / "rows.parquet"
    args = ["--vary", "impact.speed=20:60", "--samples", "6", "--seed", "3", "--chunk", "3"]
    assert main(["sweep", *args, "--out", str(out), "--no-plots"]) == 1
    speed = draw(_varies("impact.speed=20:60"), 6, 3)[4, 0]
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (
        f"error: row 4 (impact.speed={speed:.6g}): model: the phase spent its step budget "
        f"(scenario 1 of 3); the finished chunks are in {parts_folder(out)}: --resume "
        "carries on"
    )
    assert [p.name for p in parts_folder(out).glob("part-*")] == ["part-00000.parquet"]
    assert not out.exists()
    # Called from Python, the error's failures are by the sweep's rows.
    sweep = Sweep(_varies("impact.speed=20:60"), 6, 3, chunk=3)
    with pytest.raises(SolveError) as raised:
        run_sweep(default_scene(), sweep, tmp_path / "again.parquet")
    assert raised.value.failures == {4: "model: the phase spent its step budget"}
    assert raised.value.scenario == 4


def test_skipped_failures_are_rows_of_nulls_and_the_rest_are_solved(capsys, tmp_path, monkeypatch):
    # One scenario "fails" wherever it is in a chunk: it is replaced, the chunk solved again,
    # and its row holds nulls and the error; every other row is the sweep's without it.
    from barrierjax import sweep as sweep_module
    from barrierjax.hinge import SolveError

    varies = _varies("impact.speed=20:60")
    bad = draw(varies, 6, 3)[4, 0]

    def failing_at_the_bad_speed(batch, **options):
        at = np.flatnonzero(np.asarray(batch.impact.speed) == bad)
        if at.size:
            raise SolveError(f"model: it failed (scenario {at[0]} of 3)", {int(at[0]): "it failed"})
        return simulate(batch, **options)

    args = ["--vary", "impact.speed=20:60", "--samples", "6", "--seed", "3", "--chunk", "3"]
    plain = tmp_path / "plain.parquet"
    assert main(["sweep", *args, "--out", str(plain), "--no-plots"]) == 0
    monkeypatch.setattr(sweep_module, "simulate", failing_at_the_bad_speed)
    out = tmp_path / "rows.parquet"
    assert main(["sweep", *args, "--out", str(out), "--no-plots", "--skip-failures"]) == 0
    assert "1 could not be solved" in capsys.readouterr().out
    rows, expected = pq.read_table(out).to_pydict(), pq.read_table(plain).to_pydict()
    assert rows.pop("failure") == ["", "", "", "", "it failed", ""]
    assert rows["impact.speed"] == expected["impact.speed"]
    assert rows["damage"][4] is None and rows["duration"][4] is None
    for name, values in rows.items():
        assert values[:4] + values[5:] == expected[name][:4] + expected[name][5:], name


def test_skipped_failures_keep_the_rows_a_model_solved_before_it_raised(tmp_path, monkeypatch):
    # A model that solved the chunk before it raised (`SolveError.result`) is not called
    # again: its other rows are kept as solved, the failed one is a row of nulls.
    from barrierjax import sweep as sweep_module
    from barrierjax.hinge import SolveError

    varies = _varies("impact.speed=20:60")
    plain = run_sweep(default_scene(), Sweep(varies, 6, 3, chunk=3), tmp_path / "plain.parquet")
    calls = []

    def fails_at_row_1_after_solving(batch, **options):
        calls.append(batch)
        result = simulate(batch, **options)
        raise SolveError("model: it failed (scenario 1 of 3)", {1: "it failed"}, result)

    monkeypatch.setattr(sweep_module, "simulate", fails_at_row_1_after_solving)
    sweep = Sweep(varies, 6, 3, chunk=3, skip_failures=True)
    rows = run_sweep(default_scene(), sweep, tmp_path / "rows.parquet")
    assert len(calls) == 2  # one a chunk
    assert list(rows["failure"]) == ["", "it failed", "", "", "it failed", ""]
    for name in ("damage", "duration", "max_deflection"):
        assert [rows[name][k] for k in (0, 2, 3, 5)] == [plain[name][k] for k in (0, 2, 3, 5)]
        assert np.isnan(rows[name][1]) and np.isnan(rows[name][4])


def test_an_unwritable_output_is_refused_in_one_line(capsys, tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("")
    out = blocked / "rows.parquet"  # a folder that is a file
    assert main(["sweep", "--vary", "impact.speed=1:2", "--samples", "4", "--out", str(out)]) == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].startswith(f"error: --out {out}")


# The sweep that several devices or processes solve, against one.
DEVICE_SWEEP = ["sweep", "--vary", "impact.speed=20 km/h:60 km/h", "--vary",
                "vehicle.mass=1000:2500", "--samples", "100", "--chunk", "64", "--no-plots"]  # fmt: skip


def _assert_same_rows(path, reference):
    """The two files hold the same columns, equal to 1e-12."""
    a, b = pq.read_table(path), pq.read_table(reference)
    assert a.column_names == b.column_names
    for name in a.column_names:
        np.testing.assert_allclose(a.column(name).to_numpy(), b.column(name).to_numpy(),
                                   rtol=1e-12, atol=0)  # fmt: skip


def test_four_emulated_devices_give_the_rows_of_one(tmp_path):
    """The chunk's rows sharded over 4 host-emulated devices (a process of its own:
    the device count is fixed at start-up) against this process's one device."""
    import os
    import subprocess
    import sys

    args = DEVICE_SWEEP
    four = tmp_path / "four.parquet"
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=4"}
    code = ("import jax, sys; from barrierjax.cli import main; assert jax.local_device_count() "
            "== 4; sys.exit(main(sys.argv[1:]))")  # fmt: skip
    subprocess.run([sys.executable, "-c", code, *args, "--out", str(four)], env=env, check=True,
                   capture_output=True, timeout=300)  # fmt: skip
    one = tmp_path / "one.parquet"
    assert main([*args, "--out", str(one)]) == 0
    _assert_same_rows(four, one)


def test_a_chunk_in_parts_on_the_cores_gives_the_rows_of_one(tmp_path, monkeypatch):
    """A chunk of 2,100 rows solved in two parts side by side (`rows_in_parts`) against the
    same chunk whole (`BARRIERJAX_PARTS=1`)."""
    from barrierjax._solve import batching

    monkeypatch.setattr(batching.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    args = [*DEVICE_SWEEP[:-5], "--samples", "2100", "--chunk", "2100", "--no-plots"]
    parts = tmp_path / "parts.parquet"
    assert main([*args, "--out", str(parts)]) == 0
    monkeypatch.setenv("BARRIERJAX_PARTS", "1")
    whole = tmp_path / "whole.parquet"
    assert main([*args, "--out", str(whole)]) == 0
    _assert_same_rows(parts, whole)


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("localhost", 0))
        return s.getsockname()[1]


def test_two_processes_of_jax_distributed_give_the_rows_of_one(tmp_path):
    """Two processes joined by `jax.distributed` (gloo collectives between them on this
    CPU), two emulated devices each: every chunk's rows sharded over the four devices of
    both; process 0 alone writes the file, which equals this process's one-device sweep."""
    import os
    import subprocess
    import sys

    args = DEVICE_SWEEP
    two = tmp_path / "two.parquet"
    env = {**os.environ, "XLA_FLAGS": "--xla_force_host_platform_device_count=2"}
    code = ("import jax, sys; from barrierjax.cli import main; status = main(sys.argv[1:]); "
            "assert jax.process_count() == 2 and jax.device_count() == 4; sys.exit(status)")  # fmt: skip
    address = f"localhost:{_free_port()}"
    processes = [
        subprocess.Popen([sys.executable, "-c", code, *args, "--out", str(two), "--coordinator",
                          address, "--processes", "2", "--process-id", str(i)], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        for i in range(2)
    ]  # fmt: skip
    try:
        outputs = [p.communicate(timeout=300) for p in processes]
    finally:
        for p in processes:
            p.kill()  # where one hung: its peer waits for it
    for p, (out, err) in zip(processes, outputs):
        assert p.returncode == 0, err[-2000:]
    # Process 0 sums up, alone (gloo prints its connections to stdout in both).
    assert "scenarios in" in outputs[0][0] and "scenarios in" not in outputs[1][0]
    one = tmp_path / "one.parquet"
    assert main([*args, "--out", str(one)]) == 0
    _assert_same_rows(two, one)


SYSTEM_SCENE = """test = "MASH 3-11"
[vehicle]
preset = "2270P"
[barrier]
preset = "MGS"
length = "30.48 m"
elements_per_span = 4
[impact]
point = "10 m"
duration = "0.15 s"
"""


def test_a_barrier_system_sweep_equals_single_runs_of_the_redesigned_system(tmp_path):
    """Speed, post spacing and vehicle mass varied on a MASH 3-11 scene: each row is
    `crash_numbers` of the system `redesign` gives, at the stable step of the shortest
    spacing."""
    from barrierjax.scene_file import read_toml
    from barrierjax.system import stable_step
    from barrierjax.system.design import crash_numbers, redesign
    from barrierjax.system.scene import parse_system_scene
    from barrierjax.system.sweep import SWEEP_FIELDS
    from barrierjax.system.vehicle import contact_stiffness_bound

    path = tmp_path / "mash.toml"
    path.write_text(SYSTEM_SCENE)
    scene = parse_system_scene(read_toml(path))
    texts = ("impact.speed=90 km/h:110 km/h", "barrier.post_spacing=1.5:2.0",
             "vehicle.mass=2000:2500")  # fmt: skip
    varies = [parse_vary(t, SWEEP_FIELDS) for t in texts]
    columns = run_sweep(scene, Sweep(varies, 2, seed=5, chunk=2), tmp_path / "rows.parquet")
    _, stiffest = redesign(scene.vehicle, scene.barrier, post_spacing=1.5)
    dt = stable_step(stiffest, contact_stiffness_bound(scene.vehicle))
    for i in range(2):
        vehicle, barrier = redesign(scene.vehicle, scene.barrier,
                                    vehicle_mass=columns["vehicle.mass"][i],
                                    post_spacing=columns["barrier.post_spacing"][i])  # fmt: skip
        one = crash_numbers(vehicle, barrier, speed=columns["impact.speed"][i],
                            angle_deg=scene.angle_deg, impact_point=scene.impact_point,
                            duration=scene.duration, dt=dt, friction=scene.friction)  # fmt: skip
        for name in ("dynamic_deflection", "working_width", "oiv_y", "exit_angle"):
            assert columns[name][i] == pytest.approx(float(one[name]), rel=1e-9)
    with pytest.raises(SweepError, match="unknown key"):
        parse_vary("barrier.backing_strength=1:2", SWEEP_FIELDS)


def test_chunks_do_not_depend_on_the_devices_and_a_bad_chunk_is_refused(tmp_path):
    """The files' layout is the sweep's alone (a sweep resumed on another device count
    finds its chunks where it left them)."""
    varies = _varies("impact.speed=10:20")
    out = tmp_path / "rows.parquet"
    with pytest.raises(KeyboardInterrupt):
        run_sweep(default_scene(), Sweep(varies, 7, 0, chunk=3), out,
                  progress=lambda n: (_ for _ in ()).throw(KeyboardInterrupt))  # fmt: skip
    assert len(pq.read_table(parts_folder(out) / "part-00000.parquet")) == 3  # chunks of 3, 3 and 1
    with pytest.raises(SweepError, match="--chunk must be a positive integer"):
        run_sweep(default_scene(), Sweep(varies, 7, 0, chunk=0), tmp_path / "other.parquet")
