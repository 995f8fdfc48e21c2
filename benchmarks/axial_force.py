"""Benchmark of `barrierjax.hinge.axial_impact` (report 3.4: the beam stage with axial force,
then the plastic string).

    python benchmarks/axial_force.py [--quick] [--out DIR] [--seed N] [--no-plots]

Tables: (1) the report's example (mu 0.5, phi 2, speed 1; figure 3.4.9): the reduction of
the final displacement by eta0 = 2, 2.5, 5 from barrierjax and from the report's own
linearised scheme (3.4.42), transcribed here in numpy, at steps dT; (2) accuracy against
time per scenario of the beam stage (rtol against the model at rtol 1e-12); (3) throughput
beside `normal_impact(..., method="ode")` (the 3.2 model without axial force) on the same
inputs; (4) the plastic string: grid refinement against the finest grid, and its cost beside
the 3.2 ODE; (5) gradient over forward cost; (6) the first call in a fresh process.
Writes `axial_force.json` and `axial_force.png` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import functools
import time

import jax.numpy as jnp
import numpy as np
from harness import argument_parser, first_calls, pyplot, save_figure, steady, table, write_json

from barrierjax.hinge import axial_impact, normal_impact

EXAMPLE = (0.5, 2.0, 1.0)  # mass ratio, force ratio, speed
ETAS = (2.0, 2.5, 5.0)
REPORT_REDUCTIONS = {2.0: 2.5, 5.0: 12.5}  # per cent, quoted after (3.4.40)
STRING_CASES = ((0.5, 2.0, 1.0, 10.0), (5.0, 1.5, 1.0, 5.0), (2.0, 4.0, 1.5, 4.0), (0.5, 2.0, 2.0, 10.0))
FIELDS = ("duration", "barrier_displacement", "damage", "hinge_position")


def config(quick: bool) -> dict:
    if quick:  # one shape and one rtol for (2) and (3): they share their compilations
        return {"report_steps": (0.05, 0.01), "n_scenarios": 4, "rtols": (1e-6,), "batches": (4,), "grad_batch": 4,
                    "string_cells": (16,), "string_courants": (1.0,), "string_reference": 32, "string_batches": (4,),
                    "first_batch": 4}
    return {"report_steps": (0.05, 0.02, 0.01, 0.005, 0.001, 0.0001), "n_scenarios": 64,
                "rtols": (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10), "batches": (1, 10, 100, 1000, 10000),
                "grad_batch": 256, "string_cells": (16, 32, 64, 128, 256, 512, 1024), "string_courants": (1.0, 0.5),
                "string_reference": 4096, "string_batches": (100, 1000), "first_batch": 100}


def report_scheme(mu, phi, speed, eta0, dT):
    """(3.4.41)-(3.4.42): V0' = f(S, V0), V0 S' = g(S, V0), each step linearised about T_n
    and solved for (dV0, dS); W0 by the trapezoidal rule; W0's dependence on V0 through
    dW0/dV0 = V0 / f, as printed. Returns the final displacement."""
    s, v, w, u, dv_previous, accelerating = -phi + np.sqrt(phi**2 + 3.0), 0.0, 0.0, speed, 0.0, True

    def rates(s, w):
        k = 1.5 + 6.0 * eta0**2 * w**2
        if accelerating:
            return 2.0 * phi / s - 0.5 - k / s**2, k / s - s / 2.0 - phi
        total = s + 2.0 * mu
        return -(s / 2.0 + k / s) / total, (s + mu) * k / (s * total) - s * (s + 3.0 * mu) / (2.0 * total)

    h = 1e-7
    while True:
        f, g = rates(s, w)
        f_s, g_s = [(a - b) / (2 * h) for a, b in zip(rates(s + h, w), rates(s - h, w))]
        f_w, g_w = [(a - b) / (2 * h) for a, b in zip(rates(s, w + h), rates(s, w - h))]
        dw_dv = v / f
        a11, a12, a13 = 1.0 - dT / 2 * f_w * dw_dv, -dT / 2 * f_s, f * dT
        a21, a22, a23 = -dT / 2 * g_w * dw_dv, v + dv_previous / 2 - dT / 2 * g_s, g * dT
        det = a11 * a22 - a12 * a21
        dv, ds = (a13 * a22 - a12 * a23) / det, (a11 * a23 - a21 * a13) / det
        if not accelerating and v + dv <= 0.0:
            return w + 0.5 * v * (v / -dv) * dT
        w += v * dT + 0.5 * dv * dT
        v, s, dv_previous = v + dv, s + ds, dv
        if accelerating:
            u -= phi / mu * dT
            accelerating = v < u


def example(cfg) -> list:
    inputs = [jnp.full(4, x) for x in EXAMPLE]
    start = time.perf_counter()
    w = np.asarray(axial_impact(*inputs, jnp.asarray((0.0,) + ETAS), rtol=1e-10).barrier_displacement)
    rows = [dict(method="barrierjax (rtol 1e-10)", w_final_eta0_0=float(w[0]), seconds=time.perf_counter() - start,
                 **{f"reduction_eta0_{e:g}": 100.0 * (1.0 - w[i + 1] / w[0]) for i, e in enumerate(ETAS)})]
    for dT in cfg["report_steps"]:
        start = time.perf_counter()
        base, *reduced = (report_scheme(*EXAMPLE, e, dT) for e in (0.0, *ETAS))
        rows.append(dict(method=f"report scheme dT={dT:g}", w_final_eta0_0=base, seconds=time.perf_counter() - start,
                         **{f"reduction_eta0_{e:g}": 100.0 * (1.0 - r / base) for e, r in zip(ETAS, reduced)}))
    return rows


def scenarios(n, seed, n_bound=(0.05, 0.9)):
    """Random mass and force ratios and speeds; eta0 with 2 eta0 W_f(eta0 = 0) in `n_bound`.
    By default n_final < 0.9 (the axial force only stiffens the beam, so n_final <= 2 eta0
    W_f(eta0 = 0)): the beam stage alone; bounds above 1 aim at the string."""
    rng = np.random.default_rng(seed)
    mu, phi, speed = 10 ** rng.uniform(-1, 1.5, n), 10 ** rng.uniform(0.05, 0.9, n), 10 ** rng.uniform(-1, 0.3, n)
    w0 = np.asarray(normal_impact(mu, phi, speed).barrier_displacement)
    eta0 = rng.uniform(*n_bound, n) / (2.0 * w0)
    return tuple(jnp.asarray(x) for x in (mu, phi, speed, eta0))


def fields(r):
    return np.stack([np.asarray(getattr(r, k)) for k in FIELDS])


def accuracy(cfg, inputs) -> list:
    reference, rows, n = fields(axial_impact(*inputs, rtol=1e-12)), [], len(inputs[0])
    for rtol in cfg["rtols"]:
        call = lambda rtol=rtol: axial_impact(*inputs, rtol=rtol)
        seconds = steady(call)
        rows.append({"rtol": rtol, "error": float(np.max(np.abs(fields(call()) / reference - 1.0))),
                         "us_per_scenario": seconds / n * 1e6})
    return rows


def beside_ode(batches, seed, n_bound, **options) -> list:
    """Time per scenario of `axial_impact` and of the 3.2 ODE on the same normal inputs."""
    rows = []
    for batch in batches:
        mu, phi, speed, eta0 = scenarios(batch, seed + batch, n_bound)
        axial = steady(functools.partial(axial_impact, rtol=1e-6, **options), mu, phi, speed, eta0)
        plain = steady(functools.partial(normal_impact, method="ode", rtol=1e-6), mu, phi, speed)
        reached = float(np.mean(np.isfinite(np.asarray(axial_impact(mu, phi, speed, eta0, rtol=1e-6).t_string))))
        rows.append({"batch": batch, "axial_us": axial / batch * 1e6, "ode_us": plain / batch * 1e6,
                         "ratio": axial / plain, "reached_string": reached})
    return rows


def string_refinement(cfg) -> list:
    mu, phi, speed, eta0 = (jnp.asarray(x) for x in zip(*STRING_CASES))

    def solve(cells, courant):
        return axial_impact(mu, phi, speed, eta0, rtol=1e-11, string_cells=cells, string_courant=courant)

    def energy(r):
        work = r.crush_work + r.backing_work + r.hinge_work + r.string_work
        return float(np.max(np.abs(np.asarray(work) / (0.5 * np.asarray(mu) * np.asarray(speed) ** 2) - 1.0)))

    reference, rows = fields(solve(cfg["string_reference"], 1.0))[:3], []
    for courant in cfg["string_courants"]:
        for cells in cfg["string_cells"]:
            seconds = steady(lambda cells=cells, courant=courant: solve(cells, courant))
            r = solve(cells, courant)
            errors = np.max(np.abs(fields(r)[:3] / reference - 1.0), axis=1)
            rows.append(dict(courant=courant, cells=cells, **dict(zip(FIELDS, errors.tolist())), energy=energy(r),
                             ms_per_scenario=seconds / len(STRING_CASES) * 1e3))
    return rows


def gradient(cfg, seed) -> list:
    def total(*x):
        r = axial_impact(*x, rtol=1e-8)
        return jnp.sum(r.barrier_displacement + r.damage + r.duration)

    rows = []
    for stage, bound in (("beam stage", (0.05, 0.9)), ("plastic string", (2.0, 6.0))):
        inputs = scenarios(cfg["grad_batch"], seed + 7, bound)
        forward, grad = steady(total, *inputs), steady(jax.grad(total, argnums=(0, 1, 2, 3)), *inputs)
        rows.append({"stage": stage, "batch": cfg["grad_batch"], "forward_s": forward, "grad_s": grad, "ratio": grad / forward})
    return rows


def first_call_cases(n) -> dict:
    setup = f"""
        import numpy as np, jax, jax.numpy as jnp
        from barrierjax.hinge import axial_impact
        m, p, s = np.geomspace(0.1, 30, {n}), np.geomspace(1.2, 8, {n}), np.geomspace(0.1, 2, {n})
        eta = np.geomspace(0.5, 10, {n})
        total = lambda *x: jnp.sum(axial_impact(*x).barrier_displacement)
    """
    return {f"forward, {n} scenarios": (setup, "axial_impact(m, p, s, eta)"),
            f"gradient, {n} scenarios": (setup, "jax.grad(total, (0, 1, 2, 3))(m, p, s, eta)")}


def plots(args, data):
    plt = pyplot()
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.2))
    rows = data["error_vs_time"]["rows"]
    axes[0].loglog([r["us_per_scenario"] for r in rows], [r["error"] for r in rows], "o-")
    axes[0].set(xlabel="time per scenario (us)", ylabel="max relative error", title="beam stage: error vs time")
    report = data["example"][1:]
    steps = [float(r["method"].split("=")[1]) for r in report]
    for i, e in enumerate(ETAS):
        key = f"reduction_eta0_{e:g}"
        axes[1].semilogx(steps, [r[key] for r in report], "o-", color=f"C{i}", label=f"report scheme, eta0 {e:g}")
        axes[1].axhline(data["example"][0][key], color=f"C{i}", ls="--", lw=0.9)
        if e in REPORT_REDUCTIONS:
            axes[1].axhline(REPORT_REDUCTIONS[e], color=f"C{i}", ls=":", lw=1.5)
    axes[1].set(xlabel="report scheme's step dT (dashed: barrierjax; dotted: quoted)",
                ylabel="reduction of W_f (%)", title="the report's example")
    axes[1].legend(fontsize=7)
    for courant, style in ((1.0, "-"), (0.5, "--")):
        sub = [r for r in data["string"]["refinement"] if r["courant"] == courant]
        for key, color in (("barrier_displacement", "C0"), ("duration", "C1"), ("energy", "C2")):
            axes[2].loglog([r["cells"] for r in sub], [max(r[key], 1e-16) for r in sub], "o" + style, color=color,
                           ms=3, label=f"{key}, Courant {courant:g}")
    axes[2].set(xlabel="string cells", ylabel="max relative error", title="plastic string: refinement")
    axes[2].legend(fontsize=7)
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    save_figure(fig, args, "axial_force")


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    data = {"example": example(cfg)}
    table("The report's example: reduction of the final displacement (report quotes 2.5 % at eta0 2, "
          "12.5 % at eta0 5)", data["example"],
          [("method", "method", "s"), ("W_f (eta0 0)", "w_final_eta0_0", ".5f"),
           *[(f"eta0 {e:g} (%)", f"reduction_eta0_{e:g}", ".2f") for e in ETAS], ("s", "seconds", ".2f")])
    data["error_vs_time"] = {"rows": accuracy(cfg, scenarios(cfg["n_scenarios"], args.seed))}
    table(f"Beam stage, {cfg['n_scenarios']} scenarios: max relative error of {', '.join(FIELDS)} "
          "against rtol 1e-12", data["error_vs_time"]["rows"],
          [("rtol", "rtol", ".0e"), ("max rel. error", "error", ".2e"), ("us / scenario", "us_per_scenario", ".1f")])
    cost = [("batch", "batch", "d"), ("axial us / scen.", "axial_us", ".1f"), ("3.2 ODE us / scen.", "ode_us", ".1f"),
            ("axial / ODE", "ratio", ".1f"), ("reached string", "reached_string", ".0%")]
    data["throughput"] = beside_ode(cfg["batches"], args.seed, (0.05, 0.9))
    table("Beam stage: time per scenario beside the 3.2 ODE (rtol 1e-6, same inputs)", data["throughput"], cost)
    data["string"] = {"refinement": string_refinement(cfg),
                          "throughput": beside_ode(cfg["string_batches"], args.seed, (2.0, 6.0))}
    table(f"Plastic string, 4 scenarios {STRING_CASES}: max relative errors against "
          f"{cfg['string_reference']} cells at Courant 1", data["string"]["refinement"],
          [("Courant", "courant", ".1f"), ("cells", "cells", "d"), ("W_f", "barrier_displacement", ".2e"),
           ("damage", "damage", ".2e"), ("duration", "duration", ".2e"), ("energy balance", "energy", ".1e"),
           ("ms / scen.", "ms_per_scenario", ".2f")])
    table("Plastic string (128 cells): time per scenario beside the 3.2 ODE", data["string"]["throughput"], cost)
    data["gradient"] = gradient(cfg, args.seed)
    table("Gradient of sum(barrier_displacement + damage + duration) w.r.t. the 4 inputs", data["gradient"],
          [("stage", "stage", "s"), ("batch", "batch", "d"), ("forward s", "forward_s", ".3e"),
           ("gradient s", "grad_s", ".3e"), ("gradient / forward", "ratio", ".2f")])
    data["first_call"] = first_calls(first_call_cases(cfg["first_batch"]))
    ours = data["example"][0]
    print("\nSUMMARY: report example reductions (eta0 2 / 2.5 / 5): barrierjax "
          + " / ".join(f"{ours[f'reduction_eta0_{e:g}']:.2f}%" for e in ETAS)
          + f" (the report quotes 2.5% / - / 12.5%); beam stage / 3.2 ODE at batch {data['throughput'][-1]['batch']}: "
          f"{data['throughput'][-1]['ratio']:.1f}x")
    if not args.no_plots:
        plots(args, data)
    write_json(args, "axial_force", data, config=cfg)


if __name__ == "__main__":
    main()
