"""Benchmark of the uniaxial rate laws (report 2.2, `barrierjax.materials`): error against run
time for each law and each method from the slow to the stiff end, and the throughput of one
update over a batch of material points.

(a) Error against run time. A ramp-and-hold strain history: constant rate alpha to 1 % strain
    (eight times the yield strain of a 250 MPa, 200 GPa steel), then held as long again (the
    stress relaxes towards the static curve). Rates 1e-3, 1, 1e4 per second; relaxation
    times tau 1 s, 1e-3 s, 1e-7 s (the stiff end: tau alpha E / sigma0 spans 1e-10 .. 1e7).
    Laws: `LinearOverstress` and `LogOverstress` against their closed forms (the constant-rate
    solutions (2.2.4), (2.2.8) and their relaxation at fixed strain), `CowperSymonds` with
    D = 1/tau against diffrax at rtol 1e-12 (itself checked against 1e-11). Methods: backward
    Euler ("implicit"), the report's scheme (4.2.8)-(4.2.10) ("report"), forward Euler
    ("explicit"), each with 16 .. 4096 equal steps, and Kvaerno5 ("diffrax") at rtol 1e-4 ..
    1e-10; beside them scipy's `solve_ivp(method="Radau")`, what a user picks today for a
    stiff ODE, on the same histories. Error = max over the samples of |sigma - reference| /
    sigma0; "unstable" = non-finite or above sigma0. Time = one jitted call per history,
    best of 3, compile excluded (reported separately).
(b) Throughput: one backward-Euler update of `CowperSymonds` (D = 40/s, q = 5, report 4.3.1)
    with its consistent tangent over a batch of 1e3 .. 1e6 material points (random stress,
    plastic strain and strain increment, dt = 1e-4 s), jitted and vmapped, against the same
    algorithm (rtsafe, the same iteration count) written in vectorised NumPy, side by side.

    python benchmarks/materials.py            # full run, about 10 minutes on 2 cores
    python benchmarks/materials.py --quick    # smoke run
"""

import json
import math
import os
import sys
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _common import argument_parser, drain, meta, save, source_fingerprint, sources_changed

from barrierjax.materials.overstress import (
    CowperSymonds,
    GilmanJohnston,
    LinearOverstress,
    LogOverstress,
    OverstressState,
    SinhOverstress,
    StrainDependentOverstress,
)
from barrierjax.materials.response import uniaxial_response, update_with_tangent

E = 200e9  # Pa
SIGMA0 = 250e6  # Pa
STRAIN = 0.01
SIGMA_C = 20e6  # Pa, the logarithmic law's characteristic stress


def config(quick: bool) -> dict:
    if quick:
        return {
            "laws": LAWS[:3],
            "rates": [1.0],
            "taus": [1e-3],
            "steps": [16, 64],
            "diffrax_rtols": [1e-6],
            "samples": 17,
            "batches": [1000],
            "repeats": 1,
        }
    return {
        "laws": LAWS,
        "rates": [1e-3, 1.0, 1e4],
        "taus": [1.0, 1e-3, 1e-7],
        "steps": [16, 64, 256, 1024, 4096],
        "diffrax_rtols": [1e-4, 1e-6, 1e-8, 1e-10],
        "samples": 65,
        "batches": [1000, 10_000, 100_000, 1_000_000],
        "repeats": 3,
    }


# ---------------------------------------------------------------------------------------
# The laws and their references.


LAWS = (
    "LinearOverstress",
    "LogOverstress",
    "CowperSymonds",
    "SinhOverstress",
    "StrainDependentOverstress",
    "GilmanJohnston",
)
CLOSED_FORMS = ("LinearOverstress", "LogOverstress")
REFERENCE_STEPS = 1 << 20  # the diffrax reference's step budget (the runs' is 65536)
RADAU = ("LinearOverstress", "LogOverstress", "CowperSymonds")  # `numpy_flow` has these


def make_law(name, tau):
    """Each law with the relaxation time `tau` (for Cowper-Symonds D = 1/tau; for
    Gilman-Johnston rate0 = 1/tau with a drag stress that puts its flow stress at sigma0
    for a plastic strain rate of 1e-3/tau)."""
    if name == "LinearOverstress":
        return LinearOverstress(E, SIGMA0, tau)
    if name == "LogOverstress":
        return LogOverstress(E, SIGMA0, SIGMA_C, tau)
    if name == "SinhOverstress":
        return SinhOverstress(E, SIGMA0, SIGMA_C, tau)
    if name == "StrainDependentOverstress":
        return StrainDependentOverstress(E, SIGMA0, tau, -0.01)
    if name == "GilmanJohnston":
        return GilmanJohnston(E, 1.0 / tau, SIGMA0 * math.log(1e3))
    return CowperSymonds(E, SIGMA0, 1.0 / tau, 5.0)


def history(rate, n):
    """Ramp to STRAIN at `rate` in n/2 steps, then hold for as long in n/2 steps."""
    t_ramp = STRAIN / rate
    half = n // 2
    times = np.concatenate(
        [np.linspace(0.0, t_ramp, half + 1), np.linspace(t_ramp, 2 * t_ramp, half + 1)[1:]]
    )
    strains = np.minimum(times * rate, STRAIN)
    return times, strains


def closed_form(name, rate, tau, times):
    """The exact stress of the linear and logarithmic laws on the ramp-and-hold history."""
    t_yield = SIGMA0 / (E * rate)
    t_ramp = STRAIN / rate
    s = np.clip(times, t_yield, t_ramp) - t_yield  # time flowing during the ramp
    hold = np.maximum(times - t_ramp, 0.0)
    if name == "LinearOverstress":
        over = E * rate * tau * -np.expm1(-s / tau)  # (2.2.4)
        over = over * np.exp(-hold / tau)
    else:
        ratio = E * rate * tau / SIGMA_C
        beta = E * rate / SIGMA_C + 1.0 / tau
        u = np.exp(-beta * s) + -np.expm1(-beta * s) / (1.0 + ratio)  # (2.2.8), exact
        u = 1.0 - (1.0 - u) * np.exp(-hold / tau)  # relaxation at fixed strain
        over = -SIGMA_C * np.log(u)
    return np.where(times < t_yield, E * rate * times, SIGMA0 + over)


def reference(name, rate, tau, times):
    """(exact stress at `times`, its own error estimate): the closed form, or for
    Cowper-Symonds diffrax at rtol 1e-12 checked against rtol 1e-11."""
    if name in CLOSED_FORMS:
        return closed_form(name, rate, tau, times), 0.0
    strains = np.minimum(times * rate, STRAIN)
    law = make_law(name, tau)
    fine = solve(law, times, strains, "diffrax", rtol=1e-12, max_steps=REFERENCE_STEPS)
    check = solve(law, times, strains, "diffrax", rtol=1e-11, max_steps=REFERENCE_STEPS)
    return fine, float(np.max(np.abs(check - fine)) / SIGMA0)


@eqx.filter_jit
def _response(law, times, strains, method, rtol, max_steps=65536):
    return uniaxial_response(
        law, times, strains, method=method, rtol=rtol, atol=1e-6 * rtol, max_steps=max_steps
    ).stress


def solve(law, times, strains, method, rtol=1e-8, max_steps=65536):
    return np.asarray(
        _response(law, jnp.asarray(times), jnp.asarray(strains), method, rtol, max_steps)
    )


def timed(fn, repeats):
    """(result, best seconds, first-call seconds): the first call includes compilation."""
    t0 = time.perf_counter()
    out = jax.block_until_ready(fn())
    first = time.perf_counter() - t0
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(fn())
        best = min(best, time.perf_counter() - t0)
    return out, best, first


def numpy_flow(name, tau):
    """g(x), the overstress law's stress rate at overstress x > 0, in NumPy (as a user
    would write it for scipy)."""
    if name == "LinearOverstress":
        return lambda x: x / tau
    if name == "LogOverstress":
        return lambda x: SIGMA_C / tau * np.expm1(x / SIGMA_C)
    return lambda x: E / tau * (x / SIGMA0) ** 5.0


def radau(name, tau, times, strains, rtol):
    """scipy's Radau on the plastic strain: eps_p' = g(|sigma| - sigma0) sign(sigma) / E."""
    from scipy.integrate import solve_ivp

    slopes = np.diff(strains) / np.diff(times)
    flow = numpy_flow(name, tau)

    def field(t, y):
        i = min(max(np.searchsorted(times, t, side="right") - 1, 0), len(slopes) - 1)
        stress = E * (strains[i] + slopes[i] * (t - times[i]) - y[0])
        x = abs(stress) - SIGMA0
        return [flow(x) * np.sign(stress) / E if x > 0 else 0.0]

    with np.errstate(over="ignore", invalid="ignore"):
        sol = solve_ivp(
            field,
            (times[0], times[-1]),
            [0.0],
            method="Radau",
            t_eval=times,
            rtol=rtol,
            atol=1e-6 * rtol,
            first_step=min(np.diff(times)) / 16,
        )
    return E * (strains - sol.y[0]) if sol.success else np.full_like(times, np.nan)


def first_line(exc) -> str:
    """The line of an exception's message that says what went wrong."""
    lines = str(exc).strip().splitlines() or [type(exc).__name__]
    reason = [x for x in lines if "maximum number" in x or "Error:" in x]
    return (reason or lines)[0].strip()[:120]


def run_method(law, name, tau, method, times, strains, rtol, cfg):
    """(stress history, best seconds, first-call seconds) of one method on one history."""
    if method == "scipy Radau":
        t0 = time.perf_counter()
        stress = radau(name, tau, times, strains, rtol)
        return stress, time.perf_counter() - t0, time.perf_counter() - t0
    stress, best, first = timed(
        lambda: _response(law, jnp.asarray(times), jnp.asarray(strains), method, rtol or 1e-8),
        cfg["repeats"],
    )
    return np.asarray(stress), best, first


def section_error_vs_time(cfg):
    print(
        "\n(a) Error against run time: ramp to 1 % at rate alpha, hold as long; error = max |dsigma| / sigma0"
    )
    header = f"{'law':<26}{'method':<12}{'n / rtol':>9}{'alpha':>8}{'tau':>8}{'error':>10}{'time s':>10}{'compile s':>10}"
    print(header)
    rows = []
    for name in cfg["laws"]:
        for rate in cfg["rates"]:
            for tau in cfg["taus"]:
                law = make_law(name, tau)
                references = {}
                runs = [
                    (m, n, None) for m in ("implicit", "report", "explicit") for n in cfg["steps"]
                ]
                runs += [("diffrax", cfg["samples"] - 1, r) for r in cfg["diffrax_rtols"]]
                if name in RADAU:
                    runs += [
                        ("scipy Radau", cfg["samples"] - 1, r) for r in cfg["diffrax_rtols"][:2]
                    ]
                for method, n, rtol in runs:
                    times, strains = history(rate, n)
                    row = {"law": name, "method": method, "steps": n, "rtol": rtol}
                    row.update(rate=rate, tau=tau, error=None, stable=False, failure=None)
                    row.update(time_s=None, compile_s=None, reference_check=None)
                    if n not in references:
                        try:
                            references[n] = reference(name, rate, tau, times)
                        except Exception as exc:  # noqa: BLE001
                            drain()
                            references[n] = exc
                    if isinstance(references[n], Exception):
                        row["failure"] = "no reference: " + first_line(references[n])
                        row["stable"] = None
                        rows.append(row)
                        continue
                    try:
                        ref, row["reference_check"] = references[n]
                        stress, best, first = run_method(
                            law, name, tau, method, times, strains, rtol, cfg
                        )
                    except Exception as exc:  # noqa: BLE001 - a failure is a result
                        drain()
                        row["failure"] = first_line(exc)
                        rows.append(row)
                        print(
                            f"{name:<26}{method:<12}{rtol or n!s:>9}{rate:>8.0e}{tau:>8.0e}  FAILED: {row['failure']}",
                            flush=True,
                        )
                        continue
                    err = float(np.max(np.abs(stress - ref)) / SIGMA0)
                    row.update(time_s=best, compile_s=max(first - best, 0.0))
                    row["stable"] = bool(np.all(np.isfinite(stress))) and err < 1.0
                    row["error"] = err if np.isfinite(err) else None
                    rows.append(row)
                    knob = f"{rtol:.0e}" if rtol else f"{n}"
                    shown = f"{err:10.2e}" if row["stable"] else f"{'unstable':>10}"
                    print(
                        f"{name:<26}{method:<12}{knob:>9}{rate:>8.0e}{tau:>8.0e}{shown}{best:>10.2e}{row['compile_s']:>10.1f}",
                        flush=True,
                    )
    return rows


# ---------------------------------------------------------------------------------------
# (b) Throughput of one update.


def numpy_cowper_symonds(stress, plastic_strain, d_strain, dt, D, q, iterations):
    """The backward-Euler Cowper-Symonds update in vectorised NumPy, the library's algorithm
    with the same iteration count: the overstress x solves x - x_trial + dt E D (x/sigma0)^q
    = 0, by Newton from x0 = min(x_trial, sigma0 (x_trial / (dt E D))^(1/q)), safeguarded by
    bisection, held once converged to rounding."""
    trial = stress + E * d_strain
    x_trial = np.abs(trial) - SIGMA0
    flowing = x_trial > 0
    x_trial = np.maximum(x_trial, 0.0)
    c = dt * E * D
    x = np.minimum(x_trial, SIGMA0 * (x_trial / c) ** (1 / q))
    lo, hi, last = np.zeros_like(x), x.copy(), 2 * x_trial
    tolerance = 16 * np.finfo(float).eps * (x_trial + SIGMA0)
    for _ in range(iterations):
        r = x - x_trial + c * (x / SIGMA0) ** q
        slope = 1.0 + c * q * (x / SIGMA0) ** (q - 1) / SIGMA0
        lo, hi = np.where(r <= 0, x, lo), np.where(r >= 0, x, hi)
        newton = x - r / slope
        use = (newton >= lo) & (newton <= hi) & (np.abs(2 * r) <= np.abs(last * slope))
        new = np.where(use, newton, 0.5 * (lo + hi))
        new = np.where(np.abs(r) <= tolerance, x, new)
        x, last = new, new - x
    sign = np.sign(trial)
    new_stress = np.where(flowing, sign * (SIGMA0 + x), trial)
    new_plastic = plastic_strain + np.where(flowing, sign * (x_trial - x) / E, 0.0)
    tangent = np.where(flowing, E / (1.0 + c * q * (x / SIGMA0) ** (q - 1) / SIGMA0), E)
    return new_stress, new_plastic, tangent


def section_throughput(cfg, seed):
    print(
        "\n(b) Throughput: one backward-Euler Cowper-Symonds update with its tangent (D = 40/s, q = 5, dt = 1e-4 s)"
    )
    print(
        f"{'points':>10}{'jax s':>11}{'ns/point':>10}{'numpy s':>11}{'ns/point':>10}{'numpy/jax':>10}{'compile s':>10}"
    )
    law = CowperSymonds(E, SIGMA0, 40.0, 5.0)
    rng = np.random.default_rng(seed)
    update = jax.jit(
        jax.vmap(
            lambda s, ep, de: update_with_tangent(
                law, s, OverstressState(ep, jnp.abs(ep)), de, 1e-4
            )
        )
    )
    rows = []
    for n in cfg["batches"]:
        stress = rng.uniform(-1.5, 1.5, n) * SIGMA0
        plastic = rng.uniform(-1e-2, 1e-2, n)
        d_strain = rng.uniform(-2e-3, 2e-3, n)
        args = tuple(jnp.asarray(a) for a in (stress, plastic, d_strain))
        out, best, first = timed(lambda args=args: update(*args), cfg["repeats"])
        t0 = time.perf_counter()
        ref = numpy_cowper_symonds(stress, plastic, d_strain, 1e-4, 40.0, 5.0, law.iterations)
        numpy_s = time.perf_counter() - t0
        agree = float(np.max(np.abs(np.asarray(out[0]) - ref[0])) / SIGMA0)
        row = {
            "points": n,
            "jax_s": best,
            "numpy_s": numpy_s,
            "compile_s": max(first - best, 0.0),
            "max_stress_difference": agree,
        }
        rows.append(row)
        print(
            f"{n:>10d}{best:>11.3e}{best / n * 1e9:>10.1f}{numpy_s:>11.3e}{numpy_s / n * 1e9:>10.1f}"
            f"{numpy_s / best:>10.1f}{row['compile_s']:>10.1f}   (stresses agree to {agree:.1e} sigma0)",
            flush=True,
        )
    return rows


def plot(out: Path, rows) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    laws = [law for law in LAWS if any(r["law"] == law for r in rows)]
    ncols = min(3, len(laws))
    nrows = -(-len(laws) // ncols)
    fig, axes = plt.subplots(nrows, ncols, figsize=(5 * ncols, 4.5 * nrows), sharey=True)
    axes = np.atleast_1d(axes).ravel()
    markers = {"implicit": "o", "report": "s", "explicit": "x", "diffrax": "^", "scipy Radau": "v"}
    for ax, name in zip(axes, laws):
        for k, method in enumerate(markers):
            mine = [r for r in rows if r["law"] == name and r["method"] == method]
            ok = [r for r in mine if r["stable"] and r["error"]]
            bad = [r for r in mine if not r["stable"] and r["time_s"]]
            ax.loglog(
                [r["time_s"] for r in ok],
                [max(r["error"], 1e-16) for r in ok],
                markers[method],
                color=f"C{k}",
                label=method,
                alpha=0.7,
            )
            if bad:
                ax.loglog(
                    [r["time_s"] for r in bad],
                    [1.0] * len(bad),
                    markers[method],
                    color=f"C{k}",
                    mfc="none",
                    ms=10,
                )
        ax.set_title(name)
        ax.set_xlabel("time per history, s")
        ax.grid(True, which="both", alpha=0.3)
    for ax in axes[::ncols]:
        ax.set_ylabel("max |error| / sigma0 (unstable: hollow, at 1)")
    axes[0].legend()
    fig.suptitle(
        "Uniaxial rate laws: error against run time over rates 1e-3 .. 1e4/s and tau 1 .. 1e-7 s"
    )
    return save(fig, out / "materials_error_vs_time.png")


def summarise(rows) -> dict:
    """Per law and method: how many histories were unstable or failed, and the worst error
    over rates and relaxation times at the finest setting (most steps, or tightest rtol)."""
    out = {}
    unchecked = [r for r in rows if r["stable"] is None]
    rows = [r for r in rows if r["stable"] is not None]
    for r in rows:
        key = f"{r['law']} / {r['method']}"
        entry = out.setdefault(key, {"histories": 0, "unstable": 0, "unstable_cases": []})
        entry["histories"] += 1
        if not r["stable"]:  # unstable, or failed (a diffrax step budget spent)
            entry["unstable"] += 1
            entry["unstable_cases"].append(
                {k: r[k] for k in ("steps", "rtol", "rate", "tau", "failure")}
            )
    for key, entry in out.items():
        mine = [r for r in rows if f"{r['law']} / {r['method']}" == key]
        finest = max(mine, key=lambda r: (-(r["rtol"] or 0.0), r["steps"]))
        at_finest = [
            r for r in mine if (r["rtol"], r["steps"]) == (finest["rtol"], finest["steps"])
        ]
        errors = [r["error"] if r["stable"] else math.inf for r in at_finest]
        entry["finest"] = {"steps": finest["steps"], "rtol": finest["rtol"]}
        entry["finest_worst_error"] = max(errors)
        entry["finest_mean_time_s"] = float(np.mean([r["time_s"] or np.nan for r in at_finest]))
    out["without reference"] = sorted(
        {f"{r['law']} alpha {r['rate']:g} tau {r['tau']:g}" for r in unchecked}
    )
    return out


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    load_start = os.getloadavg()
    sources = source_fingerprint()
    start = time.perf_counter()
    print(
        f"materials benchmark ({'quick' if args.quick else 'full'}), jax {jax.__version__} on {jax.default_backend()}, {os.cpu_count()} CPU cores"
    )
    rows_a = section_error_vs_time(cfg)
    rows_b = section_throughput(cfg, args.seed)
    summary = summarise(rows_a)
    print("\nSUMMARY")
    for key, entry in summary.items():
        if key == "without reference":
            print(f"  no reference (diffrax at rtol 1e-12 failed), not scored: {entry}")
            continue
        cases = ", ".join(
            f"alpha {c['rate']:g} tau {c['tau']:g} "
            + (f"rtol {c['rtol']:g}" if c["rtol"] else f"n {c['steps']}")
            + (" (failed)" if c["failure"] else "")
            for c in entry["unstable_cases"][:3]
        )
        finest = entry["finest"]
        setting = f"rtol {finest['rtol']:g}" if finest["rtol"] else f"n {finest['steps']}"
        print(
            f"  {key:<40} worst error at {setting:<10} {entry['finest_worst_error']:9.2e}"
            f" ({entry['finest_mean_time_s']:.1e} s); unstable or failed"
            f" {entry['unstable']:>3} of {entry['histories']:<3} {cases}"
        )
    big = rows_b[-1]
    print(
        f"  throughput: {big['points']:.0e} points in {big['jax_s']:.3e} s ({big['jax_s'] / big['points'] * 1e9:.1f} ns/point), NumPy {big['numpy_s'] / big['jax_s']:.1f} x slower"
    )
    args.out.mkdir(parents=True, exist_ok=True)
    data = {
        "meta": {
            **meta(args, load_start, sources, sources_changed(sources)),
            "config": cfg,
            "elapsed_s": time.perf_counter() - start,
        },
        "error_vs_time": rows_a,
        "throughput": rows_b,
        "summary": summary,
    }
    if not args.no_plots:
        data["plots"] = [str(plot(args.out, rows_a))]
    (args.out / "materials.json").write_text(json.dumps(data, indent=1))
    print(f"wrote {args.out / 'materials.json'}")


if __name__ == "__main__":
    main()
