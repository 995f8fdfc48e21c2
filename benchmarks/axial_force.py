"""Benchmark of the beam stage with axial force, `axial_impact(..., axial_ratio=eta0)`
(report section 3.4).

Run from the repository root:

    python benchmarks/axial_force.py            # full run (about 10 minutes on 2 cores)
    python benchmarks/axial_force.py --quick    # smoke run (tiny sizes)

It prints tables and writes `axial_force.json` and PNG plots to `--out` (default
`benchmarks/results/`). Sections:

(a) the report's example (mu 0.5, phi 2, speed 1; figure 3.4.9): the reduction of the final
    displacement by eta0 = 2, 2.5 and 5, from barrierjax and from the report's own
    linearised step-by-step scheme (3.4.42), written here from the report's formulas (in
    numpy, with finite-difference partial derivatives where the scan garbles them), at step
    sizes dT = 0.05 .. 1e-4. The report quotes 2.5 % (eta0 = 2) and 12.5 % (eta0 = 5).
(b) error against run time: rtol 1e-4 .. 1e-10 against the same model at rtol 1e-12, over
    random scenarios whose eta0 keeps N below N0 (n_final < 0.9: the beam stage alone; the
    string stage is (e)); error = max relative error of t_final,
    w_final, damage and s_final. Time per scenario of one vmapped call, after a warm-up.
(c) throughput against batch size at rtol 1e-6, beside `normal_impact(..., method="ode")`
    without axial force (diffrax Tsit5) on the same inputs, in the same run.
(d) gradient cost: jax.grad of sum(w_final + damage + t_final) with respect to all four inputs
    over a vmapped batch, over the forward call's cost.
(e) the plastic-string stage: four scenarios that reach it (after the crushing, during it,
    and two more), string grids of 16 .. 1024 cells at Courant numbers 1 and 0.5, against
    4096 cells at Courant 1: errors of w_final, damage and t_final, the energy balance, the
    observed orders, the time per scenario, the share of plastic flow outside the flow
    rule's corner cone; then throughput and gradient cost over random scenarios that reach
    the string, beside the ODE of 3.2.

Timing protocol: one warm-up call (compile, reported separately), then the best of 3 calls.
A benchmark reports; it never tunes the model.
"""

import jax

jax.config.update("jax_enable_x64", True)

import functools
import json
import os
import time

import jax.numpy as jnp
import numpy as np
from _common import argument_parser, meta, save, source_fingerprint, sources_changed

from barrierjax.hinge import axial_impact, normal_impact

EXAMPLE = {"mass_ratio": 0.5, "force_ratio": 2.0, "speed": 1.0}
EXAMPLE_ETAS = (2.0, 2.5, 5.0)
REPORT_REDUCTIONS = {2.0: 2.5, 5.0: 12.5}  # per cent, quoted after (3.4.40)


def config(quick: bool) -> dict:
    if quick:
        return {
            "report_steps": (0.05, 0.01),
            # One shape and one rtol for (b) and (c), so that they share their compilations.
            "n_scenarios": 4,
            "rtols": (1e-6,),
            "batches": (4,),
            "grad_batch": 4,
            # One grid and one Courant number: (e) then compiles twice.
            "string_cells": (16,),
            "string_courants": (1.0,),
            "string_reference_cells": 32,
            "string_batches": (4,),
        }
    return {
        "report_steps": (0.05, 0.02, 0.01, 0.005, 0.001, 0.0001),
        "n_scenarios": 64,
        "rtols": (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10),
        "batches": (1, 10, 100, 1000, 10000),
        "grad_batch": 256,
        "string_cells": (16, 32, 64, 128, 256, 512, 1024),
        "string_courants": (1.0, 0.5),
        "string_reference_cells": 4096,
        "string_batches": (100, 1000),
    }


def best_of(fn, reps=3):
    start = time.perf_counter()
    jax.block_until_ready(fn())
    first = time.perf_counter() - start
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - start)
    return min(times), first


# --------------------------------------------------------------------------------------
# (a) The report's scheme.


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
        return -(s / 2.0 + k / s) / total, (s + mu) * k / (s * total) - s * (s + 3.0 * mu) / (
            2.0 * total
        )

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


def section_example(cfg):
    ours = axial_impact(
        jnp.full(4, EXAMPLE["mass_ratio"]),
        jnp.full(4, EXAMPLE["force_ratio"]),
        jnp.full(4, EXAMPLE["speed"]),
        rtol=1e-10,
        axial_ratio=jnp.asarray((0.0,) + EXAMPLE_ETAS),
    )
    w = np.asarray(ours.w_final)
    row = {"method": "barrierjax (rtol 1e-10)", "w_final_eta0_0": float(w[0])}
    row.update(
        {
            f"reduction_eta0_{e:g}": 100.0 * (1.0 - w[i + 1] / w[0])
            for i, e in enumerate(EXAMPLE_ETAS)
        }
    )
    rows = [row]
    args = (EXAMPLE["mass_ratio"], EXAMPLE["force_ratio"], EXAMPLE["speed"])
    for dT in cfg["report_steps"]:
        start = time.perf_counter()
        base = report_scheme(*args, 0.0, dT)
        reduced = [report_scheme(*args, e, dT) for e in EXAMPLE_ETAS]
        row = {
            "method": f"report scheme dT={dT:g}",
            "w_final_eta0_0": base,
            "seconds": time.perf_counter() - start,
        }
        row.update(
            {
                f"reduction_eta0_{e:g}": 100.0 * (1.0 - r / base)
                for e, r in zip(EXAMPLE_ETAS, reduced)
            }
        )
        rows.append(row)
    print(
        "\n(a) the report's example (mu 0.5, phi 2, speed 1): reduction of the final "
        "displacement, per cent\n    report quotes: eta0 2: 2.5 %, eta0 5: 12.5 %"
    )
    print(
        f"    {'method':28s} {'W_f(eta0=0)':>11s} "
        + " ".join(f"{'eta0 ' + format(e, 'g'):>9s}" for e in EXAMPLE_ETAS)
    )
    for r in rows:
        print(
            f"    {r['method']:28s} {r['w_final_eta0_0']:11.5f} "
            + " ".join(f"{r[f'reduction_eta0_{e:g}']:8.2f}%" for e in EXAMPLE_ETAS)
        )
    return rows


# --------------------------------------------------------------------------------------
# (b)-(d).


def scenarios(n, seed, n_bound=(0.05, 0.9)):
    """Random mass and force ratios and speeds; eta0 with 2 eta0 W_f(eta0 = 0) in
    `n_bound`. By default n_final < 0.9 (n_final = 2 eta0 W_f <= 2 eta0 W_f(eta0 = 0),
    since the axial force only stiffens the beam); bounds above 1 aim at the string
    (which some still stop short of)."""
    rng = np.random.default_rng(seed)
    mu = 10 ** rng.uniform(-1, 1.5, n)
    phi = 10 ** rng.uniform(0.05, 0.9, n)
    speed = 10 ** rng.uniform(-1, 0.3, n)
    w0 = np.asarray(normal_impact(mu, phi, speed).w_final)
    eta0 = rng.uniform(*n_bound, n) / (2.0 * w0)
    return tuple(jnp.asarray(x) for x in (mu, phi, speed, eta0))


def fields(r):
    return np.stack(
        [np.asarray(getattr(r, k)) for k in ("t_final", "w_final", "damage", "s_final")]
    )


def section_error_vs_time(cfg, inputs):
    reference = fields(axial_impact(*inputs[:3], rtol=1e-12, axial_ratio=inputs[3]))
    rows = []
    print(f"\n(b) error against run time, {len(inputs[0])} scenarios (reference: rtol 1e-12)")
    print(f"    {'rtol':>8s} {'error':>9s} {'us/scen':>9s} {'compile s':>9s}")
    for rtol in cfg["rtols"]:
        call = lambda rtol=rtol: (
            axial_impact(*inputs[:3], rtol=rtol, axial_ratio=inputs[3]).w_final
        )
        seconds, first = best_of(call)
        result = axial_impact(*inputs[:3], rtol=rtol, axial_ratio=inputs[3])
        error = float(np.max(np.abs(fields(result) / reference - 1.0)))
        per = seconds / len(inputs[0])
        rows.append(
            {
                "rtol": rtol,
                "error": error,
                "seconds_per_scenario": per,
                "compile_s": first - seconds,
            }
        )
        print(f"    {rtol:8.0e} {error:9.2e} {per * 1e6:9.1f} {first - seconds:9.1f}")
    logs = np.log([[r["seconds_per_scenario"], r["error"]] for r in rows if r["error"] > 1e-13])
    order = -np.polyfit(logs[:, 0], logs[:, 1], 1)[0] if len(logs) > 2 else None
    if order is not None:
        print(f"    error falls as time^-{order:.1f}")
    return {"rows": rows, "order_in_time": order}


def section_throughput(cfg, seed):
    rows = []
    print("\n(c) throughput at rtol 1e-6, per scenario (us): with axial force, and the ODE of 3.2")
    print(f"    {'batch':>7s} {'axial':>9s} {'3.2 ODE':>9s} {'ratio':>6s}")
    for batch in cfg["batches"]:
        mu, phi, speed, eta0 = scenarios(batch, seed + batch)
        axial, _ = best_of(
            functools.partial(axial_impact, mu, phi, speed, rtol=1e-6, axial_ratio=eta0)
        )
        plain, _ = best_of(
            functools.partial(normal_impact, mu, phi, speed, method="ode", rtol=1e-6)
        )
        rows.append(
            {
                "batch": batch,
                "axial_s": axial / batch,
                "ode_s": plain / batch,
                "ratio": axial / plain,
            }
        )
        print(
            f"    {batch:7d} {axial / batch * 1e6:9.1f} {plain / batch * 1e6:9.1f} "
            f"{axial / plain:6.1f}"
        )
    return rows


def section_gradient(cfg, seed):
    inputs = scenarios(cfg["grad_batch"], seed + 7)

    def total(*x):
        r = axial_impact(*x[:3], rtol=1e-8, axial_ratio=x[3])
        return jnp.sum(r.w_final + r.damage + r.t_final)

    forward, _ = best_of(lambda: total(*inputs))
    gradient, _first = best_of(lambda: jax.grad(total, argnums=(0, 1, 2, 3))(*inputs))
    ratio = gradient / forward
    print(
        f"\n(d) gradient over {cfg['grad_batch']} scenarios, 4 inputs: forward "
        f"{forward * 1e3:.1f} ms, gradient {gradient * 1e3:.1f} ms, ratio {ratio:.2f}"
    )
    return {
        "batch": cfg["grad_batch"],
        "forward_s": forward,
        "gradient_s": gradient,
        "ratio": ratio,
    }


# --------------------------------------------------------------------------------------
# (e) the plastic-string stage.

STRING_CASES = ((0.5, 2.0, 1.0, 10.0), (5.0, 1.5, 1.0, 5.0), (2.0, 4.0, 1.5, 4.0), (0.5, 2.0, 2.0, 10.0))


def _string_fields(r, mu, speed):
    work = r.crush_work + r.backing_work + r.hinge_work + r.string_work
    energy = np.abs(np.asarray(work) / (0.5 * np.asarray(mu) * np.asarray(speed) ** 2) - 1.0)
    return {k: np.asarray(getattr(r, k)) for k in ("w_final", "damage", "t_final")}, energy


def section_string(cfg, seed):
    mu, phi, speed, eta0 = (jnp.asarray(x) for x in zip(*STRING_CASES))

    def solve(cells, courant, n_history=0):
        return axial_impact(
            mu, phi, speed, rtol=1e-11, axial_ratio=eta0,
            string_cells=cells, string_courant=courant, n_history=n_history,
        )

    # With a history, for the flow rule's check on the finest grid.
    finest = solve(cfg["string_reference_cells"], 1.0, n_history=2)
    reference, _ = _string_fields(finest, mu, speed)
    print(
        f"\n(e) plastic string, {len(STRING_CASES)} scenarios (mu, phi, V, eta0) = {STRING_CASES};"
        f"\n    reference {cfg['string_reference_cells']} cells at Courant 1; max relative errors"
    )
    print(f"    {'courant':>7s} {'cells':>6s} {'w_final':>9s} {'damage':>9s} {'t_final':>9s} "
          f"{'energy':>9s} {'ms/scen':>8s}")
    rows = []
    for courant in cfg["string_courants"]:
        for cells in cfg["string_cells"]:
            seconds, _ = best_of(lambda cells=cells, courant=courant: solve(cells, courant).w_final)
            values, energy = _string_fields(solve(cells, courant), mu, speed)
            errors = {k: float(np.max(np.abs(values[k] / reference[k] - 1.0))) for k in values}
            row = {"courant": courant, "cells": cells, **errors, "energy": float(np.max(energy)),
                   "seconds_per_scenario": seconds / len(STRING_CASES)}
            rows.append(row)
            print(f"    {courant:7.1f} {cells:6d} {errors['w_final']:9.2e} {errors['damage']:9.2e} "
                  f"{errors['t_final']:9.2e} {row['energy']:9.2e} {row['seconds_per_scenario'] * 1e3:8.2f}")
    orders = {}
    for courant in cfg["string_courants"]:
        sub = [r for r in rows if r["courant"] == courant]
        for key in ("w_final", "t_final", "energy"):
            pts = np.log([[r["cells"], max(r[key], 1e-16)] for r in sub])
            if len(pts) > 2:
                orders[f"{key}_courant_{courant:g}"] = -np.polyfit(pts[:, 0], pts[:, 1], 1)[0]
    if orders:
        print("    observed orders in cells (least squares over the grids): " + ", ".join(
            f"{k} {v:.1f}" for k, v in orders.items()))
    moving = np.asarray(finest.history.string_flow_rule)
    flow = [
        {"case": STRING_CASES[i], "mean_share": float(np.mean(moving[i, :-1])),
         "nodes_mostly_outside": float(np.mean(moving[i, :-1] > 0.5))}
        for i in range(len(STRING_CASES))
    ]
    print(f"    flow rule's corner cone N0 eps' >= 2 M0 |kappa'| (3.4.49 corrected), share of each"
          f" node's moving time outside it, mean over the nodes ({cfg['string_reference_cells']} cells):")
    for f in flow:
        print(f"      {f['case']}: {f['mean_share']:.2f} (nodes mostly outside: "
              f"{f['nodes_mostly_outside']:.0%})")
    throughput = []
    print("    throughput at rtol 1e-6, 128 cells, random scenarios past N = N0, per scenario (us):")
    print(f"    {'batch':>7s} {'string':>9s} {'reached':>8s} {'3.2 ODE':>9s} {'ratio':>6s}")
    for batch in cfg["string_batches"]:
        inputs = scenarios(batch, seed + batch, (2.0, 6.0))
        call = functools.partial(axial_impact, *inputs[:3], rtol=1e-6, axial_ratio=inputs[3])
        axial, _ = best_of(call)
        reached = float(np.mean(np.isfinite(np.asarray(call().t_string))))
        plain, _ = best_of(functools.partial(normal_impact, *inputs[:3], method="ode", rtol=1e-6))
        throughput.append({"batch": batch, "axial_s": axial / batch, "ode_s": plain / batch,
                           "reached": reached, "ratio": axial / plain})
        print(f"    {batch:7d} {axial / batch * 1e6:9.1f} {reached:8.0%} {plain / batch * 1e6:9.1f} "
              f"{axial / plain:6.1f}")
    inputs = scenarios(cfg["string_batches"][0], seed + 11, (2.0, 6.0))

    def total(*x):
        r = axial_impact(*x[:3], rtol=1e-8, axial_ratio=x[3])
        return jnp.sum(r.w_final + r.damage + r.t_final)

    forward, _ = best_of(lambda: total(*inputs))
    gradient, _ = best_of(lambda: jax.grad(total, argnums=(0, 1, 2, 3))(*inputs))
    print(f"    gradient over {len(inputs[0])} such scenarios, 4 inputs: forward {forward * 1e3:.1f} ms,"
          f" gradient {gradient * 1e3:.1f} ms, ratio {gradient / forward:.2f}")
    return {"rows": rows, "orders": orders, "flow_rule": flow, "throughput": throughput,
            "gradient": {"forward_s": forward, "gradient_s": gradient, "ratio": gradient / forward}}


def plots(out, data):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.2))
    rows = data["error_vs_time"]["rows"]
    axes[0].loglog(
        [r["seconds_per_scenario"] * 1e6 for r in rows], [r["error"] for r in rows], "o-"
    )
    axes[0].set_xlabel("run time per scenario (us), one vmapped call")
    axes[0].set_ylabel("max relative error")
    axes[0].set_title("(b) beam stage with axial force: error against run time")
    axes[0].grid(True, which="both", alpha=0.3)
    report = [r for r in data["example"] if r["method"].startswith("report")]
    steps = [float(r["method"].split("=")[1]) for r in report]
    for i, e in enumerate(EXAMPLE_ETAS):
        key = f"reduction_eta0_{e:g}"
        axes[1].semilogx(
            steps, [r[key] for r in report], "o-", color=f"C{i}", label=f"report scheme, eta0 {e:g}"
        )
        axes[1].axhline(data["example"][0][key], color=f"C{i}", ls="--", lw=0.9)
        if e in REPORT_REDUCTIONS:
            axes[1].axhline(REPORT_REDUCTIONS[e], color=f"C{i}", ls=":", lw=1.5)
    axes[1].plot([], [], "k--", lw=0.9, label="barrierjax (converged)")
    axes[1].plot([], [], "k:", lw=1.5, label="quoted in the report")
    axes[1].set_xlabel("report scheme's step dT")
    axes[1].set_ylabel("reduction of the final displacement (%)")
    axes[1].set_title("(a) the report's example, mu 0.5, phi 2, V 1")
    axes[1].legend(fontsize=7)
    axes[1].grid(True, alpha=0.3)
    for courant, style in ((1.0, "-"), (0.5, "--")):
        sub = [r for r in data["string"]["rows"] if r["courant"] == courant]
        if not sub:
            continue
        for key, color in (("w_final", "C0"), ("t_final", "C1"), ("energy", "C2")):
            axes[2].loglog([r["cells"] for r in sub], [max(r[key], 1e-16) for r in sub], "o" + style,
                           color=color, ms=3, label=f"{key}, Courant {courant:g}")
    axes[2].set_xlabel("string cells over the half-span")
    axes[2].set_ylabel("max relative error / energy imbalance")
    axes[2].set_title("(e) plastic string: refinement")
    axes[2].legend(fontsize=7)
    axes[2].grid(True, which="both", alpha=0.3)
    save(fig, out / "axial_force.png")


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    args.out.mkdir(parents=True, exist_ok=True)
    load_start, sources_start = os.getloadavg(), source_fingerprint()
    print(
        f"axial_force benchmark ({'quick' if args.quick else 'full'}), jax {jax.__version__} "
        f"on {jax.devices()[0].platform}, {os.cpu_count()} CPU cores, load average "
        f"{load_start[0]:.1f}"
    )
    data = {"example": section_example(cfg)}
    inputs = scenarios(cfg["n_scenarios"], args.seed)
    data["error_vs_time"] = section_error_vs_time(cfg, inputs)
    data["throughput"] = section_throughput(cfg, args.seed)
    data["gradient"] = section_gradient(cfg, args.seed)
    data["string"] = section_string(cfg, args.seed)
    data["meta"] = meta(args, load_start, sources_start, sources_changed(sources_start))
    (args.out / "axial_force.json").write_text(json.dumps(data, indent=1, default=float))
    if not args.no_plots:
        plots(args.out, data)
    ours = data["example"][0]
    print(
        "\nSUMMARY: report example reductions (eta0 2 / 2.5 / 5): barrierjax "
        + " / ".join(f"{ours[f'reduction_eta0_{e:g}']:.2f}%" for e in EXAMPLE_ETAS)
        + "; the report quotes 2.5% / - / 12.5%; largest-batch cost over the 3.2 ODE "
        f"{data['throughput'][-1]['ratio']:.1f}x; gradient/forward "
        f"{data['gradient']['ratio']:.2f}"
    )


if __name__ == "__main__":
    main()
