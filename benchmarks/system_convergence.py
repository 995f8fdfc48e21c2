"""Mesh and step convergence of the barrier-system model on MASH tests 3-11 and 3-10.

    python benchmarks/system_convergence.py [--quick] [--out DIR]

The scenes of `examples/mash_3_11.toml` and `examples/mash_3_10.toml` (1.0 s each) with 2,
4, 8 (the scenes' own), 16 and 32 elements between posts at the stable step, and with 8
elements at a half and a quarter of it: the crash-test numbers and the energy audit's largest
remainder of each, and the wall time of each run after compilation. Writes
`system_convergence.json` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import time
from pathlib import Path

import numpy as np
from harness import argument_parser, table, write_json

from barrierjax.scene_file import read_toml
from barrierjax.system import stable_step, system_impact
from barrierjax.system.assessment import summary
from barrierjax.system.scene import parse_system_scene
from barrierjax.system.vehicle import contact_stiffness_bound

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
KEYS = ("dynamic_deflection", "working_width", "exit_speed", "exit_angle", "oiv_x", "oiv_y",
        "ora_x", "ora_y")  # fmt: skip


def run(path, elements_per_span, step_fraction):
    data = read_toml(path)
    data["barrier"]["elements_per_span"] = elements_per_span
    s = parse_system_scene(data)
    dt = step_fraction * stable_step(s.barrier, contact_stiffness_bound(s.vehicle))
    options = {"speed": s.speed, "angle_deg": s.angle_deg, "impact_point": s.impact_point,
               "duration": s.duration, "friction": s.friction, "dt": dt}  # fmt: skip
    system_impact(s.vehicle, s.barrier, **options)  # compile
    start = time.perf_counter()
    r = jax.block_until_ready(system_impact(s.vehicle, s.barrier, **options))
    seconds = time.perf_counter() - start
    numbers = {k: float(v) for k, v in summary(r).items() if k in KEYS}
    error = float(np.max(np.abs(np.asarray(r.history.energy_error))))
    return {"elements_per_span": elements_per_span, "dt": dt, "energy_audit": error,
            "run_s": seconds, **numbers}  # fmt: skip


def main():
    args = argument_parser(__doc__).parse_args()
    cases = [(2, 1.0), (4, 1.0)] if args.quick else [
        (2, 1.0), (4, 1.0), (8, 1.0), (16, 1.0), (32, 1.0), (8, 0.5), (8, 0.25)]  # fmt: skip
    data = {}
    for name in ("mash_3_11", "mash_3_10"):
        rows = [run(EXAMPLES / f"{name}.toml", n, f) for n, f in cases]
        data[name] = rows
        table(
            f"{name}: elements between posts and time step",
            rows,
            [("elements/span", "elements_per_span", "d"), ("dt s", "dt", ".3g"),
             ("deflection m", "dynamic_deflection", ".3f"),
             ("working width m", "working_width", ".3f"),
             ("exit m/s", "exit_speed", ".2f"), ("exit deg", "exit_angle", ".2f"),
             ("OIV x", "oiv_x", ".2f"), ("OIV y", "oiv_y", ".2f"),
             ("ORA x", "ora_x", ".1f"), ("ORA y", "ora_y", ".1f"),
             ("energy audit", "energy_audit", ".1e"), ("run s", "run_s", ".2f")],
        )  # fmt: skip
    write_json(args, "system_convergence", data)


if __name__ == "__main__":
    main()
