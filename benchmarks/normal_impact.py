"""Benchmark of `barrierjax.hinge.normal_impact` (report 3.2) beside scipy's `solve_ivp`.

    python benchmarks/normal_impact.py [--quick] [--out DIR] [--seed N] [--no-plots]

Tables: (1) accuracy against time per scenario: the closed form and the ODE (diffrax Tsit5)
over rtol, and scipy `solve_ivp` (one scenario at a time, as a user writes it) side by side,
all against the script's own mpmath reference of the report's closed form; (2) throughput
against batch size; (3) gradient cost over forward cost; (4) the first call in a fresh
process (time and peak memory) of the forward and the gradient. Writes `normal_impact.json`,
`normal_impact_error_vs_time.png` and `normal_impact_throughput.png` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import functools
import logging
import math
import sys
import time

import jax.numpy as jnp
import mpmath as mp
import numpy as np
from harness import (
    argument_parser,
    drain,
    failure,
    first_calls,
    pyplot,
    save_figure,
    steady,
    table,
    write_json,
)

from barrierjax.hinge import normal_impact

logging.getLogger("jax._src.callback").setLevel(logging.CRITICAL)  # a failed solve's traceback
FIELDS = ("duration", "barrier_displacement", "damage")


def config(quick: bool) -> dict:
    if quick:
        return {"n_draws": 6, "corners": False, "dps": 20, "cf_rtols": [1e-4, 1e-8], "ode_rtols": [1e-8],
                    "scipy_methods": ["LSODA"], "scipy_rtols": [1e-6], "scipy_n": 3, "batches": [6],
                    "grad_batches": [6], "grad_methods": ["closed_form"], "first_batch": 100,
                    "first_methods": ["closed_form"]}
    return {"n_draws": 64, "corners": True, "dps": 30, "cf_rtols": [10.0**-k for k in range(4, 13, 2)],
                "ode_rtols": [10.0**-k for k in range(4, 13)],
                "scipy_methods": ["RK45", "DOP853", "LSODA", "Radau"], "scipy_rtols": [1e-6, 1e-8, 1e-10],
                "scipy_n": 24, "batches": [10**k for k in range(7)], "grad_batches": [1, 1000, 100_000],
                "grad_methods": ["closed_form", "ode"], "first_batch": 1000,
                "first_methods": ["closed_form", "ode"]}


def draw(n: int, rng: np.random.Generator):
    """Log-uniform mass ratio in [1e-3, 1e4], force ratio in [1 + 1e-6, 1e3], speed in
    [1e-4, 1e2]."""
    mu = 10.0 ** rng.uniform(-3.0, 4.0, n)
    phi = np.exp(rng.uniform(math.log1p(1e-6), math.log(1e3), n))
    speed = 10.0 ** rng.uniform(-4.0, 2.0, n)
    return mu, phi, speed


def scenario_set(n_draws: int, corners: bool, seed: int):
    mu, phi, speed = draw(n_draws, np.random.default_rng(seed))
    if corners:  # the 8 corners of the box, where the singular factors are worst
        grid = np.array(np.meshgrid([1e-3, 1e4], [1.0 + 1e-6, 1e3], [1e-4, 1e2], indexing="ij"))
        mu, phi, speed = (np.concatenate([a, g]) for a, g in zip((mu, phi, speed), grid.reshape(3, -1)))
    return mu, phi, speed


def reference(mu, phi, v0, dps: int = 30) -> dict:
    """T**, W_final and D for one scenario, in mpmath at `dps` digits, from the report's
    quadrature formulas (3.2.11)-(3.2.20) as corrected in docs/errata.md (no barrierjax code).

    Accelerative phase: S* = sqrt(phi^2 + 3) - phi, T* = V0 / (phi/mu + (phi - S*)/S*).
    Decelerative phase: p(S) = S^3 + 3mu S^2 - 3S - 3mu = (S - alpha)(S + beta)(S + gamma),
    V = V* r^A g(S) (3.2.19); the substitution x = r^A removes the end singularity and
    mpmath.quad (tanh-sinh) integrates dT and dW over x in [0, 1] with break points."""
    with mp.workdps(dps):
        mu, phi, v0 = mp.mpf(float(mu)), mp.mpf(float(phi)), mp.mpf(float(v0))
        s_star = mp.sqrt(phi**2 + 3) - phi
        acc = (phi - s_star) / s_star
        t_star = v0 / (acc + phi / mu)
        v_star, w_star, damage = acc * t_star, acc * t_star**2 / 2, v0 * t_star / 2
        if phi <= 1:  # rigid barrier: the vehicle alone crushes to rest
            return {"duration": mu * v0 / phi, "barrier_displacement": mp.mpf(0), "damage": mu * v0**2 / (2 * phi)}
        alpha = mp.findroot(lambda s: s**3 + 3 * mu * s**2 - 3 * s - 3 * mu, (mp.mpf(1), mp.sqrt(3)),
                            solver="anderson")
        total, product = alpha + 3 * mu, 3 * mu / alpha  # p(S) = (S - alpha)(S^2 + total S + product)
        gamma = (total + mp.sqrt(total**2 - 4 * product)) / 2
        beta = product / gamma
        a = (3 + alpha**2) / ((alpha + beta) * (alpha + gamma))
        b = (3 + beta**2) / ((alpha + beta) * (beta - gamma))
        c = (3 + gamma**2) / ((gamma + alpha) * (gamma - beta))
        h = alpha - s_star

        def g(s):
            return ((s + beta) / (s_star + beta)) ** b * ((s + gamma) / (s_star + gamma)) ** c

        def dtime(x):
            s = alpha - h * x ** (1 / a)
            return 2 * s * (s + 2 * mu) * v_star * g(s) / ((s + beta) * (s + gamma) * a)

        def ddisp(x):
            return dtime(x) * v_star * x * g(alpha - h * x ** (1 / a))

        marks = [s_star + (s_star + beta) * k for k in (0.1, 1, 10, 100)]
        marks += [s_star + h * f for f in (0.01, 0.1, 0.5, 0.9, 0.99)]
        xs = sorted({mp.mpf(0), mp.mpf(1)} | {((alpha - s) / h) ** a for s in marks if s_star < s < alpha})
        return {"duration": t_star + mp.quad(dtime, xs),
                    "barrier_displacement": w_star + mp.quad(ddisp, xs), "damage": damage}


def max_error(values: dict, ref: dict) -> np.ndarray:
    """Per scenario, the largest |x / x_ref - 1| over FIELDS (|x| where x_ref is 0)."""
    errs = []
    for k in FIELDS:
        x, r = np.asarray(values[k], float), ref[k]
        errs.append(np.where(r != 0, np.abs(x / np.where(r != 0, r, 1.0) - 1.0), np.abs(x)))
    return np.where(np.isfinite(e := np.maximum.reduce(errs)), e, np.inf)


def scipy_solve(mu, phi, v0, method, rtol, max_nfev=100_000):
    """The physical equations of motion in time T with solve_ivp, as a user would write
    them: the accelerative phase (vehicle and beam velocities, W, crush) until the
    velocities meet, then (V, S, W) with V' and S' of (3.2.15)-(3.2.16) until V = 0
    (terminal events); atol = 1e-3 rtol in units of the impact speed. None on failure."""
    from scipy.integrate import solve_ivp

    atol, s_star = 1e-3 * rtol, math.sqrt(phi * phi + 3.0) - phi
    acc, dec, nfev = (phi - s_star) / s_star, phi / mu, [0]

    def count():
        nfev[0] += 1
        if nfev[0] > max_nfev:
            raise RuntimeError(f"gave up after {max_nfev} evaluations")

    def accelerative(t, y):
        count()
        return [-dec, acc, y[1], y[0] - y[1]]

    def meet(t, y):
        return y[0] - y[1]

    def decelerative(t, y):
        count()
        v, s, _ = y
        den = 2.0 * s * (s + 2.0 * mu)
        return [-(s * s + 3.0) / den, -(s**3 + 3.0 * mu * s * s - 3.0 * s - 3.0 * mu) / (den * v), v]

    def rest(t, y):
        return y[0]

    meet.terminal = rest.terminal = True
    meet.direction = rest.direction = -1
    first = solve_ivp(accelerative, (0.0, mu * v0 / phi), [v0, 0.0, 0.0, 0.0], method=method,
                      rtol=rtol, atol=atol * np.array([v0, v0, v0 * v0, v0 * v0]), events=meet)
    if first.status != 1:
        return None
    t_star = first.t_events[0][0]
    vehicle, beam, w_star, crush = first.y_events[0][0]
    v_star = 0.5 * (vehicle + beam)  # rest comes before T* + 10 V* (1 + mu)
    second = solve_ivp(decelerative, (t_star, t_star + 10.0 * v_star * (1.0 + mu)), [v_star, s_star, w_star],
                       method=method, rtol=rtol, atol=atol * np.array([v0, 1.0, v0 * v0]), events=rest)
    if second.status != 1:
        return None
    return {"duration": second.t_events[0][0], "barrier_displacement": second.y_events[0][0][2], "damage": crush}


def accuracy(cfg, mu, phi, speed, ref) -> list:
    rows, n = [], len(mu)
    for method, rtols in (("closed_form", cfg["cf_rtols"]), ("ode", cfg["ode_rtols"])):
        for rtol in rtols:
            row = {"model": "barrierjax", "method": method, "rtol": rtol, "n": n}
            try:
                call = lambda rtol=rtol, method=method: normal_impact(mu, phi, speed, method=method, rtol=rtol)
                seconds = steady(call)
                err = max_error({k: getattr(call(), k) for k in FIELDS}, ref)
                row.update(ok=True, error=float(err.max()), failed=0, us_per_scenario=seconds / n * 1e6)
            except Exception as exc:  # noqa: BLE001 - a failure is a result
                drain()
                row.update(ok=False, failure=failure(exc))
            rows.append(row)
    idx = np.unique(np.linspace(0, n - 1, min(cfg["scipy_n"], n)).round().astype(int))
    for method in cfg["scipy_methods"]:
        for rtol in cfg["scipy_rtols"]:
            start, results = time.perf_counter(), []
            for i in idx:
                try:
                    results.append(scipy_solve(mu[i], phi[i], speed[i], method, rtol))
                except (RuntimeError, ValueError):  # ValueError: its event search failed
                    results.append(None)
            seconds = (time.perf_counter() - start) / len(idx)
            ok = [j for j, r in enumerate(results) if r is not None]
            values = {k: np.array([results[j][k] for j in ok]) for k in FIELDS}
            err = max_error(values, {k: v[idx[ok]] for k, v in ref.items()}) if ok else np.array([np.inf])
            rows.append({"model": "scipy solve_ivp", "method": method, "rtol": rtol, "n": len(idx), "ok": True,
                             "error": float(err.max()), "failed": len(idx) - len(ok), "us_per_scenario": seconds * 1e6})
    return rows


def throughput(cfg, seed) -> list:
    rows = []
    for method in ("closed_form", "ode"):
        for n in cfg["batches"] if method == "closed_form" else [b for b in cfg["batches"] if b <= 10**5]:
            mu, phi, speed = draw(n, np.random.default_rng(seed + 1))
            seconds = steady(functools.partial(normal_impact, method=method, rtol=1e-8), mu, phi, speed)
            rows.append({"method": method, "rtol": 1e-8, "batch": n, "batch_s": seconds, "per_second": n / seconds})
    return rows


def total(method):
    def fn(m, p, s):
        r = jax.vmap(lambda a, b, c: normal_impact(a, b, c, method=method, rtol=1e-8))(m, p, s)
        return jnp.sum(r.damage + r.barrier_displacement + r.duration)

    return fn


def gradient(cfg, seed) -> list:
    rows = []
    for method in cfg["grad_methods"]:
        forward, grad = jax.jit(total(method)), jax.jit(jax.grad(total(method), argnums=(0, 1, 2)))
        for n in cfg["grad_batches"] if method == "closed_form" else [b for b in cfg["grad_batches"] if b <= 1000]:
            args = draw(n, np.random.default_rng(seed + 2))
            f, g = steady(forward, *args), steady(grad, *args)
            rows.append({"method": method, "batch": n, "forward_s": f, "grad_s": g, "ratio": g / f})
    return rows


def first_call_cases(n, methods) -> dict:
    """Forward and gradient over `n` scenarios, each in a fresh process."""
    setup = f"""
        import numpy as np, jax, jax.numpy as jnp
        from barrierjax.hinge import normal_impact
        m, p, s = (np.geomspace(lo, hi, {n}) for lo, hi in ((1e-2, 1e3), (1.01, 1e2), (1e-3, 1e1)))
        def total(method):
            def fn(m, p, s):
                r = jax.vmap(lambda a, b, c: normal_impact(a, b, c, method=method))(m, p, s)
                return jnp.sum(r.damage + r.barrier_displacement + r.duration)
            return fn
    """
    cases = {}
    for method in methods:
        cases[f"{method} forward, {n} scenarios"] = (setup, f"normal_impact(m, p, s, method={method!r})")
        cases[f"{method} gradient, {n} scenarios"] = (setup, f"jax.grad(total({method!r}), (0, 1, 2))(m, p, s)")
    return cases


def plots(args, data):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    for (model, method) in {(r["model"], r["method"]): None for r in data["accuracy"]}:
        rows = [r for r in data["accuracy"] if (r["model"], r["method"]) == (model, method) and r["ok"]]
        ax.loglog([r["us_per_scenario"] for r in rows], [max(r["error"], 1e-17) for r in rows],
                  "o-" if model == "barrierjax" else "x--", label=f"{model} {method}")
    ax.set(xlabel="time per scenario (us)", ylabel="max relative error", title="normal_impact: error vs time")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    save_figure(fig, args, "normal_impact_error_vs_time")
    fig, ax = plt.subplots(figsize=(7, 5))
    for method in ("closed_form", "ode"):
        rows = [r for r in data["throughput"] if r["method"] == method]
        ax.loglog([r["batch"] for r in rows], [r["per_second"] for r in rows], "o-", label=method)
    ax.set(xlabel="batch size", ylabel="scenarios per second", title="normal_impact throughput")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    save_figure(fig, args, "normal_impact_throughput")


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    mu, phi, speed = scenario_set(cfg["n_draws"], cfg["corners"], args.seed)
    refs = [reference(m, p, s, cfg["dps"]) for m, p, s in zip(mu, phi, speed)]
    ref = {k: np.array([float(r[k]) for r in refs]) for k in FIELDS}
    check = reference(mu[0], phi[0], speed[0], cfg["dps"] + 10)  # the reference's own precision
    with mp.workdps(cfg["dps"] + 20):
        ref_check = max(float(abs(refs[0][k] / check[k] - 1)) for k in ("duration", "barrier_displacement"))
    print(f"normal_impact: {len(mu)} scenarios; mpmath reference at {cfg['dps']} digits agrees with "
          f"{cfg['dps'] + 10} digits to {ref_check:.1e}")
    data = {"accuracy": accuracy(cfg, mu, phi, speed, ref)}
    table("Accuracy against time per scenario (max relative error of duration, barrier_displacement, damage)",
          data["accuracy"], [("code", "model", "s"), ("method", "method", "s"), ("rtol", "rtol", ".0e"),
                             ("n", "n", "d"), ("max rel. error", "error", ".1e"), ("failed", "failed", "d"),
                             ("us / scenario", "us_per_scenario", ".2f")])
    data["throughput"] = throughput(cfg, args.seed)
    table("Throughput (array API, rtol 1e-8)", data["throughput"],
          [("method", "method", "s"), ("batch", "batch", "d"), ("batch s", "batch_s", ".3e"),
           ("scenarios / s", "per_second", ".3e")])
    data["gradient"] = gradient(cfg, args.seed)
    table("Gradient of sum(damage + barrier_displacement + duration) w.r.t. the 3 inputs", data["gradient"],
          [("method", "method", "s"), ("batch", "batch", "d"), ("forward s", "forward_s", ".3e"),
           ("gradient s", "grad_s", ".3e"), ("gradient / forward", "ratio", ".2f")])
    data["first_call"] = first_calls(first_call_cases(cfg["first_batch"], cfg["first_methods"]))
    summary = []
    for s in (r for r in data["accuracy"] if r["model"] != "barrierjax" and r["failed"] < r["n"]):
        match = [r for r in data["accuracy"] if r["model"] == "barrierjax" and r["ok"] and r["error"] <= s["error"]]
        for method in ("closed_form", "ode"):
            best = min((r for r in match if r["method"] == method), key=lambda r: r["us_per_scenario"], default=None)
            if best:
                summary.append({"scipy": f"{s['method']} rtol {s['rtol']:.0e}", "scipy_error": s["error"],
                                    "barrierjax": f"{method} rtol {best['rtol']:.0e}", "error": best["error"],
                                    "speedup": s["us_per_scenario"] / best["us_per_scenario"]})
    data["summary"] = summary
    table("SUMMARY: scipy against the cheapest barrierjax setting at equal or better error", summary,
          [("scipy", "scipy", "s"), ("scipy error", "scipy_error", ".1e"), ("barrierjax", "barrierjax", "s"),
           ("error", "error", ".1e"), ("scipy time / barrierjax time", "speedup", ".0f")])
    data["scenarios"] = {"mass_ratio": mu, "force_ratio": phi, "speed": speed,
                             "reference": {k: [str(r[k]) for r in refs] for k in FIELDS}}
    if not args.no_plots:
        plots(args, data)
    write_json(args, "normal_impact", {k: _listed(v) for k, v in data.items()},
               reference_digits=cfg["dps"], reference_self_check=ref_check, config=cfg)
    return 0


def _listed(value):
    if isinstance(value, dict):
        return {k: _listed(v) for k, v in value.items()}
    return value.tolist() if isinstance(value, np.ndarray) else value


if __name__ == "__main__":
    sys.exit(main())
