"""Benchmark of `barrierjax sweep`: scenarios per second through the command, against the
model's own vmapped call.

    python benchmarks/sweep.py [--quick] [--out DIR]

(1) `barrierjax sweep` on the default scene, 10^6 normal impacts (speed 20-60 km/h, mass
1000-2500 kg), wall time of the whole command in a fresh process (start-up, compilation,
chunks, the Parquet file; no plot), twice (the second with the compilation cache warm);
(2) the same number of scenarios as one `barrierjax.simulate` call on arrays after
compilation (what a user writes by hand with vmap); (3) the same for 10^5 oblique impacts
(angle 10-40 degrees); (4) the sweep's first call in a fresh process and its peak memory
(one chunk of 65,536). Writes `sweep.json` to `--out`.
"""

import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness import argument_parser, first_calls, table, write_json

COMMAND = [sys.executable, "-c", "import sys; from barrierjax.cli import command; command()"]
VARY = {
    "normal": ["--vary", "impact.speed=20 km/h:60 km/h", "--vary", "vehicle.mass=1000:2500"],
    "oblique": ["--vary", "impact.angle=10:40"],
}


def command_wall(kind, n, folder) -> float:
    out = Path(folder) / f"{kind}-{n}-{time.monotonic_ns()}.parquet"
    start = time.perf_counter()
    subprocess.run([*COMMAND, "sweep", *VARY[kind], "--samples", str(n), "--out", str(out),
                    "--no-plots"], check=True, capture_output=True)  # fmt: skip
    return time.perf_counter() - start


def direct(kind, n) -> float:
    """One `simulate` call on arrays of n scenarios, after compiling it (the best of 2)."""
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
    run = jax.jit(lambda sc: simulate(sc, n_history=0, **options))  # every field, as the sweep
    jax.block_until_ready(run(scene))
    times = []
    for _ in range(2):
        start = time.perf_counter()
        jax.block_until_ready(run(scene))
        times.append(time.perf_counter() - start)
    return min(times)


def main():
    args = argument_parser(__doc__).parse_args()
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


if __name__ == "__main__":
    main()
