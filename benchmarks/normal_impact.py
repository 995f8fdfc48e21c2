"""Benchmark of `barrierjax.hinge.normal_impact` (report section 3.2).

Run from the repository root:

    python benchmarks/normal_impact.py            # full run (about 10-15 minutes on 2 cores)
    python benchmarks/normal_impact.py --quick    # smoke run (tiny sizes, ~30 s, mostly compile)

It prints tables and writes `normal_impact.json` and PNG plots to `--out`
(default `benchmarks/results/`). Sections:

(a) error against run time: the closed form over rtol 1e-4 .. 1e-12 and the ODE method with
    diffrax Tsit5, Dopri5, Dopri8 and Kvaerno5 over rtol 1e-4 .. 1e-12, on a fixed set of
    scenarios; error = max over scenarios of the relative error of t_final, w_final and damage
    against an mpmath reference (30 digits) written here from the report's formulas, not from
    barrierjax's code; time = the array API (jit-compiled, vmapped in cache-sized chunks)
    over the scenario set, per scenario, after a warm-up call (compile time reported
    separately).
(b) throughput against batch size (closed form to 1e6, ODE to 1e5), and the spread of the ODE's
    step counts across a batch (diffrax solved directly with the model's vector fields).
(c) gradient cost: jax.grad of sum(damage + w_final + t_final) w.r.t. all three inputs over a
    vmapped batch, divided by the cost of the same forward sum.
(d) scipy.integrate.solve_ivp on the same physics, one scenario at a time in a Python loop, as a
    user would write it (two phases in time T, terminal events), with the error against the same
    reference, and the ratio scipy time / barrierjax vmapped ODE time at 1e5 scenarios at equal or
    better error.

Finally the acceptance targets of the issue are printed as PASS/FAIL with the measured numbers.
A benchmark reports; it never tunes the model.
"""

import jax

jax.config.update("jax_enable_x64", True)

import json
import logging
import math
import os
import sys
import time
from pathlib import Path

import diffrax
import jax.numpy as jnp
import numpy as np
from _common import argument_parser, drain, meta, save, source_fingerprint, sources_changed

from barrierjax.hinge.normal import normal_impact
from barrierjax.hinge.normal.ode import ode_phases

try:
    import mpmath as mp
except ImportError:  # pragma: no cover
    sys.exit("mpmath is needed for the reference: pip install mpmath (it is in the test extra)")

# A failing solve inside jit reports through a callback that logs a long traceback; the
# benchmark records the failure itself.
logging.getLogger("jax._src.callback").setLevel(logging.CRITICAL)

FIELDS = ("t_final", "w_final", "damage")
SOLVERS = {
    "Tsit5": diffrax.Tsit5,
    "Dopri5": diffrax.Dopri5,
    "Dopri8": diffrax.Dopri8,
    "Kvaerno5": diffrax.Kvaerno5,
}
TARGET_SCIPY_RATIO = 300.0
TARGET_THROUGHPUT = 1e6
TARGET_GRAD_RATIO = 5.0


# ---------------------------------------------------------------------------------------
# Configuration.


def config(quick: bool) -> dict:
    if quick:
        return dict(
            n_draws=6,
            corners=False,
            ref_dps=20,
            cf_rtols=[1e-4, 1e-8],
            ode_rtols={"Tsit5": [1e-8]},
            cf_batches=[6],
            ode_batches=[6],
            ode_throughput_rtol=1e-8,
            step_batch=0,
            grad_cf_batches=[1],
            grad_ode_batches=[],
            scipy_methods=["LSODA"],
            scipy_rtols=[1e-6],
            scipy_n=3,
            scipy_max_nfev=20_000,
            match_batch=6,
            chunk=0,
        )
    tols = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]
    return dict(
        n_draws=64,
        corners=True,
        ref_dps=30,
        cf_rtols=[10.0**-k for k in range(4, 13)],
        # Tsit5 (the default, and the solver of the scipy comparison) on every half decade, so
        # that the scipy errors can be matched closely; Kvaerno5 compiles in ~10-25 s and runs ~10x
        # slower than the explicit solvers: 4 tolerances.
        ode_rtols={
            name: (
                [10.0 ** (-k / 2) for k in range(8, 25)]
                if name == "Tsit5"
                else tols
                if name != "Kvaerno5"
                else tols[:4]
            )
            for name in SOLVERS
        },
        cf_batches=[10**k for k in range(7)],
        ode_batches=[10**k for k in range(6)],
        ode_throughput_rtol=1e-8,
        step_batch=10_000,
        grad_cf_batches=[1, 1000, 100_000],
        grad_ode_batches=[1, 1000],
        scipy_methods=["RK45", "DOP853", "LSODA", "Radau"],
        scipy_rtols=[1e-6, 1e-8, 1e-10],
        scipy_n=24,  # RK45, DOP853 and Radau take up to seconds per heavy-vehicle scenario
        scipy_n_by_method={"LSODA": 72},  # LSODA is cheap: all scenarios
        scipy_max_nfev=100_000,
        match_batch=100_000,
        chunk=10_000,
    )


# ---------------------------------------------------------------------------------------
# Scenarios.


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
        grid = grid.reshape(3, -1)
        mu, phi, speed = (np.concatenate([a, g]) for a, g in zip((mu, phi, speed), grid))
    return mu, phi, speed


# ---------------------------------------------------------------------------------------
# Reference: the report's quadrature formulas (3.2.11)-(3.2.20), corrected per docs/errata.md,
# evaluated with mpmath. Written from the formulas, not from barrierjax's code.


def reference(mu, phi, v0, dps: int = 30) -> dict:
    """T**, W_final and D for one scenario, in mpmath at `dps` digits.

    Accelerative phase: S* = sqrt(phi^2 + 3) - phi, beam acceleration (phi - S*)/S*, vehicle
    deceleration phi/mu, T* = V0 / (phi/mu + (phi - S*)/S*), V* = (phi - S*) T*/S*,
    W* = (phi - S*) T*^2 / (2 S*), D = V0 T*/2.
    Decelerative phase: V' = -(S^2+3)/(2S(S+2mu)), V S' = -p(S)/(2S(S+2mu)),
    p(S) = S^3 + 3mu S^2 - 3S - 3mu = (S - alpha)(S + beta)(S + gamma), so
    dT/dS = 2S(S+2mu) V / (-p(S)), dW/dS = V dT/dS, with V(S) from (3.2.19):
    V = V* r^A g(S), r = (alpha - S)/(alpha - S*), g = ((S+beta)/(S*+beta))^B ((S+gamma)/(S*+gamma))^C.
    The end singularity r^(A-1) is removed by the substitution x = r^A in [0, 1]:
    dT = 2S(S+2mu) V* g / ((S+beta)(S+gamma)) dx / A, dW = V* x g dT, S = alpha - (alpha-S*) x^(1/A),
    and mpmath.quad (tanh-sinh) integrates over x with break points where S is near S* (on the
    scale S* + beta) and at fixed fractions of alpha - S*.
    """
    with mp.workdps(dps):
        mu, phi, v0 = mp.mpf(float(mu)), mp.mpf(float(phi)), mp.mpf(float(v0))
        s_star = mp.sqrt(phi**2 + 3) - phi
        acc = (phi - s_star) / s_star
        t_star = v0 / (acc + phi / mu)
        v_star = acc * t_star
        w_star = acc * t_star**2 / 2
        damage = v0 * t_star / 2
        if phi <= 1:  # rigid barrier: the vehicle alone crushes to rest
            t = mu * v0 / phi
            return dict(t_final=t, w_final=mp.mpf(0), damage=mu * v0**2 / (2 * phi))
        alpha = mp.findroot(
            lambda s: s**3 + 3 * mu * s**2 - 3 * s - 3 * mu,
            (mp.mpf(1), mp.sqrt(3)),
            solver="anderson",
        )
        # p(S) = (S - alpha)(S^2 + (alpha + 3 mu) S + 3 mu / alpha)
        total, product = alpha + 3 * mu, 3 * mu / alpha
        gamma = (total + mp.sqrt(total**2 - 4 * product)) / 2
        beta = product / gamma
        a = (3 + alpha**2) / ((alpha + beta) * (alpha + gamma))
        b = (3 + beta**2) / ((alpha + beta) * (beta - gamma))
        c = (3 + gamma**2) / ((gamma + alpha) * (gamma - beta))
        h = alpha - s_star

        def hinge(x):
            return alpha - h * x ** (1 / a)

        def g(s):
            return ((s + beta) / (s_star + beta)) ** b * ((s + gamma) / (s_star + gamma)) ** c

        def dtime(x):
            s = hinge(x)
            return 2 * s * (s + 2 * mu) * v_star * g(s) / ((s + beta) * (s + gamma) * a)

        def ddisp(x):
            s = hinge(x)
            return dtime(x) * v_star * x * g(s)

        marks = [s_star + (s_star + beta) * k for k in (0.1, 1, 10, 100)]
        marks += [s_star + h * f for f in (0.01, 0.1, 0.5, 0.9, 0.99)]
        xs = {mp.mpf(0), mp.mpf(1)} | {((alpha - s) / h) ** a for s in marks if s_star < s < alpha}
        xs = sorted(xs)
        return dict(
            t_final=t_star + mp.quad(dtime, xs),
            w_final=w_star + mp.quad(ddisp, xs),
            damage=damage,
        )


def reference_set(mu, phi, speed, dps):
    return [reference(m, p, s, dps) for m, p, s in zip(mu, phi, speed)]


def as_float(refs) -> dict:
    return {k: np.array([float(r[k]) for r in refs]) for k in FIELDS}


def rel_errors(result, ref: dict) -> dict:
    """Per-field arrays of |x / x_ref - 1| (|x| where x_ref is 0)."""
    out = {}
    for k in FIELDS:
        x = np.asarray(getattr(result, k) if not isinstance(result, dict) else result[k], float)
        r = ref[k]
        out[k] = np.where(r != 0, np.abs(x / np.where(r != 0, r, 1.0) - 1.0), np.abs(x))
    return out


def max_error(errs: dict) -> float:
    worst = max(float(np.max(np.where(np.isfinite(e), e, np.inf))) for e in errs.values())
    return worst


# ---------------------------------------------------------------------------------------
# Timing.


def timed(fn, *args, min_total=0.2, max_reps=20):
    """(output, compile_s, run_s) for a `jax.jit`-wrapped `fn`: compile ahead of time (trace +
    lower + compile, timed), one warm-up call, then the best of >= 3 timed calls (of one call
    when the warm-up took over 1 s, to bound the run time of the largest batches)."""
    t0 = time.perf_counter()
    compiled = fn.lower(*args).compile()
    compile_s = time.perf_counter() - t0
    t0 = time.perf_counter()
    out = jax.block_until_ready(compiled(*args))
    warm = time.perf_counter() - t0
    runs = []
    while True:
        t0 = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        runs.append(time.perf_counter() - t0)
        if warm > 1.0 or runs[-1] > 1.0 or len(runs) >= max_reps:
            break
        if len(runs) >= 3 and sum(runs) >= min_total:
            break
    return out, compile_s, min(runs)


_TIMINGS = {}


def timed_forward(method, rtol, solver, n, seed):
    """`timed` on `forward(...)` over `batch_inputs(n, seed)`, memoised (shared by (b) and (d))."""
    key = (method, rtol, solver, n)
    if key not in _TIMINGS:
        mu, phi, speed = batch_inputs(n, seed)
        try:
            _, compile_s, run_s = timed(forward(method, rtol, solver), mu, phi, speed)
            _TIMINGS[key] = dict(ok=True, compile_s=compile_s, batch_s=run_s)
        except Exception as exc:  # noqa: BLE001 - a failure is a result
            drain()
            _TIMINGS[key] = dict(ok=False, failure=f"{type(exc).__name__}: {first_line(exc)}")
    return _TIMINGS[key]


def plain_vmap(method, rtol, solver):
    """jit(vmap(normal_impact)) over the whole batch at once: a diagnostic showing what the
    array API's cache-sized chunks save on large batches."""
    kwargs = dict(method=method, rtol=rtol)
    if solver is not None:
        kwargs["solver"] = SOLVERS[solver]()
    return jax.jit(jax.vmap(lambda m, p, s: normal_impact(m, p, s, **kwargs)))


def first_line(exc: BaseException) -> str:
    text = str(exc).strip().splitlines()
    for line in text:
        if "Terminating" in line or "must" in line or "maximum" in line.lower():
            return line.strip()[:200]
    return (text[0] if text else type(exc).__name__)[:200]


_FORWARD = {}


def forward(method: str, rtol: float, solver: str | None = None):
    """normal_impact on arrays (the public batch API: jit-compiled, vmapped in cache-sized
    chunks), memoised so that equal shapes reuse one compilation."""
    key = (method, rtol, solver)
    if key not in _FORWARD:
        kwargs = dict(method=method, rtol=rtol)
        if solver is not None:
            kwargs["solver"] = SOLVERS[solver]()
        _FORWARD[key] = jax.jit(lambda m, p, s: normal_impact(m, p, s, **kwargs))
    return _FORWARD[key]


# ---------------------------------------------------------------------------------------
# (a) error against run time.


def section_error_vs_time(cfg, mu, phi, speed, ref):
    n = len(mu)
    rows = []
    configs = [("closed_form", None, r) for r in cfg["cf_rtols"]]
    configs += [("ode", s, r) for s, rtols in cfg["ode_rtols"].items() for r in rtols]
    for method, solver, rtol in configs:
        label = "closed_form" if method == "closed_form" else solver
        row = dict(method=method, solver=solver, label=label, rtol=rtol)
        try:
            out, compile_s, run_s = timed(forward(method, rtol, solver), mu, phi, speed)
            errs = rel_errors(out, ref)
            row.update(
                ok=True,
                error=max_error(errs),
                error_by_field={k: float(np.max(e)) for k, e in errs.items()},
                worst_scenario=int(np.argmax(np.maximum.reduce([errs[k] for k in FIELDS]))),
                per_scenario_error=np.maximum.reduce([errs[k] for k in FIELDS]).tolist(),
                batch_s=run_s,
                per_scenario_s=run_s / n,
                compile_s=compile_s,
            )
        except Exception as exc:  # noqa: BLE001 - a failure is a result
            drain()
            row.update(ok=False, failure=f"{type(exc).__name__}: {first_line(exc)}")
            # Which scenarios fail one at a time (the batch fails as a whole).
            if method == "ode":
                row["failing_alone"] = failing_alone(method, rtol, solver, mu, phi, speed)
        rows.append(row)
        print_row_a(row)
    return rows


def failing_alone(method, rtol, solver, mu, phi, speed):
    fn = forward(method, rtol, solver)
    bad = []
    for i in range(len(mu)):
        try:
            jax.block_until_ready(fn(mu[i : i + 1], phi[i : i + 1], speed[i : i + 1]))
        except Exception:  # noqa: BLE001 - a failure is a result
            drain()
            bad.append(i)
    return bad


def print_header_a(n):
    print(f"\n(a) Error against run time: {n} scenarios, array API batch, time per scenario")
    print(
        f"{'method':<12}{'rtol':>8}{'max rel err':>13}{'t_final':>10}{'w_final':>10}"
        f"{'damage':>10}{'us/scen':>10}{'compile s':>11}"
    )


def print_row_a(row):
    if row["ok"]:
        e = row["error_by_field"]
        print(
            f"{row['label']:<12}{row['rtol']:>8.0e}{row['error']:>13.2e}{e['t_final']:>10.1e}"
            f"{e['w_final']:>10.1e}{e['damage']:>10.1e}{row['per_scenario_s'] * 1e6:>10.2f}"
            f"{row['compile_s']:>11.1f}",
            flush=True,
        )
    else:
        print(f"{row['label']:<12}{row['rtol']:>8.0e}  FAILED: {row['failure']}", flush=True)


# ---------------------------------------------------------------------------------------
# (b) throughput against batch size.


def section_throughput(cfg, seed):
    rows = {"closed_form": [], "ode": []}
    print("\n(b) Throughput against batch size (array API, vmapped chunks; after warm-up)")
    print(f"{'method':<12}{'rtol':>8}{'batch':>10}{'batch s':>12}{'scen/s':>12}{'compile s':>11}")
    for method, batches, rtol, solver in (
        ("closed_form", cfg["cf_batches"], 1e-8, None),
        ("ode", cfg["ode_batches"], cfg["ode_throughput_rtol"], "Tsit5"),
    ):
        for n in batches:
            t = timed_forward(method, rtol, solver, n, seed)
            if t["ok"]:
                row = dict(
                    batch=n,
                    rtol=rtol,
                    ok=True,
                    batch_s=t["batch_s"],
                    per_second=n / t["batch_s"],
                    compile_s=t["compile_s"],
                )
                print(
                    f"{method:<12}{rtol:>8.0e}{n:>10d}{t['batch_s']:>12.3e}{n / t['batch_s']:>12.3e}"
                    f"{t['compile_s']:>11.1f}",
                    flush=True,
                )
            else:
                row = dict(batch=n, rtol=rtol, ok=False, failure=t["failure"])
                print(f"{method:<12}{rtol:>8.0e}{n:>10d}  FAILED: {row['failure']}", flush=True)
            rows[method].append(row)
    # Diagnostic: the largest batch again, as one jit(vmap) over all of it.
    diag = []
    for method, n, rtol, solver in (
        ("closed_form", max(cfg["cf_batches"]), 1e-8, None),
        ("ode", max(cfg["ode_batches"]), cfg["ode_throughput_rtol"], "Tsit5"),
    ):
        chunk = cfg["chunk"]
        if not chunk or n <= chunk:
            continue
        mu, phi, speed = batch_inputs(n, seed)
        try:
            _, compile_s, run_s = timed(plain_vmap(method, rtol, solver), mu, phi, speed)
            d = dict(
                method=method,
                batch=n,
                chunk=chunk,
                rtol=rtol,
                ok=True,
                batch_s=run_s,
                per_second=n / run_s,
                compile_s=compile_s,
            )
            print(
                f"{method:<12}{rtol:>8.0e}{n:>10d}{run_s:>12.3e}{n / run_s:>12.3e}{compile_s:>11.1f}"
                "  (diagnostic: one jit(vmap) over the whole batch)",
                flush=True,
            )
        except Exception as exc:  # noqa: BLE001 - a failure is a result
            drain()
            d = dict(method=method, batch=n, chunk=chunk, ok=False, failure=first_line(exc))
        diag.append(d)
    return rows, diag


_BATCHES = {}


def batch_inputs(n, seed):
    """Fresh draws (seed + 1) of the same distribution, shared by (b), (c) and (d)."""
    if n not in _BATCHES:
        _BATCHES[n] = draw(n, np.random.default_rng(seed + 1))
    return _BATCHES[n]


def ode_step_counts(n, seed, rtol, solver_name="Tsit5"):
    """Steps per phase for each scenario of a batch, from the model's own two solves
    (`normal_impact` does not return solver statistics)."""
    mu, phi, _ = batch_inputs(n, seed)

    def solve(m, p):
        *_, first, second = ode_phases(m, p, rtol=rtol, solver=SOLVERS[solver_name]())
        return first.num_steps, second.num_steps

    first, second = jax.block_until_ready(jax.jit(jax.vmap(solve))(mu, phi))
    out = {}
    for name, steps in (
        ("accelerative", np.asarray(first)),
        ("decelerative", np.asarray(second)),
        ("total", np.asarray(first) + np.asarray(second)),
    ):
        out[name] = dict(
            min=int(steps.min()),
            median=float(np.median(steps)),
            p99=float(np.percentile(steps, 99)),
            max=int(steps.max()),
            mean=float(steps.mean()),
        )
    worst = int(np.argmax(np.asarray(second)))
    out["worst_decelerative"] = dict(mass_ratio=float(mu[worst]), force_ratio=float(phi[worst]))
    # A vmapped while loop runs until its slowest member is done: useful fraction of work.
    out["vmap_efficiency"] = dict(
        accelerative=out["accelerative"]["mean"] / out["accelerative"]["max"],
        decelerative=out["decelerative"]["mean"] / out["decelerative"]["max"],
    )
    out.update(batch=n, rtol=rtol, solver=solver_name)
    return out


# ---------------------------------------------------------------------------------------
# (c) gradient against forward cost.


def section_gradient(cfg, seed):
    rows = {"closed_form": [], "ode": []}
    print(
        "\n(c) Gradient cost: grad of sum(damage + w_final + t_final) w.r.t. (mu, phi, V0), rtol 1e-8"
    )
    print(
        f"{'method':<12}{'batch':>8}{'forward s':>12}{'grad s':>12}{'ratio':>8}"
        f"{'fwd compile':>13}{'grad compile':>14}"
    )
    for method, batches in (
        ("closed_form", cfg["grad_cf_batches"]),
        ("ode", cfg["grad_ode_batches"]),
    ):
        if not batches:
            continue

        def total(m, p, s, method=method):
            r = jax.vmap(lambda a, b, c: normal_impact(a, b, c, method=method, rtol=1e-8))(m, p, s)
            return jnp.sum(r.damage + r.w_final + r.t_final)

        fwd = jax.jit(total)
        grad = jax.jit(jax.grad(total, argnums=(0, 1, 2)))
        for n in batches:
            mu, phi, speed = batch_inputs(n, seed)
            _, fc, fr = timed(fwd, mu, phi, speed)
            g, gc, gr = timed(grad, mu, phi, speed)
            finite = bool(all(np.all(np.isfinite(np.asarray(x))) for x in g))
            row = dict(
                batch=n,
                forward_s=fr,
                grad_s=gr,
                ratio=gr / fr,
                forward_compile_s=fc,
                grad_compile_s=gc,
                finite=finite,
            )
            rows[method].append(row)
            print(
                f"{method:<12}{n:>8d}{fr:>12.3e}{gr:>12.3e}{gr / fr:>8.2f}{fc:>13.1f}{gc:>14.1f}"
                + ("" if finite else "  NON-FINITE GRADIENT"),
                flush=True,
            )
    return rows


def jaxpr_sizes(method, n=8):
    """Equation counts of the forward and gradient programs (a cheap profile)."""

    def total(m, p, s):
        r = jax.vmap(lambda a, b, c: normal_impact(a, b, c, method=method, rtol=1e-8))(m, p, s)
        return jnp.sum(r.damage + r.w_final + r.t_final)

    x = jnp.linspace(2.0, 3.0, n)

    def subjaxprs(value):
        if hasattr(value, "jaxpr") and hasattr(value, "consts"):  # ClosedJaxpr
            yield value.jaxpr
        elif hasattr(value, "eqns"):  # Jaxpr
            yield value
        elif isinstance(value, (tuple, list)):
            for v in value:
                yield from subjaxprs(v)

    def count(jaxpr):
        k = 0
        for eqn in jaxpr.eqns:
            k += 1
            for value in eqn.params.values():
                for sub in subjaxprs(value):
                    k += count(sub)
        return k

    fwd = jax.make_jaxpr(total)(x, x, x)
    grad = jax.make_jaxpr(jax.grad(total, argnums=(0, 1, 2)))(x, x, x)
    return dict(forward_eqns=count(fwd.jaxpr), grad_eqns=count(grad.jaxpr))


# ---------------------------------------------------------------------------------------
# (d) scipy.integrate.solve_ivp, one scenario at a time.


class _GaveUp(Exception):
    pass


def scipy_solve(mu, phi, v0, method, rtol, max_nfev):
    """Integrate the physical equations of motion in time T, as a user would.

    Accelerative phase: state (vehicle velocity, beam velocity, W, crush) with the constant
    accelerations of (3.2.11)-(3.2.12), until the velocities meet (terminal event).
    Decelerative phase: state (V, S, W) with V' and S' from (3.2.15)-(3.2.16), until V = 0
    (terminal event). atol = 1e-3 rtol in units of the impact speed (as barrierjax's ODE).
    Gives up (as a failure) after `max_nfev` right-hand-side evaluations.
    """
    from scipy.integrate import solve_ivp

    atol = 1e-3 * rtol
    s_star = math.sqrt(phi * phi + 3.0) - phi
    acc = (phi - s_star) / s_star
    dec = phi / mu
    nfev = [0]

    def count():
        nfev[0] += 1
        if nfev[0] > max_nfev:
            raise _GaveUp(f"gave up after {max_nfev} evaluations")

    def accelerative(t, y):
        count()
        return [-dec, acc, y[1], y[0] - y[1]]

    def meet(t, y):
        return y[0] - y[1]

    meet.terminal, meet.direction = True, -1
    # The vehicle alone would stop at mu V0 / phi; the velocities meet before.
    first = solve_ivp(
        accelerative,
        (0.0, mu * v0 / phi),
        [v0, 0.0, 0.0, 0.0],
        method=method,
        rtol=rtol,
        atol=atol * np.array([v0, v0, v0 * v0, v0 * v0]),
        events=meet,
    )
    if first.status != 1:
        return dict(status="failed", message=f"accelerative: {first.message}", nfev=nfev[0])
    t_star = first.t_events[0][0]
    vehicle, beam, w_star, crush = first.y_events[0][0]

    def decelerative(t, y):
        count()
        v, s, _ = y
        den = 2.0 * s * (s + 2.0 * mu)
        return [
            -(s * s + 3.0) / den,
            -(s**3 + 3.0 * mu * s * s - 3.0 * s - 3.0 * mu) / (den * v),
            v,
        ]

    def rest(t, y):
        return y[0]

    rest.terminal, rest.direction = True, -1
    # |V'| >= (alpha^2+3)/(2 alpha (alpha + 2 mu)), so rest comes before T* + 10 V* (1 + mu).
    v_star = 0.5 * (vehicle + beam)
    second = solve_ivp(
        decelerative,
        (t_star, t_star + 10.0 * v_star * (1.0 + mu)),
        [v_star, s_star, w_star],
        method=method,
        rtol=rtol,
        atol=atol * np.array([v0, 1.0, v0 * v0]),
        events=rest,
    )
    if second.status != 1:
        return dict(
            status="failed",
            message=f"decelerative: {second.message}",
            nfev=nfev[0],
            # what a user ignoring the warning would read off the last step
            last=dict(t_final=second.t[-1], w_final=second.y[2, -1], damage=crush),
        )
    return dict(
        status="ok",
        nfev=nfev[0],
        t_final=second.t_events[0][0],
        w_final=second.y_events[0][0][2],
        damage=crush,
    )


def section_scipy(cfg, mu, phi, speed, ref):
    def subset(k):
        return np.unique(np.linspace(0, len(mu) - 1, min(k, len(mu))).round().astype(int))

    rows, subsets = [], {}
    print(
        f"\n(d) scipy.integrate.solve_ivp, one scenario at a time (gives up after "
        f"{cfg['scipy_max_nfev']} RHS evaluations); n = scenarios used, evenly spaced over the "
        f"{len(mu)}"
    )
    print(
        f"{'method':<8}{'rtol':>8}{'n':>4}{'ms/scen':>10}{'max err (ok)':>14}{'failed':>8}"
        f"{'err incl. last state':>22}  first failure"
    )
    for method in cfg["scipy_methods"]:
        idx = subset(cfg.get("scipy_n_by_method", {}).get(method, cfg["scipy_n"]))
        subsets[method] = idx.tolist()
        sub_ref = {k: v[idx] for k, v in ref.items()}
        # Warm-up (imports, first-call set-up), not timed.
        try:
            scipy_solve(2.0, 3.0, 1.0, method, 1e-6, cfg["scipy_max_nfev"])
        except Exception:  # noqa: BLE001, S110
            pass
        for rtol in cfg["scipy_rtols"]:
            results, times = [], []
            for i in idx:
                t0 = time.perf_counter()
                try:
                    r = scipy_solve(mu[i], phi[i], speed[i], method, rtol, cfg["scipy_max_nfev"])
                except _GaveUp as exc:
                    r = dict(status="failed", message=str(exc))
                except Exception as exc:  # noqa: BLE001 - a failure is a result
                    r = dict(status="failed", message=f"{type(exc).__name__}: {exc}")
                times.append(time.perf_counter() - t0)
                results.append(r)
            ok = np.array([r["status"] == "ok" for r in results])
            errs_ok = []
            errs_all = []
            for r, j in zip(results, range(len(idx))):
                vals = r if r["status"] == "ok" else r.get("last")
                if vals is None:
                    errs_all.append(np.inf)
                    continue
                e = max(
                    abs(vals[k] / sub_ref[k][j] - 1.0) if sub_ref[k][j] else abs(vals[k])
                    for k in FIELDS
                )
                errs_all.append(e)
                if r["status"] == "ok":
                    errs_ok.append(e)
            failures = [
                dict(
                    scenario=int(idx[j]),
                    mass_ratio=float(mu[idx[j]]),
                    force_ratio=float(phi[idx[j]]),
                    message=r["message"][:160],
                )
                for j, r in enumerate(results)
                if r["status"] != "ok"
            ]
            row = dict(
                method=method,
                rtol=rtol,
                n=len(idx),
                per_scenario_s=float(np.mean(times)),
                per_scenario_s_median=float(np.median(times)),
                error=float(max(errs_ok)) if errs_ok else None,
                error_including_failed_last_state=float(max(errs_all)),
                n_failed=int((~ok).sum()),
                failures=failures,
            )
            rows.append(row)
            err = f"{row['error']:.2e}" if row["error"] is not None else "n/a"
            first = failures[0]["message"][:50] if failures else ""
            print(
                f"{method:<8}{rtol:>8.0e}{len(idx):>4d}{row['per_scenario_s'] * 1e3:>10.2f}{err:>14}"
                f"{row['n_failed']:>5d}/{len(idx):<3d}{row['error_including_failed_last_state']:>21.2e}"
                f"  {first}",
                flush=True,
            )
    return rows, subsets


def section_ratio(cfg, scipy_rows, a_rows, seed):
    """Ratio scipy time per scenario / barrierjax vmapped ODE (Tsit5) time per scenario at
    `match_batch` scenarios, with the loosest Tsit5 rtol whose error (section a) is <= scipy's
    (the next tighter one if that solve fails on the large batch)."""
    tsit = sorted(
        [r for r in a_rows if r["label"] == "Tsit5" and r["ok"]], key=lambda r: -r["rtol"]
    )
    n = cfg["match_batch"]
    out = []
    print(
        f"\n(d) Ratio scipy / barrierjax ODE (Tsit5, array API over {n} scenarios, per scenario), "
        "at equal or better error"
    )
    print(
        f"{'scipy':<8}{'rtol':>8}{'scipy err':>11}{'failed':>8}{'bj rtol':>9}{'bj err':>10}"
        f"{'scipy ms':>10}{'bj us':>9}{'ratio':>9}"
    )
    for row in scipy_rows:
        e = row["error"]
        res = dict(
            method=row["method"],
            rtol=row["rtol"],
            scipy_error=e,
            n_failed=row["n_failed"],
            n=row["n"],
            scipy_per_scenario_s=row["per_scenario_s"],
            ratio=None,
            bj_failures=[],
        )
        for match in (r for r in tsit if e is not None and r["error"] <= e):
            t = timed_forward("ode", match["rtol"], "Tsit5", n, seed)
            if not t["ok"]:
                res["bj_failures"].append(dict(rtol=match["rtol"], failure=t["failure"]))
                continue
            per = t["batch_s"] / n
            res.update(
                bj_rtol=match["rtol"],
                bj_error=match["error"],
                bj_per_scenario_s=per,
                ratio=row["per_scenario_s"] / per,
            )
            break
        out.append(res)
        failed = f"{row['n_failed']:>5d}/{row['n']:<3d}"
        if res["ratio"] is None:
            why = (
                "barrierjax failed at " + ", ".join(f"{f['rtol']:.0e}" for f in res["bj_failures"])
                if res["bj_failures"]
                else "no Tsit5 tolerance in (a) reaches this error"
            )
            err = f"{e:>11.1e}" if e is not None else f"{'n/a':>11}"
            print(f"{row['method']:<8}{row['rtol']:>8.0e}{err}{failed}  {why}", flush=True)
            continue
        note = (
            "  (bj failed at " + ", ".join(f"{f['rtol']:.0e}" for f in res["bj_failures"]) + ")"
            if res["bj_failures"]
            else ""
        )
        print(
            f"{row['method']:<8}{row['rtol']:>8.0e}{e:>11.1e}{failed}{res['bj_rtol']:>8.0e}"
            f"{res['bj_error']:>10.1e}{row['per_scenario_s'] * 1e3:>10.2f}"
            f"{res['bj_per_scenario_s'] * 1e6:>9.2f}{res['ratio']:>9.0f}{note}",
            flush=True,
        )
    return out


def cost_profile(method, n=1000):
    """XLA's cost analysis of the compiled forward batch, per scenario (the ODE's while loops
    are counted once, so only the closed form's numbers are totals)."""
    mu, phi, speed = batch_inputs(n, 0)
    compiled = (
        forward(method, 1e-8, "Tsit5" if method == "ode" else None).lower(mu, phi, speed).compile()
    )
    cost = compiled.cost_analysis()
    if isinstance(cost, (list, tuple)):
        cost = cost[0]
    keys = {
        "flops": "flops",
        "transcendentals": "transcendentals",
        "bytes accessed": "bytes_accessed",
    }
    return {v: float(cost[k]) / n for k, v in keys.items() if k in cost}


# ---------------------------------------------------------------------------------------
# Plots.


def plots(out_dir: Path, data: dict):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    fig, ax = plt.subplots(figsize=(7, 5))
    by_label = {}
    for r in data["error_vs_time"]["rows"]:
        if r["ok"]:
            by_label.setdefault(r["label"], []).append(r)
    for label, rows in by_label.items():
        rows = sorted(rows, key=lambda r: -r["rtol"])
        ax.loglog(
            [r["per_scenario_s"] for r in rows],
            [max(r["error"], 1e-17) for r in rows],
            "o-",
            label=f"barrierjax {label}" if label == "closed_form" else f"barrierjax ODE {label}",
        )
    for method in sorted({r["method"] for r in data["scipy"]["rows"]}):
        rows = [
            r for r in data["scipy"]["rows"] if r["method"] == method and r["error"] is not None
        ]
        if rows:
            ax.loglog(
                [r["per_scenario_s"] for r in rows],
                [r["error"] for r in rows],
                "x--",
                label=f"scipy {method} (loop; failed runs excluded)",
            )
    ax.set_xlabel("time per scenario [s] (barrierjax: array API batch / n; scipy: loop)")
    ax.set_ylabel("max relative error (t_final, w_final, damage)")
    ax.set_title(f"normal_impact: error vs time, {data['meta']['n_scenarios']} scenarios")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    paths.append(save(fig, out_dir / "normal_impact_error_vs_time.png"))

    fig, ax = plt.subplots(figsize=(7, 5))
    for method, rows in data["throughput"]["rows"].items():
        rows = [r for r in rows if r["ok"]]
        if rows:
            ax.loglog(
                [r["batch"] for r in rows],
                [r["per_second"] for r in rows],
                "o-",
                label=f"{method} (rtol {rows[0]['rtol']:.0e})",
            )
    ax.axhline(TARGET_THROUGHPUT, color="k", ls=":", label="target 1e6/s (closed form)")
    ax.set_xlabel("batch size")
    ax.set_ylabel("scenarios per second")
    ax.set_title("normal_impact throughput, array API (vmapped chunks), CPU")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    paths.append(save(fig, out_dir / "normal_impact_throughput.png"))

    fig, ax = plt.subplots(figsize=(7, 4))
    for method, rows in data["gradient"]["rows"].items():
        if rows:
            ax.semilogx([r["batch"] for r in rows], [r["ratio"] for r in rows], "o-", label=method)
    ax.axhline(TARGET_GRAD_RATIO, color="k", ls=":", label="target 5")
    ax.set_xlabel("batch size")
    ax.set_ylabel("grad time / forward time")
    ax.set_title("normal_impact gradient cost")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    paths.append(save(fig, out_dir / "normal_impact_gradient.png"))
    return paths


# ---------------------------------------------------------------------------------------


def main(argv=None):
    parser = argument_parser(__doc__)
    args = parser.parse_args(argv)
    cfg = config(args.quick)
    args.out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    load_start = os.getloadavg()
    sources_start = source_fingerprint()

    mu, phi, speed = scenario_set(cfg["n_draws"], cfg["corners"], args.seed)
    n = len(mu)
    print(
        f"normal_impact benchmark ({'quick' if args.quick else 'full'}), {n} scenarios, "
        f"jax {jax.__version__} on {jax.devices()[0].platform}, {os.cpu_count()} CPU cores, "
        f"load average {load_start[0]:.1f}"
    )
    t0 = time.perf_counter()
    refs = reference_set(mu, phi, speed, cfg["ref_dps"])
    ref = as_float(refs)
    ref_s = time.perf_counter() - t0
    # Self-check of the reference: a few scenarios again at +10 digits.
    check = []
    for i in range(min(4, n)):
        hi = reference(mu[i], phi[i], speed[i], cfg["ref_dps"] + 10)
        with mp.workdps(cfg["ref_dps"] + 20):
            check.append(max(float(abs(refs[i][k] / hi[k] - 1)) for k in ("t_final", "w_final")))
    ref_check = max(check)
    print(
        f"reference: mpmath {cfg['ref_dps']} digits, {ref_s:.1f} s; "
        f"agreement with {cfg['ref_dps'] + 10} digits: {ref_check:.1e}"
    )

    print_header_a(n)
    a_rows = section_error_vs_time(cfg, mu, phi, speed, ref)

    b_rows, b_diag = section_throughput(cfg, args.seed)
    steps = None
    if cfg["step_batch"]:
        steps = ode_step_counts(cfg["step_batch"], args.seed, cfg["ode_throughput_rtol"])
        print(
            f"ODE step counts over {steps['batch']} scenarios (Tsit5, rtol {steps['rtol']:.0e}): "
            + "; ".join(
                f"{ph} min {steps[ph]['min']} median {steps[ph]['median']:.0f} "
                f"p99 {steps[ph]['p99']:.0f} max {steps[ph]['max']}"
                for ph in ("accelerative", "decelerative")
            )
            + f"; vmap efficiency (mean/max) decelerative {steps['vmap_efficiency']['decelerative']:.2f}"
        )

    c_rows = section_gradient(cfg, args.seed)

    d_rows, d_subsets = section_scipy(cfg, mu, phi, speed, ref)
    ratios = section_ratio(cfg, d_rows, a_rows, args.seed)
    cf_cost = cost_profile("closed_form")

    # ------------------------------------------------------------------ verdicts
    valid = [r for r in ratios if r.get("ratio") is not None]
    worst = min(valid, key=lambda r: r["ratio"]) if valid else None
    t1 = dict(
        target=f"vmapped ODE over {cfg['match_batch']} scenarios costs <= 1/{TARGET_SCIPY_RATIO:.0f} "
        "of scipy solve_ivp per scenario at equal or better error",
        measured_min_ratio=worst["ratio"] if worst else None,
        at=dict(method=worst["method"], rtol=worst["rtol"]) if worst else None,
        all_ratios=[(r["method"], r["rtol"], r.get("ratio")) for r in ratios],
        verdict=("PASS" if worst and worst["ratio"] >= TARGET_SCIPY_RATIO else "FAIL"),
    )
    cf_ok = [r for r in b_rows["closed_form"] if r["ok"]]
    best = max(cf_ok, key=lambda r: r["per_second"]) if cf_ok else None
    largest = max(cf_ok, key=lambda r: r["batch"]) if cf_ok else None
    t2 = dict(
        target="closed form evaluates >= 1e6 scenarios per second",
        measured_peak_per_second=best["per_second"] if best else None,
        at_batch=best["batch"] if best else None,
        at_largest_batch=dict(batch=largest["batch"], per_second=largest["per_second"])
        if largest
        else None,
        verdict="PASS" if best and best["per_second"] >= TARGET_THROUGHPUT else "FAIL",
    )
    g_all = [(m, r["batch"], r["ratio"]) for m, rows in c_rows.items() for r in rows]
    g_worst = max(g_all, key=lambda x: x[2]) if g_all else None
    t3 = dict(
        target="gradient costs <= 5x the forward solve",
        measured=[dict(method=m, batch=b, ratio=x) for m, b, x in g_all],
        worst=dict(method=g_worst[0], batch=g_worst[1], ratio=g_worst[2]) if g_worst else None,
        verdict="PASS" if g_worst and g_worst[2] <= TARGET_GRAD_RATIO else "FAIL",
    )
    profile = {}
    if t3["verdict"] == "FAIL":
        for m in sorted({x[0] for x in g_all if x[2] > TARGET_GRAD_RATIO}):
            profile[m] = jaxpr_sizes(m)

    # ------------------------------------------------------------------ surprises
    surprises = []
    for r in a_rows:
        if not r["ok"]:
            surprises.append(
                f"{r['label']} rtol {r['rtol']:.0e} failed on the batch: {r['failure']}"
                + (
                    f"; alone, scenarios {r['failing_alone']} fail"
                    if r.get("failing_alone") is not None
                    else ""
                )
            )
        elif r["rtol"] <= 1e-8 and r["error"] > 1e-7:
            surprises.append(
                f"{r['label']} rtol {r['rtol']:.0e}: error {r['error']:.1e} > 1e-7 "
                f"(worst scenario {r['worst_scenario']}: mu {mu[r['worst_scenario']]:.3g}, "
                f"phi {phi[r['worst_scenario']]:.6g}, V0 {speed[r['worst_scenario']]:.3g})"
            )
        elif r["error"] > 100 * r["rtol"]:
            surprises.append(
                f"{r['label']} rtol {r['rtol']:.0e}: error {r['error']:.1e} is over 100 x rtol"
            )

    for r in ratios:
        for f in r.get("bj_failures", []):
            line = (
                f"barrierjax ODE Tsit5 rtol {f['rtol']:.0e} failed on the {cfg['match_batch']}-scenario "
                f"batch: {f['failure']}"
            )
            if line not in surprises:
                surprises.append(line)
    for r in d_rows:
        if r["n_failed"]:
            mus = sorted(f["mass_ratio"] for f in r["failures"])
            kinds = sorted({f["message"].split(":")[0] for f in r["failures"]})
            surprises.append(
                f"scipy {r['method']} rtol {r['rtol']:.0e} failed on {r['n_failed']}/{r['n']} "
                f"scenarios (mass ratio {mus[0]:.3g} .. {mus[-1]:.3g}; {', '.join(kinds)})"
            )

    changed = sources_changed(sources_start)
    if changed:
        surprises.append(changed)

    elapsed = time.perf_counter() - start
    data = dict(
        meta=dict(
            **meta(args, load_start, sources_start, changed, mpmath=mp.__version__),
            n_scenarios=n,
            reference_digits=cfg["ref_dps"],
            reference_self_check=ref_check,
            reference_seconds=ref_s,
            elapsed_s=elapsed,
            config={k: v for k, v in cfg.items()},
            timing="ahead-of-time compile (timed separately), one warm-up call, then best of >= 3 calls (1 call when a call takes > 1 s)",
        ),
        scenarios=dict(
            mass_ratio=mu.tolist(),
            force_ratio=phi.tolist(),
            speed=speed.tolist(),
            reference={k: [str(r[k]) for r in refs] for k in FIELDS},
        ),
        error_vs_time=dict(rows=a_rows),
        throughput=dict(
            rows=b_rows,
            chunked_diagnostic=b_diag,
            ode_step_counts=steps,
            closed_form_cost_per_scenario=cf_cost,
        ),
        gradient=dict(rows=c_rows, profile=profile),
        scipy=dict(rows=d_rows, scenarios=d_subsets, ratios=ratios),
        targets=dict(scipy_ratio=t1, closed_form_throughput=t2, gradient_ratio=t3),
        surprises=surprises,
    )
    if not args.no_plots:
        data["plots"] = [str(p) for p in plots(args.out, data)]
    path = args.out / "normal_impact.json"
    path.write_text(json.dumps(data, indent=1, default=float))

    print("\n" + "=" * 78)
    print(
        "SUMMARY: acceptance targets"
        + (" (quick run: sizes too small for the verdicts to mean anything)" if args.quick else "")
    )
    if worst:
        print(
            f"[{t1['verdict']}] ODE vs scipy: min ratio {worst['ratio']:.0f} (target >= "
            f"{TARGET_SCIPY_RATIO:.0f}, i.e. {TARGET_SCIPY_RATIO / worst['ratio']:.1f}x short) at scipy "
            f"{worst['method']} rtol {worst['rtol']:.0e} ({worst['scipy_per_scenario_s'] * 1e3:.2f} ms/scenario)"
            f" vs barrierjax Tsit5 rtol {worst['bj_rtol']:.0e} ({worst['bj_per_scenario_s'] * 1e6:.1f} us/scenario"
            f" over {cfg['match_batch']})"
            if worst["ratio"] < TARGET_SCIPY_RATIO
            else f"[{t1['verdict']}] ODE vs scipy: min ratio {worst['ratio']:.0f} (target >= "
            f"{TARGET_SCIPY_RATIO:.0f}) at scipy {worst['method']} rtol {worst['rtol']:.0e}"
        )
        print(
            "    all ratios: "
            + ", ".join(
                f"{r['method']} {r['rtol']:.0e}: "
                + (f"{r['ratio']:.0f}" if r["ratio"] is not None else "n/a")
                + (f" ({r['n_failed']}/{r['n']} scipy failed)" if r["n_failed"] else "")
                for r in ratios
            )
        )
    else:
        print(f"[{t1['verdict']}] ODE vs scipy: no comparable configuration")
    if best:
        print(
            f"[{t2['verdict']}] closed-form throughput: peak {best['per_second']:.3e} scenarios/s "
            f"at batch {best['batch']} (target >= 1e6"
            + (
                f", {TARGET_THROUGHPUT / best['per_second']:.1f}x short"
                if best["per_second"] < TARGET_THROUGHPUT
                else ""
            )
            + f"); at batch {largest['batch']}: {largest['per_second']:.3e}/s"
        )
        if cf_cost:
            print(
                "    XLA cost per scenario (closed form, rtol 1e-8): "
                + ", ".join(f"{k} {v:.0f}" for k, v in cf_cost.items())
            )
        for d in b_diag:
            if d["ok"]:
                print(
                    f"    diagnostic: {d['method']} batch {d['batch']} as one jit(vmap) over the "
                    f"whole batch: {d['per_second']:.3e} scenarios/s"
                )
    if g_worst:
        print(
            f"[{t3['verdict']}] gradient / forward: worst {g_worst[2]:.2f} ({g_worst[0]}, batch "
            f"{g_worst[1]}) (target <= 5); all: "
            + ", ".join(f"{m} {b}: {x:.2f}" for m, b, x in g_all)
        )
    for m, p in profile.items():
        print(
            f"    profile {m}: jaxpr equations forward {p['forward_eqns']}, grad {p['grad_eqns']}"
        )
    if surprises:
        print("Numerical surprises:")
        for s in surprises:
            print("  - " + s)
    print(
        f"load average at start {load_start[0]:.1f}, at end {os.getloadavg()[0]:.1f} "
        f"({os.cpu_count()} cores); elapsed {elapsed:.0f} s"
    )
    print(
        f"wrote {path}"
        + ("" if args.no_plots else " and " + ", ".join(p.name for p in map(Path, data["plots"])))
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
