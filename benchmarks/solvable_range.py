"""Where the models solve: random scenarios over wide boxes, and the failures by reason.

    python benchmarks/solvable_range.py [--quick] [--out DIR] [--seed N]

Each model by time integration is called once on a batch of scenarios drawn log-uniformly
over a box much wider than the benchmarks' own (mass ratio 1e-3 to 1e3, phi - 1 from 1e-3
to 100, speed 1e-3 to 10; the oblique model's angle to the barrier uniform in 0.5-89.5
degrees, friction 0.3 on every other scenario; the axial model's eta0 1e-2 to 50), and a
second batch of heavy vehicles (mass ratio 10 to 1000) that barely yield the barrier (phi
- 1 from 1e-5 to 1e-3), where the crushing phase needs steps in proportion to
1 / (phi - 1). A scenario that fails raises a `SolveError` naming it (`failures`); the
table counts them by reason and gives the range of phi - 1 and of the mass ratio among
them, and the wall time of the call (with its compilations and any budget's growth). The
oblique model raises for the first kind of failure it checks (the mechanism overtaken,
then a stalled step, then a spent budget): a batch's other kinds are not counted. Writes
`solvable_range.json`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import collections
import time

import numpy as np
from harness import argument_parser, table, write_json

from barrierjax.hinge import SolveError, axial_impact, normal_impact, oblique_impact


def draw(rng, n: int, mass_ratio, phi_minus_one) -> dict:
    """Log-uniform mass ratio, phi - 1, speed and eta0; angle uniform; friction 0.3 on
    every other scenario."""
    log_uniform = lambda lo, hi: np.exp(rng.uniform(np.log(lo), np.log(hi), n))
    return {
        "mass_ratio": log_uniform(*mass_ratio),
        "force_ratio": 1.0 + log_uniform(*phi_minus_one),
        "speed": log_uniform(1e-3, 10.0),
        "angle_deg": rng.uniform(0.5, 89.5, n),
        "friction": np.where(np.arange(n) % 2 == 1, 0.3, 0.0),
        "axial_ratio": log_uniform(1e-2, 50.0),
    }


def solve(model: str, s: dict):
    mu, phi, v = s["mass_ratio"], s["force_ratio"], s["speed"]
    if model == "normal, ODE":
        return normal_impact(mu, phi, v, method="ode")
    if model == "axial (3.4)":
        return axial_impact(mu, phi, v, s["axial_ratio"])
    angle = np.radians(s["angle_deg"])
    return oblique_impact(
        mu, phi, v * np.sin(angle), v * np.cos(angle), friction=s["friction"]
    )


def probe(model: str, box: str, s: dict) -> list:
    """One row per reason of failure (one row, reason "none", where none failed)."""
    n = len(s["mass_ratio"])
    start = time.perf_counter()
    try:
        solve(model, s)
        failures = {}
    except SolveError as error:
        failures = error.failures
    seconds = time.perf_counter() - start
    by_reason = collections.defaultdict(list)
    for k, reason in failures.items():
        by_reason[reason.split(" at T = ")[0]].append(k)  # (without where it failed)
    row = {"model": model, "box": box, "n": n, "s": seconds}
    rows = []
    for reason, ks in sorted(by_reason.items()):
        phi, mu = s["force_ratio"][ks] - 1.0, s["mass_ratio"][ks]
        rows.append(
            row | {"failed": len(ks), "reason": reason[:90], "phi_lo": phi.min(),
                   "phi_hi": phi.max(), "mu_lo": mu.min(), "mu_hi": mu.max()}  # fmt: skip
        )
    return rows or [row | {"failed": 0, "reason": "none"}]


def main():
    args = argument_parser(__doc__).parse_args()
    rng = np.random.default_rng(args.seed)
    n = 32 if args.quick else 512
    wide = draw(rng, n, (1e-3, 1e3), (1e-3, 100.0))
    near_one = draw(rng, n // 2, (10.0, 1e3), (1e-5, 1e-3))
    boxes = {"wide": wide, "heavy, phi near 1": near_one}
    rows = [
        row
        for model in ("normal, ODE", "axial (3.4)", "oblique (3.3)")
        for box, s in boxes.items()
        for row in probe(model, box, s)
    ]
    table(
        "Scenarios that fail, by reason (phi - 1 and mass ratio: their range among them)",
        rows,
        [("model", "model", ""), ("box", "box", ""), ("n", "n", "d"),
         ("failed", "failed", "d"), ("phi - 1", "phi_lo", ".2g"), ("to", "phi_hi", ".2g"),
         ("mass ratio", "mu_lo", ".3g"), ("to", "mu_hi", ".3g"), ("call s", "s", ".1f"),
         ("reason", "reason", "")],  # fmt: skip
    )
    write_json(args, "solvable_range", {"rows": rows})


if __name__ == "__main__":
    main()
