"""Benchmark of `barrierjax sweep`: scenarios per second through the command, against the
model's own vmapped call.

    python benchmarks/sweep.py [--quick] [--out DIR]

(1) `barrierjax sweep` on the default scene, 10^6 normal impacts (speed 20-60 km/h, mass
1000-2500 kg), wall time of the whole command in a fresh process (start-up, compilation,
chunks, the Parquet file; no plot), twice (the second with the compilation cache warm);
(2) the same number of scenarios as one `barrierjax.simulate` call on arrays after
compilation (what a user writes by hand; not inside a `jit` of the caller's, where a batch
is solved whole and the oblique model's about 2.7 times slower); (3) the same for 10^5 oblique impacts
(angle 10-40 degrees); (4) the sweep's first call in a fresh process and its peak memory
(one chunk of 65,536); (5) 10^3 barrier-system impacts of `examples/mash_3_11.toml`
(speed 90-110 km/h, angle 20-30 degrees, post spacing 1.7-2.1 m; chunks of 64) through the
command once, against one vmapped `system_solver` call on 64 of them, and that chunk's first
call and peak memory in a fresh process. `--system-only` runs (5) alone (about 15 min on 2
cores). Writes `sweep.json` (`sweep_system.json`) to `--out`.
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import argument_parser, first_calls, table, write_json

COMMAND = [sys.executable, "-c", "import sys; from barrierjax.cli import command; command()"]
SYSTEM_SCENE = str(Path(__file__).resolve().parents[1] / "examples" / "mash_3_11.toml")
SYSTEM_CHUNK = 64
VARY = {
    "normal": ["--vary", "impact.speed=20 km/h:60 km/h", "--vary", "vehicle.mass=1000:2500"],
    "oblique": ["--vary", "impact.angle=10:40"],
    "system": [SYSTEM_SCENE, "--vary", "impact.speed=90 km/h:110 km/h", "--vary",
               "impact.angle=20:30", "--vary", "barrier.post_spacing=1.7:2.1",
               "--chunk", str(SYSTEM_CHUNK)],
}  # fmt: skip


def command_wall(kind, n, folder) -> float:
    out = Path(folder) / f"{kind}-{n}-{time.monotonic_ns()}.parquet"
    start = time.perf_counter()
    subprocess.run([*COMMAND, "sweep", *VARY[kind], "--samples", str(n), "--out", str(out),
                    "--no-plots"], check=True, capture_output=True)  # fmt: skip
    return time.perf_counter() - start


_SYSTEM_SETUP = f"""
    import numpy as np
    from barrierjax.scene_file import read_toml
    from barrierjax.system.scene import parse_system_scene
    from barrierjax.system.sweep import system_solver
    from barrierjax.sweep import parse_vary
    from barrierjax.system.sweep import SWEEP_FIELDS
    scene = parse_system_scene(read_toml({SYSTEM_SCENE!r}))
    varies = [parse_vary(v, SWEEP_FIELDS) for v in ("impact.speed=90 km/h:110 km/h",
              "impact.angle=20:30", "barrier.post_spacing=1.7:2.1")]
    rows = np.random.default_rng(0).uniform([v.low for v in varies], [v.high for v in varies],
                                            ({SYSTEM_CHUNK}, 3))
    solve = system_solver(scene, varies)
"""


def direct_system() -> float:
    """One vmapped `system_solver` call on a chunk of the system sweep, after compiling it."""
    import textwrap

    namespace = {}
    exec(textwrap.dedent(_SYSTEM_SETUP), namespace)  # noqa: S102 - the benchmark's own code
    solve, rows = namespace["solve"], namespace["rows"]
    solve(rows)
    start = time.perf_counter()
    solve(rows)
    return time.perf_counter() - start


def system_main(args):
    n = 128 if args.quick else 1000
    with tempfile.TemporaryDirectory() as folder:
        wall = command_wall("system", n, folder)
    call = direct_system()
    row = {"n": n, "command_s": wall, "us_sweep": 1e6 * wall / n,
           "call_s": call, "us_call": 1e6 * call / SYSTEM_CHUNK,
           "ratio": (wall / n) / (call / SYSTEM_CHUNK)}  # fmt: skip
    table(
        f"barrierjax sweep of barrier-system impacts (MASH 3-11 scene, chunks of "
        f"{SYSTEM_CHUNK}) against one vmapped call on a chunk",
        [row],
        [("scenarios", "n", "d"), ("command s, first", "command_s", ".0f"),
         ("us / scenario, sweep", "us_sweep", ".0f"), ("one chunk's call s", "call_s", ".1f"),
         ("us / scenario, call", "us_call", ".0f"), ("sweep / call", "ratio", ".2f")],
    )  # fmt: skip
    first = first_calls({f"system sweep chunk ({SYSTEM_CHUNK} impacts)":
                         (_SYSTEM_SETUP, "solve(rows)")})  # fmt: skip
    write_json(args, "sweep_system", {"system": row, "first_call": first})


def direct(kind, n) -> float:
    """One `simulate` call on arrays of n scenarios, after its first (the best of 2)."""
    import jax

    jax.config.update("jax_enable_x64", True)
    import jax.numpy as jnp
    import numpy as np

    from barrierjax import Impact, Scene, Vehicle, simulate
    from barrierjax.scene_file import default_scene

    rng = np.random.default_rng(0)
    s = default_scene()
    if kind == "normal":
        speed, mass = rng.uniform(20 / 3.6, 60 / 3.6, n), rng.uniform(1000, 2500, n)
        scene = Scene(s.barrier, Vehicle(jnp.asarray(mass), s.vehicle.crush_force),
                      Impact(jnp.asarray(speed)))  # fmt: skip
        options = {}
    else:
        angle = rng.uniform(10, 40, n)
        scene = Scene(s.barrier, s.vehicle, Impact(s.impact.speed, jnp.asarray(angle)))
        options = {"oblique": True}
    run = lambda sc: simulate(sc, n_history=0, **options)  # every field, as the sweep
    jax.block_until_ready(run(scene))
    times = []
    for _ in range(2):
        start = time.perf_counter()
        jax.block_until_ready(run(scene))
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    parser = argument_parser(__doc__)
    parser.add_argument("--system-only", action="store_true", help="run part (5) alone")
    args = parser.parse_args()
    if args.system_only:
        return system_main(args)
    sizes = {"normal": 10**4, "oblique": 10**3} if args.quick else {"normal": 10**6,
                                                                    "oblique": 10**5}  # fmt: skip
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for kind, n in sizes.items():
            cold, warm = command_wall(kind, n, folder), command_wall(kind, n, folder)
            call = direct(kind, n)
            rows.append({"kind": kind, "n": n, "cold_s": cold, "warm_s": warm, "direct_s": call,
                         "us_sweep": 1e6 * warm / n, "us_direct": 1e6 * call / n,
                         "ratio": warm / call})  # fmt: skip
    table(
        "barrierjax sweep (whole command, fresh process) against one simulate call on arrays",
        rows,
        [("model", "kind", "s"), ("scenarios", "n", "d"), ("command s, first", "cold_s", ".1f"),
         ("command s, cache warm", "warm_s", ".1f"), ("one call s", "direct_s", ".2f"),
         ("us / scenario, sweep", "us_sweep", ".2f"), ("us / scenario, call", "us_direct", ".2f"),
         ("sweep / call", "ratio", ".1f")],
    )  # fmt: skip
    setup = """
        import jax.numpy as jnp
        from barrierjax.scene_file import default_scene
        from barrierjax.sweep import Sweep, parse_vary, run_sweep
        import tempfile, os
        folder = tempfile.mkdtemp()
        varies = [parse_vary("impact.speed=20 km/h:60 km/h"), parse_vary("vehicle.mass=1000:2500")]
    """
    call = "run_sweep(default_scene(), Sweep(varies, 65536, 0), os.path.join(folder, 'r.parquet'))"
    first = first_calls({"sweep of one chunk (65,536 normal impacts)": (setup, call)})
    write_json(args, "sweep", {"sweeps": rows, "first_call": first})
    system_main(args)


if __name__ == "__main__":
    main()
