"""Benchmark of `barrierjax.hinge.oblique_impact` (report 3.3) beside the normal impact's ODE.

    python benchmarks/oblique_impact.py [--quick] [--out DIR] [--seed N] [--no-plots]

The model has no closed form: its reference is the same model at a much tighter tolerance
(rtol 1e-12 with a large step budget, itself checked against rtol 1e-11). Tables: (1)
accuracy against time per scenario over rtol (max relative error of duration,
barrier_displacement, damage and exit speed; absolute error of the exit angle in degrees,
which passes through 0; the energy balance; the solver's mean steps); (2) the per-scenario
cost beside `normal_impact(..., method="ode")` on the same normal inputs, same machine, same
rtol 1e-6; (3) gradient cost over forward cost (one scenario, in full runs); (4) the first
call in a fresh process, forward and gradient (the gradient's compilation takes minutes and
GBs: its child is killed above a memory limit). Writes `oblique_impact.json` and
`oblique_impact_error_vs_time.png` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import functools
import math

import jax.numpy as jnp
import numpy as np
from harness import (
    argument_parser,
    failure,
    first_calls,
    pyplot,
    save_figure,
    steady,
    table,
    write_json,
)

from barrierjax.hinge import normal_impact, oblique_impact
from barrierjax.hinge.response import kinetic_energy_balance

REL_METRICS = ("duration", "barrier_displacement", "damage", "exit_speed")
INPUTS = ("mass_ratio", "force_ratio", "normal_speed", "tangential_speed", "friction")
BOX = {"mass_ratio": (0.1, 10.0), "force_ratio": (1.1, 8.0), "angle_deg": (5.0, 85.0), "speed": (0.1, 1.0)}


def config(quick: bool) -> dict:
    if quick:  # one oblique compilation in this process: rtol is traced, the shape is shared
        return {"n_draws": 4, "ref_rtol": 1e-9, "ref_max_steps": None, "ref_check_rtol": None, "rtols": [1e-6],
                    "batches": [], "grad_scenarios": 0, "first_batch": 4, "grad_timeout": 15.0, "grad_batches": []}
    return {"n_draws": 64, "ref_rtol": 1e-12, "ref_max_steps": 8192, "ref_check_rtol": 1e-11,
                "rtols": [10.0**-k for k in range(3, 11)], "batches": [1, 10, 100, 1000, 10_000], "grad_scenarios": 4,
                "first_batch": 100, "grad_timeout": 900.0, "grad_batches": [10]}


def draw(n: int, rng: np.random.Generator) -> dict:
    """Log-uniform mass ratio, force ratio, impact angle and speed within `BOX` (where the
    model converges); every third scenario has a friction coefficient uniform in [0.1, 0.4]."""

    def log_uniform(lo, hi):
        return np.exp(rng.uniform(math.log(lo), math.log(hi), n))

    mu, phi = log_uniform(*BOX["mass_ratio"]), log_uniform(*BOX["force_ratio"])
    angle, speed = log_uniform(*BOX["angle_deg"]), log_uniform(*BOX["speed"])
    friction = np.where(np.arange(n) % 3 == 2, rng.uniform(0.1, 0.4, n), 0.0)
    return {"mass_ratio": mu, "force_ratio": phi, "normal_speed": speed * np.sin(np.radians(angle)),
                "tangential_speed": speed * np.cos(np.radians(angle)), "friction": friction}


def solve(s: dict, rtol, max_steps=None):
    m, p, vn, vh, f = (np.asarray(s[k], np.float64) for k in INPUTS)
    return oblique_impact(m, p, vn, vh, friction=f, rtol=rtol, max_steps=max_steps)


def values(r, s) -> dict:
    out = {k: np.asarray(getattr(r, k), float) for k in (*REL_METRICS, "exit_angle_deg", "steps")}
    initial = 0.5 * s["mass_ratio"] * (s["normal_speed"] ** 2 + s["tangential_speed"] ** 2)
    balance = kinetic_energy_balance(r, s["mass_ratio"], s["normal_speed"], s["tangential_speed"])
    out["energy"] = np.abs(np.asarray(balance)) / initial
    return out


def errors(x: dict, ref: dict) -> dict:
    """The largest relative error over REL_METRICS and the largest exit-angle error (deg)."""
    rel = max(float(np.max(np.abs(x[k] / np.where(ref[k] != 0, ref[k], 1.0) - (ref[k] != 0)))) for k in REL_METRICS)
    d = np.abs(x["exit_angle_deg"] - ref["exit_angle_deg"]) % 360.0
    return {"error": rel, "angle_error_deg": float(np.max(np.minimum(d, 360.0 - d)))}


def accuracy(cfg, s, ref) -> list:
    rows, n = [], len(s["mass_ratio"])
    for rtol in cfg["rtols"]:
        row = {"rtol": rtol}
        try:
            seconds = steady(lambda rtol=rtol: solve(s, rtol))
            x = values(solve(s, rtol), s)
            row.update(ok=True, **errors(x, ref), energy=float(np.max(x["energy"])), steps=float(np.mean(x["steps"])),
                       ms_per_scenario=seconds / n * 1e3)
        except Exception as exc:  # noqa: BLE001 - a failure is a result
            row.update(ok=False, failure=failure(exc))
        rows.append(row)
    return rows


def beside_normal(batches, seed) -> list:
    """Time per scenario of the oblique model and of the normal ODE (same mass ratio, force
    ratio and normal speed), at rtol 1e-6, each timed in turn on the same machine."""
    rows = []
    for n in batches:
        s = draw(n, np.random.default_rng(seed + 1))
        row = {"batch": n}
        try:
            oblique = steady(solve, s, 1e-6, reps=3)
            normal = functools.partial(normal_impact, method="ode", rtol=1e-6)
            ode = steady(normal, *(s[k] for k in INPUTS[:3]), reps=3)
            row.update(ok=True, oblique_us=oblique / n * 1e6, ode_us=ode / n * 1e6, ratio=oblique / ode)
        except Exception as exc:  # noqa: BLE001 - a failure is a result
            row.update(ok=False, failure=failure(exc))
        rows.append(row)
    return rows


def total(m, p, vn, vh, f):
    r = oblique_impact(m, p, vn, vh, friction=f, rtol=1e-6)
    return jnp.sum(r.exit_angle_deg + r.exit_normal_speed + r.damage + r.barrier_displacement)


def gradient(cfg, seed) -> list:
    """One scenario at a time (no vmap): forward and gradient w.r.t. the five inputs."""
    if not cfg["grad_scenarios"]:
        return []
    s, rows = draw(cfg["grad_scenarios"], np.random.default_rng(seed + 2)), []
    forward, grad = jax.jit(total), jax.jit(jax.grad(total, argnums=(0, 1, 2, 3, 4)))
    for i in range(cfg["grad_scenarios"]):
        args = tuple(np.float64(s[k][i]) for k in INPUTS)
        try:
            f, g = steady(forward, *args), steady(grad, *args)
            finite = all(np.isfinite(float(x)) for x in grad(*args))
            rows.append({"scenario": i, "ok": True, "forward_s": f, "grad_s": g, "ratio": g / f, "finite": finite})
        except Exception as exc:  # noqa: BLE001 - a failure is a result
            rows.append({"scenario": i, "ok": False, "failure": failure(exc)})
    return rows


def first_call_cases(cfg) -> dict:
    setup = """
        import numpy as np, jax
        from barrierjax.hinge import oblique_impact
        from oblique_impact import draw, total, INPUTS
        s = draw({n}, np.random.default_rng(0))
        args = tuple(np.asarray(s[k]) for k in INPUTS)
        one = tuple(a[0] for a in args)
        grad = jax.grad(total, argnums=(0, 1, 2, 3, 4))
    """
    cases = {f"forward, {cfg['first_batch']} scenarios": (setup.format(n=cfg["first_batch"]),
                                                          "oblique_impact(*args[:4], friction=args[4])")}
    limit = {"timeout": cfg["grad_timeout"], "rss_limit_gb": 10.0}
    cases["gradient, one scenario"] = (setup.format(n=1), "grad(*one)", limit)
    for n in cfg["grad_batches"]:
        cases[f"gradient, vmap over {n}"] = (setup.format(n=n), "jax.vmap(grad)(*args)", limit)
    return cases


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    s = draw(cfg["n_draws"], np.random.default_rng(args.seed))
    ref = values(solve(s, cfg["ref_rtol"], cfg["ref_max_steps"]), s)
    check = None
    if cfg["ref_check_rtol"]:
        check = errors(values(solve(s, cfg["ref_check_rtol"], cfg["ref_max_steps"]), s), ref)
    print(f"oblique_impact: {cfg['n_draws']} scenarios in {BOX}; reference rtol {cfg['ref_rtol']:.0e}"
          + (f", against rtol {cfg['ref_check_rtol']:.0e}: {check['error']:.1e} relative, "
             f"{check['angle_error_deg']:.1e} deg" if check else ""))
    data = {"accuracy": accuracy(cfg, s, ref)}
    table("Accuracy against time per scenario (one call on arrays over the scenario set)", data["accuracy"],
          [("rtol", "rtol", ".0e"), ("max rel. error", "error", ".2e"), ("exit angle error (deg)", "angle_error_deg",
           ".1e"), ("energy balance", "energy", ".1e"), ("mean steps", "steps", ".0f"),
           ("ms / scenario", "ms_per_scenario", ".3f")])
    data["cost"] = beside_normal(cfg["batches"] or [cfg["n_draws"]], args.seed)
    table("Time per scenario beside the normal impact's ODE (rtol 1e-6, same normal inputs)", data["cost"],
          [("batch", "batch", "d"), ("oblique us / scen.", "oblique_us", ".1f"), ("normal ODE us / scen.", "ode_us",
           ".1f"), ("oblique / normal", "ratio", ".1f")])
    data["gradient"] = gradient(cfg, args.seed)
    if data["gradient"]:
        table("Gradient of sum(exit_angle_deg + exit_normal_speed + damage + barrier_displacement) w.r.t. "
              "the 5 inputs, one scenario", data["gradient"],
              [("scenario", "scenario", "d"), ("forward s", "forward_s", ".3e"), ("gradient s", "grad_s", ".3e"),
               ("gradient / forward", "ratio", ".2f"), ("finite", "finite", "s")])
    data["first_call"] = first_calls(first_call_cases(cfg), timeout=900.0)
    data["scenarios"] = dict(**{k: v.tolist() for k, v in s.items()},
                             reference={k: v.tolist() for k, v in ref.items()}, reference_check=check)
    last = data["cost"][-1]
    print(f"\nSUMMARY: at rtol {data['accuracy'][-1]['rtol']:.0e} error {data['accuracy'][-1].get('error', math.nan):.1e}; "
          f"oblique / normal ODE per scenario at batch {last['batch']}: {last.get('ratio', math.nan):.1f}")
    if not args.no_plots:
        plt = pyplot()
        fig, ax = plt.subplots(figsize=(7, 5))
        ok = [r for r in data["accuracy"] if r["ok"]]
        ax.loglog([r["ms_per_scenario"] for r in ok], [r["error"] for r in ok], "o-", label="relative error")
        ax.loglog([r["ms_per_scenario"] for r in ok], [r["angle_error_deg"] for r in ok], "s--", label="angle (deg)")
        ax.set(xlabel="time per scenario (ms)", ylabel="max error", title="oblique_impact: error vs time")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        save_figure(fig, args, "oblique_impact_error_vs_time")
    write_json(args, "oblique_impact", data, config=cfg)


if __name__ == "__main__":
    main()
