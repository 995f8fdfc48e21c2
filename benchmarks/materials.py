"""Benchmark of the uniaxial rate laws (report 2.2, `barrierjax.materials`) beside scipy and
NumPy.

    python benchmarks/materials.py [--quick] [--out DIR] [--seed N] [--no-plots]

Tables: (1) accuracy against time of each law and method on ramp-and-hold strain histories
(constant rate alpha to 1 % strain, eight times the yield strain of a 250 MPa, 200 GPa
steel, then held as long; rates 1e-3, 1, 1e4 /s; relaxation times tau 1, 1e-3, 1e-7 s),
against the closed forms of `LinearOverstress` and `LogOverstress` ((2.2.4), (2.2.8) and
their relaxation) and, for the other laws, diffrax at rtol 1e-12 (checked against 1e-11).
Methods: backward Euler ("implicit"), the report's scheme (4.2.8)-(4.2.10) ("report"),
forward Euler ("explicit") at 16 .. 4096 equal steps, Kvaerno5 ("diffrax") at rtol 1e-4 ..
1e-10, and scipy's `solve_ivp(method="Radau")` (what a user picks for a stiff ODE) side by
side. Error = max |sigma - reference| / sigma0; "unstable" = non-finite or above sigma0.
(2) Throughput of one backward-Euler `CowperSymonds` update with its tangent over 1e3 ..
1e6 material points, jitted and vmapped, against the same algorithm in vectorised NumPy.
(3) The first call in a fresh process. Writes `materials.json` and
`materials_error_vs_time.png` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import math
import time

import equinox as eqx
import jax.numpy as jnp
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
LAWS = ("LinearOverstress", "LogOverstress", "CowperSymonds", "SinhOverstress",
        "StrainDependentOverstress", "GilmanJohnston")
CLOSED_FORMS = ("LinearOverstress", "LogOverstress")
REFERENCE_STEPS = 1 << 20  # the diffrax reference's step budget (the runs' is 65536)
RADAU = ("LinearOverstress", "LogOverstress", "CowperSymonds")  # `numpy_flow` has these


def config(quick: bool) -> dict:
    if quick:
        return {"laws": LAWS[:1], "rates": [1.0], "taus": [1e-3], "steps": [16, 64], "diffrax_rtols": [1e-6],
                    "samples": 17, "batches": [1000], "repeats": 1}
    return {"laws": LAWS, "rates": [1e-3, 1.0, 1e4], "taus": [1.0, 1e-3, 1e-7], "steps": [16, 64, 256, 1024, 4096],
                "diffrax_rtols": [1e-4, 1e-6, 1e-8, 1e-10], "samples": 65, "batches": [1000, 10_000, 100_000, 1_000_000],
                "repeats": 3}


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
    t_ramp, half = STRAIN / rate, n // 2
    times = np.concatenate([np.linspace(0.0, t_ramp, half + 1), np.linspace(t_ramp, 2 * t_ramp, half + 1)[1:]])
    return times, np.minimum(times * rate, STRAIN)


def closed_form(name, rate, tau, times):
    """The exact stress of the linear and logarithmic laws on the ramp-and-hold history."""
    t_yield, t_ramp = SIGMA0 / (E * rate), STRAIN / rate
    s = np.clip(times, t_yield, t_ramp) - t_yield  # time flowing during the ramp
    hold = np.maximum(times - t_ramp, 0.0)
    if name == "LinearOverstress":
        over = E * rate * tau * -np.expm1(-s / tau) * np.exp(-hold / tau)  # (2.2.4)
    else:
        ratio, beta = E * rate * tau / SIGMA_C, E * rate / SIGMA_C + 1.0 / tau
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
    return np.asarray(_response(law, jnp.asarray(times), jnp.asarray(strains), method, rtol, max_steps))


def numpy_flow(name, tau):
    """g(x), the overstress law's stress rate at overstress x > 0, in NumPy (as a user
    would write it for scipy)."""
    if name == "LinearOverstress":
        return lambda x: x / tau
    if name == "LogOverstress":
        return lambda x: SIGMA_C / tau * np.expm1(x / SIGMA_C)
    return lambda x: E / tau * (x / SIGMA0) ** 5.0


def radau(name, tau, times, strains, rtol):
    """scipy's Radau on the plastic strain: eps_p' = g(|sigma| - sigma0) sign(sigma) / E,
    one `solve_ivp` per piece of the strain history between its kinks (where the strain
    rate changes), as a user who knows the history integrates it: stepped across the
    ramp's end at tau 1e-7, Radau ended 2.2-2.6 sigma0 off the closed form."""
    from scipy.integrate import solve_ivp

    slopes = np.diff(strains) / np.diff(times)
    flow = numpy_flow(name, tau)

    def field(t, y):
        i = min(max(np.searchsorted(times, t, side="right") - 1, 0), len(slopes) - 1)
        stress = E * (strains[i] + slopes[i] * (t - times[i]) - y[0])
        x = abs(stress) - SIGMA0
        return [flow(x) * np.sign(stress) / E if x > 0 else 0.0]

    kinks = [0, *(np.flatnonzero(np.diff(slopes) != 0.0) + 1), len(times) - 1]
    plastic, y = [0.0], [0.0]
    with np.errstate(over="ignore", invalid="ignore"):
        for start, end in zip(kinks[:-1], kinks[1:]):
            sol = solve_ivp(field, (times[start], times[end]), y, method="Radau",
                            t_eval=times[start + 1 : end + 1], rtol=rtol, atol=1e-6 * rtol,
                            first_step=min(np.diff(times)) / 16)  # fmt: skip
            if not sol.success:
                return np.full_like(times, np.nan)
            plastic.extend(sol.y[0])
            y = [sol.y[0, -1]]
    return E * (strains - np.asarray(plastic))


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


def run_method(law, name, tau, method, times, strains, rtol, cfg):
    """(stress history, seconds) of one method on one history."""
    if method == "scipy Radau":
        start = time.perf_counter()
        stress = radau(name, tau, times, strains, rtol)
        return stress, time.perf_counter() - start
    call = lambda: _response(law, jnp.asarray(times), jnp.asarray(strains), method, rtol or 1e-8)
    return np.asarray(call()), steady(call, reps=cfg["repeats"])


def error_vs_time(cfg) -> list:
    rows = []
    for name in cfg["laws"]:
        for rate in cfg["rates"]:
            for tau in cfg["taus"]:
                law, references = make_law(name, tau), {}
                runs = [(m, n, None) for m in ("implicit", "report", "explicit") for n in cfg["steps"]]
                runs += [("diffrax", cfg["samples"] - 1, r) for r in cfg["diffrax_rtols"]]
                runs += [("scipy Radau", cfg["samples"] - 1, r) for r in cfg["diffrax_rtols"][:2] if name in RADAU]
                for method, n, rtol in runs:
                    times, strains = history(rate, n)
                    row = {"law": name, "method": method, "steps": n, "rtol": rtol, "rate": rate, "tau": tau, "error": None,
                               "stable": False, "failure": None, "time_s": None}
                    try:
                        if n not in references:
                            references[n] = reference(name, rate, tau, times)
                    except Exception as exc:  # noqa: BLE001 - a failure is a result
                        drain()
                        references[n] = "no reference: " + failure(exc)
                    if isinstance(references[n], str):
                        rows.append(dict(row, failure=references[n], stable=None))
                        continue
                    try:
                        stress, seconds = run_method(law, name, tau, method, times, strains, rtol, cfg)
                    except Exception as exc:  # noqa: BLE001 - a failure is a result
                        drain()
                        rows.append(dict(row, failure=failure(exc)))
                        continue
                    err = float(np.max(np.abs(stress - references[n][0])) / SIGMA0)
                    rows.append(dict(row, time_s=seconds, stable=bool(np.isfinite(err) and err < 1.0),
                                     error=err if np.isfinite(err) else None, reference_check=references[n][1]))
    return rows


def summarise(rows) -> list:
    """Per law, method and setting (steps or rtol): the worst error over rates and relaxation
    times, the histories that were unstable or failed, and the mean time."""
    out = {}
    for r in (r for r in rows if r["stable"] is not None):
        key = (r["law"], r["method"], f"rtol {r['rtol']:.0e}" if r["rtol"] else f"{r['steps']} steps")
        e = out.setdefault(key, {"law": key[0], "method": key[1], "setting": key[2], "histories": 0, "unstable": 0,
                                     "worst_error": 0.0, "times": []})
        e["histories"] += 1
        e["unstable"] += not r["stable"]
        e["worst_error"] = max(e["worst_error"], r["error"] if r["stable"] else math.inf)
        e["times"].append(r["time_s"] or math.nan)
    for e in out.values():
        e["mean_time_s"] = float(np.mean(e.pop("times")))
    return list(out.values())


def throughput(cfg, seed) -> list:
    law, rng, rows = CowperSymonds(E, SIGMA0, 40.0, 5.0), np.random.default_rng(seed), []
    update = jax.jit(jax.vmap(lambda s, ep, de: update_with_tangent(law, s, OverstressState(ep, jnp.abs(ep)), de, 1e-4)))
    for n in cfg["batches"]:
        stress, plastic, d_strain = (rng.uniform(-1.5, 1.5, n) * SIGMA0, rng.uniform(-1e-2, 1e-2, n),
                                     rng.uniform(-2e-3, 2e-3, n))
        args = tuple(jnp.asarray(a) for a in (stress, plastic, d_strain))
        seconds = steady(update, *args, reps=max(cfg["repeats"], 3))
        start = time.perf_counter()
        ref = numpy_cowper_symonds(stress, plastic, d_strain, 1e-4, 40.0, 5.0, law.iterations)
        numpy_s = time.perf_counter() - start
        agree = float(np.max(np.abs(np.asarray(update(*args)[0]) - ref[0])) / SIGMA0)
        rows.append({"points": n, "jax_s": seconds, "jax_ns": seconds / n * 1e9, "numpy_s": numpy_s,
                         "numpy_ns": numpy_s / n * 1e9, "ratio": numpy_s / seconds, "max_stress_difference": agree})
    return rows


FIRST_SETUP = """
    import numpy as np, jax, jax.numpy as jnp
    from barrierjax.materials.overstress import CowperSymonds, OverstressState
    from barrierjax.materials.response import uniaxial_response, update_with_tangent
    law = CowperSymonds(200e9, 250e6, 40.0, 5.0)
    times = jnp.linspace(0.0, 0.02, 257); strains = jnp.minimum(times, 0.01)
    s, ep, de = jnp.linspace(-3e8, 3e8, 10000), jnp.zeros(10000), jnp.full(10000, 1e-3)
    update = jax.vmap(lambda s, ep, de: update_with_tangent(law, s, OverstressState(ep, jnp.abs(ep)), de, 1e-4))
"""
FIRST_CASES = {
    "uniaxial_response, implicit, 256 steps": (FIRST_SETUP, "uniaxial_response(law, times, strains).stress"),
    "uniaxial_response, diffrax": (FIRST_SETUP, "uniaxial_response(law, times, strains, method='diffrax').stress"),
    "update_with_tangent, 1e4 points (vmap)": (FIRST_SETUP, "update(s, ep, de)"),
}


def plot(args, rows):
    plt = pyplot()
    laws = [law for law in LAWS if any(r["law"] == law for r in rows)]
    ncols = min(3, len(laws))
    fig, axes = plt.subplots(-(-len(laws) // ncols), ncols, figsize=(5 * ncols, 4.5 * -(-len(laws) // ncols)),
                             sharey=True)
    axes = np.atleast_1d(axes).ravel()
    for ax, name in zip(axes, laws):
        for k, method in enumerate(("implicit", "report", "explicit", "diffrax", "scipy Radau")):
            mine = [r for r in rows if r["law"] == name and r["method"] == method and r["time_s"]]
            ok = [r for r in mine if r["stable"]]
            ax.loglog([r["time_s"] for r in ok], [max(r["error"], 1e-16) for r in ok], "osx^v"[k], color=f"C{k}",
                      label=method, alpha=0.7)
            bad = [r for r in mine if not r["stable"]]
            ax.loglog([r["time_s"] for r in bad], [1.0] * len(bad), "osx^v"[k], color=f"C{k}", mfc="none", ms=10)
        ax.set(title=name, xlabel="time per history (s)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("max |error| / sigma0 (unstable: hollow, at 1)")
    axes[0].legend()
    save_figure(fig, args, "materials_error_vs_time")


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    rows = error_vs_time(cfg)
    summary = summarise(rows)
    table("Accuracy against time: worst error over rates and relaxation times (max |dsigma| / sigma0)",
          summary, [("law", "law", "s"), ("method", "method", "s"), ("setting", "setting", "s"),
                    ("worst error", "worst_error", ".2e"), ("unstable / histories", "unstable", "d"),
                    ("of", "histories", "d"), ("mean s / history", "mean_time_s", ".2e")])
    missing = sorted({f"{r['law']} alpha {r['rate']:g} tau {r['tau']:g}" for r in rows if r["stable"] is None})
    if missing:
        print(f"no reference (diffrax at rtol 1e-12 failed), not scored: {missing}")
    data = {"error_vs_time": rows, "summary": summary, "throughput": throughput(cfg, args.seed)}
    table("SUMMARY: throughput of one backward-Euler Cowper-Symonds update with its tangent (D 40/s, q 5, "
          "dt 1e-4 s), JAX (jit + vmap) against the same algorithm in NumPy", data["throughput"],
          [("points", "points", "d"), ("JAX s", "jax_s", ".3e"), ("JAX ns / point", "jax_ns", ".1f"),
           ("NumPy s", "numpy_s", ".3e"), ("NumPy ns / point", "numpy_ns", ".1f"), ("NumPy / JAX", "ratio", ".1f"),
           ("stress difference / sigma0", "max_stress_difference", ".1e")])
    data["first_call"] = first_calls(dict(list(FIRST_CASES.items())[: 1 if args.quick else None]))
    if not args.no_plots:
        plot(args, rows)
    write_json(args, "materials", data, config=cfg)


if __name__ == "__main__":
    main()
