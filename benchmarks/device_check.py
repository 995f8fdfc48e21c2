"""The checks that need an accelerator, as one short script for a lent GPU (the `device`
tool of this workplace; see benchmarks/README.md): what the 2-core CPU cannot show.

    python benchmarks/device_check.py [--out DIR]

(1) Sweeps (issue 31): 10^6 normal impacts of the default scene through `run_sweep`
(speed 20-60 km/h, mass 1000-2500 kg; first call, compilation included, and again), and
one `simulate` call on the same arrays; 10^4 oblique impacts likewise. (2) The beam
(issue 28): 64 vmapped variants of the rate-dependent Example 1 against one run
(`beam_fe.vmap_variants`, 50 steps). Prints the device, the tables, and writes
`device_check.json` to `--out`.
"""

import tempfile
import time
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

from harness import argument_parser, table, write_json


def timed(fn, *args):
    start = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - start


def sweeps() -> list[dict]:
    from sweep import direct

    from barrierjax.scene_file import default_scene
    from barrierjax.sweep import Sweep, parse_vary, run_sweep

    s = default_scene()
    rows = []
    cases = {
        "normal": (10**6, ["impact.speed=20 km/h:60 km/h", "vehicle.mass=1000:2500"]),
        "oblique": (10**4, ["impact.angle=10:40"]),
    }
    for kind, (n, varies) in cases.items():
        sweep = Sweep([parse_vary(v) for v in varies], n, 0)
        with tempfile.TemporaryDirectory() as folder:
            _, first = timed(run_sweep, s, sweep, Path(folder) / "a.parquet")
            _, again = timed(run_sweep, s, sweep, Path(folder) / "b.parquet")
        call = direct(kind, n)  # benchmarks/sweep.py's: the same scenarios as one call
        rows.append({"kind": kind, "n": n, "first_s": first, "again_s": again, "call_s": call,
                     "us_sweep": 1e6 * again / n, "us_call": 1e6 * call / n})  # fmt: skip
    return rows


def main():
    args = argument_parser(__doc__).parse_args()
    device = str(jax.devices()[0])
    print(f"device: {device}; jax {jax.__version__}")
    rows = sweeps()
    table(
        f"Sweeps on {device} (run_sweep in one process: first call with compilation, then again)",
        rows,
        [("model", "kind", "s"), ("scenarios", "n", "d"), ("sweep s, first", "first_s", ".1f"),
         ("sweep s, again", "again_s", ".2f"), ("one call s", "call_s", ".3f"),
         ("us / scenario, sweep", "us_sweep", ".2f"), ("us / scenario, call", "us_call", ".3f")],
    )  # fmt: skip
    import beam_fe

    beam = beam_fe.vmap_variants(beam_fe.config(args.quick))
    table(
        f"Beam, rate-dependent Example 1 on {device}: {beam['variants']} variants in one vmap "
        f"({beam['steps']} steps) against one run",
        [beam],
        [("variants", "variants", "d"), ("one run s", "single_s", ".3f"),
         ("vmapped s", "batch_s", ".3f"), ("vmapped / one run", "ratio", ".2f"),
         ("vmap vs single", "vmap_vs_single", ".1e")],
    )  # fmt: skip
    write_json(args, "device_check", {"device": device, "jax": jax.__version__,
                                      "sweeps": rows, "beam_vmap": beam})  # fmt: skip


if __name__ == "__main__":
    main()
