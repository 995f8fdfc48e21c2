"""Benchmark of the beam finite element of report 4.2 (`barrierjax.beam`) on the cantilever
examples of 4.3, side by side with OpenSees.

Run from the repository root:

    python benchmarks/beam_fe.py            # full run (about 11 minutes on 2 cores)
    python benchmarks/beam_fe.py --quick    # smoke run (tiny sizes; OpenSees skipped if absent)

It prints tables and writes `beam_fe.json`, `beam_fe_error_vs_time.png` and
`beam_fe_tip_history.png` to `--out` (default `benchmarks/results/`). Sections:

(a) OpenSees. The rate-independent Example 1 (elastic-perfectly plastic fibres) built as
    `_opensees_cantilever.run_example_1` builds it: 20 equal layers through the depth (the
    midpoint rule of OpenSees's `patch rect`), 3 Lobatto points per element, co-rotational
    strains without barrierjax's shallow-arch term (OpenSees's axial strain is the chord
    stretch over the length), consistent mass, translational tip mass, Newmark's average
    acceleration (`scheme="newmark"`) at the same constant step. Left different: barrierjax's
    consistent mass carries the rotary inertia rho I (OpenSees's `-cMass` does not; measured
    while writing this script: 1.4e-5 of the rest deflection), and the pulse: barrierjax
    averages the rectangular force over each step, OpenSees applies it at the steps and
    scales it so that the trapezoidal impulse is exact (the two differ by O(dt)). Both codes
    run the same steps and meshes: step refinement at 14 elements, and mesh refinement with
    the step in proportion to the element's length (OpenSees alone on the finest mesh).
    Compared: the tip's rest deflection (the transverse tip deflection at the first zero of
    its velocity after the pulse, interpolated linearly between steps), the permanent
    deflection (the middle of the first elastic swing after the rest) and the whole tip
    history (largest difference over the run, relative to the largest deflection), all from
    the histories by one helper (`rest_and_permanent`) for both codes.
(b) Wall time of one run at the same model and step (14 elements, dt 1e-4 s): barrierjax
    compiled ahead of time (the compile time is reported apart), then the best of 3 calls;
    OpenSees's time stepping (`analysis_seconds`, model building apart), best of 3 runs.
(c) vmap: 64 variants of the rate-dependent Example 1 (Cowper-Symonds, barrierjax's own
    model `example_model(1)` and its default scheme and sub-step), a 4 x 4 x 4 grid of yield
    stress, D and tip mass around the report's data, as one `jax.vmap`, against one run of
    the same model over the same steps (both compiled ahead of time; best of 3 single runs,
    of 2 batched calls). The horizon is the first 5 ms (50 steps), to keep the batch's calls
    short (the whole event, 1200 steps, would take it about 3 minutes a call).
(d) Error against run time under step refinement (14 elements) and mesh refinement (the
    step in proportion to the element's length) for each scheme, on the model of (a):
    "newmark", "damped-newmark", "linear-acceleration" (at fractions of its stable step)
    and "report" (the same as linear acceleration on a rate-independent law: barrierjax then
    steps the fibres with the law's exact return map; one run checks it). Then the
    rate-dependent Example 1 (barrierjax's model) under step refinement for all four
    schemes over the first 5 ms (the tip deflection then), where "report" steps the fibres
    with the report's alpha scheme (4.2.8)-(4.2.11). References: see `section_errors` and
    `section_rate_dependent`. Newton: each run takes the first setting of `NEWTON_LADDER`
    (iterations, line-search lengths) under which every step converges (`CONVERGED`, finite
    displacements); the compile and run time of the settings that failed is reported apart
    ("search"). A run is timed once after its compilation, or as the best of 3 when a call
    takes under 1 s.
(e) Where the report's scheme ("report": linear acceleration with the alpha scheme) becomes
    unstable on Examples 1, 2 and 3 (barrierjax's models, rate-dependent): the largest stable
    constant step by bisection (unstable: non-finite, or a kinetic energy above the work of
    the load by 5 %), against `stable_step(omega_max)` from the top eigenfrequency of the
    linear matrices on the free dofs, and the report's own steps run as the report runs
    them (`report_example(n, scheme="report")`).

A benchmark reports; it never tunes the model.
"""

import os

# OpenBLAS's threads (jaxlib's LAPACK calls go to scipy's OpenBLAS) fight XLA's for the
# 2 cores: a 171-dof LU took 147 ms with them and 1.2 ms without (measured 2026-11-22).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import jax

jax.config.update("jax_enable_x64", True)

import dataclasses
import json
import math
import sys
import time
from pathlib import Path

import numpy as np
import scipy.linalg

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _opensees_cantilever as opensees
import jax.numpy as jnp
from _common import argument_parser, meta, save, source_fingerprint, sources_changed

from barrierjax.beam.examples import EXAMPLES, example_model, report_example
from barrierjax.beam.integrate import SCHEME_PARAMETERS, integrate, stable_step
from barrierjax.beam.layered import rectangular_section
from barrierjax.beam.model import cantilever, linear_matrices, mass_matrix
from barrierjax.materials.plasticity import RateIndependentPlasticity

P = opensees.EXAMPLE_1
N_FIBRES = 20  # OpenSees module's default layers
# The largest relative Newton residual of the accepted state (`BeamHistory.residual`) of a
# converged step: the rounding of the inertia term M (u - base) / (beta dt^2) alone reaches a
# few 1e-6 at steps of 1e-6 s (`integrate` stops its iterations early at `tolerance`, 1e-6).
CONVERGED = 1e-5
NEWTON_LADDER = ((2, 1), (4, 1), (8, 4), (16, 8), (32, 8))  # (iterations, line_search)
TARGET_AGREEMENT = 0.02
TARGET_SPEED_RATIO = 1.0
TARGET_VMAP_RATIO = 10.0
SCHEMES = ("newmark", "damped-newmark", "linear-acceleration", "report")


def config(quick: bool) -> dict:
    if quick:
        return {
            "n_elements": 4,
            "dt": 2.5e-5,
            "t_end": 0.12,
            "steps": (2.5e-5,),
            "meshes": (),
            "opensees_meshes": (),
            "mesh_dt": 2.5e-5,
            "la_fractions": (0.9,),
            "la_meshes": (),
            "la_t_end": 0.11,
            "opensees_repeats": 1,
            "vmap_grid": 2,
            "vmap_steps": 4,
            "rd_horizon": 0.0005,
            "rd_steps": {"implicit": (2.5e-5,), "linear": (0.9,)},
            "stability_examples": (1,),
            "stability_steps": 200,
            "bisections": 4,
        }
    return {
        "n_elements": 14,
        "dt": 1e-4,
        "t_end": 0.18,  # past the first elastic swing after the rest (about 0.16 s)
        "steps": (2e-4, 1e-4, 5e-5, 2.5e-5),
        "meshes": (7, 14, 28),
        "opensees_meshes": (56,),  # OpenSees only: barrierjax would take minutes
        "mesh_dt": 5e-5,  # at `n_elements`, in proportion to the element's length
        "la_fractions": (0.9, 0.45, 0.225),  # of the stable step
        "la_meshes": (7, 14, 28),
        "la_t_end": 0.11,  # the rest only (about 0.1 s): the small steps are dear
        "opensees_repeats": 3,
        "vmap_grid": 4,
        "vmap_steps": 50,
        "rd_horizon": 0.005,
        "rd_steps": {"implicit": (1e-4, 5e-5, 2.5e-5), "linear": (0.9, 0.45, 0.225)},
        "stability_examples": (1, 2, 3),
        "stability_steps": 2000,
        "bisections": 10,
    }


# --------------------------------------------------------------------------------------
# Models, runs and the rest deflection.


def rest_and_permanent(times, transverse, velocity, pulse_end) -> dict:
    """The tip's first rest after the pulse and its permanent deflection, from a history (as
    `_opensees_cantilever.run_example_1` computes them): the first step after `pulse_end`
    whose transverse velocity is <= 0, the rest time and deflection interpolated linearly
    between it and the step before; the permanent deflection is the middle of the first
    elastic swing after the rest, (largest deflection from the rest on + smallest before the
    velocity turns positive again) / 2. NaN where the history ends first."""
    times, transverse, velocity = (
        np.asarray(a, dtype=float) for a in (times, transverse, velocity)
    )
    out = {"rest_time": np.nan, "rest_deflection": np.nan, "permanent_deflection": np.nan}
    after = np.nonzero((times > pulse_end * (1 + 1e-9)) & (velocity <= 0.0))[0]
    if not len(after):
        return out
    k = after[0]
    v0, v1 = velocity[k - 1], velocity[k]
    s = v0 / (v0 - v1) if v0 != v1 else 1.0
    out["rest_time"] = float(times[k - 1] + s * (times[k] - times[k - 1]))
    out["rest_deflection"] = float(transverse[k - 1] + s * (transverse[k] - transverse[k - 1]))
    back = np.nonzero((np.arange(len(times)) > k) & (velocity > 0.0))[0]
    if len(back):
        swing = np.max(transverse[k - 1 :]) + np.min(transverse[k : back[0]])
        out["permanent_deflection"] = float(swing / 2)
    return out


def matched_model(n_elements):
    """Example 1 as `_opensees_cantilever` builds it (see (a) in the module docstring)."""
    law = RateIndependentPlasticity(P["E"], P["sigma0"])
    section = rectangular_section(P["width"], P["height"], law, points=N_FIBRES, rule="midpoint")
    model = cantilever(
        P["length"],
        n_elements,
        section,
        P["rho"],
        tip_mass=P["tip_mass"],
        tip_impulse=P["impulse"],
        duration=P["pulse_duration"],
    )
    return dataclasses.replace(model, shallow=False)


def top_stable_step(model, scheme="report"):
    """`stable_step` of `scheme` from the top eigenfrequency of the linear (K, M) restricted to
    the free dofs. Returns (stable step, omega_max)."""
    K, M = (np.asarray(a) for a in linear_matrices(model))
    free = model.free()
    eig = scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)
    omega_max = float(np.sqrt(eig[-1]))
    beta, gamma, _ = SCHEME_PARAMETERS[scheme]
    return float(stable_step(omega_max, beta, gamma)), omega_max


def tip_runner(model, scheme, iterations, line_search):
    """jit of dts -> (times, tip transverse displacement and velocity, largest residual, all
    displacements finite)."""

    def run(dts):
        h = integrate(model, dts, scheme=scheme, iterations=iterations, line_search=line_search)
        finite = jnp.all(jnp.isfinite(h.displacement))
        return h.times, h.displacement[:, -2], h.velocity[:, -2], jnp.max(h.residual), finite

    return jax.jit(run)


def compile_timed(fn, *args):
    """(compiled, seconds) of the ahead-of-time compilation."""
    start = time.perf_counter()
    compiled = fn.lower(*args).compile()
    return compiled, time.perf_counter() - start


def call_timed(compiled, *args, repeats=None):
    """(output, best seconds): one call, then the best of 3 when it took under 1 s (of
    `repeats` calls when given)."""
    times, out = [], None
    while True:
        start = time.perf_counter()
        out = jax.block_until_ready(compiled(*args))
        times.append(time.perf_counter() - start)
        wanted = repeats if repeats is not None else (3 if times[0] < 1.0 else 1)
        if len(times) >= wanted:
            return out, min(times)


def converged_run(model, scheme, dt, t_end, *, start=0, repeats=None) -> dict:
    """Run `model` in equal steps of at most `dt` to `t_end` with the first `NEWTON_LADDER` setting
    (from index `start`) whose every step converges. Returns a row: the setting, the tip's
    deflection at the end, its rest and permanent deflections, the run time, the compile
    time and the time spent on the settings that failed."""
    n_steps = math.ceil(t_end / dt - 1e-9)
    dts = jnp.full(n_steps, t_end / n_steps)  # equal steps ending on t_end, <= dt
    search = 0.0
    row = {}
    for rung in range(start, len(NEWTON_LADDER)):
        iterations, line_search = NEWTON_LADDER[rung]
        compiled, compile_s = compile_timed(tip_runner(model, scheme, iterations, line_search), dts)
        (times, w, v, residual, finite), seconds = call_timed(compiled, dts, repeats=repeats)
        ok = bool(finite) and float(residual) < CONVERGED
        row = {
            "scheme": scheme,
            "n_elements": len(model.connectivity),
            "dt": dt,
            "steps": int(dts.shape[0]),
            "rung": rung,
            "iterations": iterations,
            "line_search": line_search,
            "max_residual": float(residual),
            "converged": ok,
            "seconds": seconds,
            "compile_s": compile_s,
            "search_s": search,
            "tip_end": float(w[-1]),
            **rest_and_permanent(times, w, v, P["pulse_duration"]),
        }
        if ok:
            row["history"] = (np.asarray(times), np.asarray(w))
            return row
        search += compile_s + seconds
    return row


def print_run(row, tag=""):
    newton = f"{row['iterations']:2d}/{row['line_search']}"
    flag = "" if row["converged"] else f"  NOT CONVERGED (residual {row['max_residual']:.1e})"
    print(
        f"    {tag:19s} {row['n_elements']:3d} {row['dt']:9.3g} {newton:>6s} "
        f"{row['tip_end']:10.5f} {row['rest_deflection']:10.5f} "
        f"{row['permanent_deflection']:10.5f} "
        f"{row['seconds']:8.2f} {row['compile_s']:7.1f} {row['search_s']:7.1f}{flag}"
    )


RUN_HEADER = (
    f"    {'code / scheme':19s} {'el':>3s} {'dt (s)':>9s} {'Newton':>6s} {'tip at end':>10s} "
    f"{'rest (in)':>10s} "
    f"{'perm. (in)':>10s} {'run s':>8s} {'comp. s':>7s} {'search':>7s}"
)


# --------------------------------------------------------------------------------------
# (a), (b): OpenSees and barrierjax, same model and step.


def opensees_available() -> bool:
    try:
        opensees._ops()
    except ImportError as error:
        print(f"\nOpenSees skipped: {error}")
        return False
    return True


def opensees_run(n_elements, dt, t_end, repeats=1) -> dict:
    """Run the OpenSees module `repeats` times; the best analysis time. The deflections come
    from `rest_and_permanent` on its history (checked against the module's own rest)."""
    runs = [opensees.run_example_1(dt, t_end, n_elements) for _ in range(repeats)]
    r = runs[0]
    row = {
        "n_elements": n_elements,
        "dt": dt,
        "converged": bool(r.converged),
        "retried_steps": r.parameters["retried_steps"],
        "seconds": min(x.analysis_seconds for x in runs),
        "build_s": min(x.build_seconds for x in runs),
        **rest_and_permanent(r.times, r.transverse, r.transverse_velocity, P["pulse_duration"]),
    }
    assert np.isclose(row["rest_deflection"], r.rest_deflection, equal_nan=True), (row, r)
    row["history"] = (r.times, r.transverse)
    return row


def history_difference(bj, ops) -> float:
    """Largest |barrierjax - OpenSees| tip deflection over the common steps, over the largest
    OpenSees deflection."""
    (tb, wb), (to, wo) = bj["history"], ops["history"]
    n = min(len(tb), len(to))
    assert np.allclose(tb[:n], to[:n], rtol=1e-9, atol=1e-12)
    return float(np.max(np.abs(wb[:n] - wo[:n])) / np.max(np.abs(wo[:n])))


def mesh_step(cfg, n_elements):
    """The step of the mesh sweep: `mesh_dt` at `n_elements`, in proportion to the length of
    the elements."""
    return cfg["mesh_dt"] * cfg["n_elements"] / n_elements


def is_mesh_row(cfg, row):
    return np.isclose(row["dt"], mesh_step(cfg, row["n_elements"]), rtol=1e-12)


def sweep_cases(cfg):
    """(n_elements, dt) of a step sweep at `n_elements` (smallest step first: the largest
    fails soonest) and a mesh sweep (`mesh_step`)."""
    n0 = cfg["n_elements"]
    cases = [(n0, dt) for dt in sorted(cfg["steps"])]
    for n in cfg["meshes"]:
        if not any(m == n and np.isclose(d, mesh_step(cfg, n)) for m, d in cases):
            cases.append((n, mesh_step(cfg, n)))
    return cases


def run_sweep(scheme, cases, t_end, label, *, repeats_at=None, build=matched_model):
    """`converged_run` of `build(n_elements)` over `cases`; each run starts on the Newton
    setting that the largest smaller step at `cases[0]`'s mesh needed (a larger step needs
    at least as many)."""
    rows, rung_at = [], {}
    for n, dt in cases:
        rung = max([r for d, r in rung_at.items() if d <= dt], default=0)
        repeats = 3 if (n, dt) == repeats_at else None
        row = converged_run(build(n), scheme, dt, t_end, start=rung, repeats=repeats)
        if row["converged"] and n == cases[0][0]:
            rung_at[dt] = row["rung"]
        print_run(row, label)
        rows.append(row)
    return rows


def section_opensees(cfg, have_opensees):
    """(a) and (b): barrierjax ("newmark") and OpenSees at the same steps and meshes, and
    OpenSees alone on `opensees_meshes`; at (`n_elements`, `dt`) both are timed as the best
    of 3."""
    t_end, headline = cfg["t_end"], (cfg["n_elements"], cfg["dt"])
    print(
        f"\n(a) rate-independent Example 1, barrierjax 'newmark' and OpenSees, same model and "
        f"step, to {t_end:g} s"
    )
    print(RUN_HEADER)
    rows = []
    for bj in run_sweep("newmark", sweep_cases(cfg), t_end, "barrierjax", repeats_at=headline):
        n, dt = bj["n_elements"], bj["dt"]
        row = {"n_elements": n, "dt": dt, "barrierjax": bj}
        if have_opensees:
            repeats = cfg["opensees_repeats"] if (n, dt) == headline else 1
            row["opensees"] = ops = opensees_run(n, dt, t_end, repeats)
            row["rest_difference"] = bj["rest_deflection"] / ops["rest_deflection"] - 1
            row["permanent_difference"] = (
                bj["permanent_deflection"] / ops["permanent_deflection"] - 1
            )
            row["history_difference"] = history_difference(bj, ops) if bj["converged"] else None
        rows.append(row)
    if have_opensees:
        for n in cfg["opensees_meshes"]:
            dt = mesh_step(cfg, n)
            rows.append({"n_elements": n, "dt": dt, "opensees": opensees_run(n, dt, t_end)})
        print_comparison(rows)
    return rows


def print_comparison(rows):
    print(
        f"    {'el':>3s} {'dt (s)':>9s} {'OpenSees rest':>13s} {'perm.':>9s} {'run s':>7s} "
        f"{'retried':>7s} {'rest diff':>9s} {'perm diff':>9s} {'history diff':>12s}"
    )
    for row in rows:
        ops = row["opensees"]
        history = row.get("history_difference")
        differences = (
            f"{row['rest_difference']:+9.1e} {row['permanent_difference']:+9.1e} "
            if "barrierjax" in row
            else f"{'-':>9s} {'-':>9s} "
        )
        print(
            f"    {row['n_elements']:3d} {row['dt']:9.3g} {ops['rest_deflection']:13.5f} "
            f"{ops['permanent_deflection']:9.5f} {ops['seconds']:7.2f} {ops['retried_steps']:7d} "
            + differences
            + (f"{history:12.1e}" if history is not None else f"{'-':>12s}")
        )


def convergence(cfg, rows):
    """Each code's values under step refinement (at `n_elements`) and mesh refinement
    (`mesh_step`, with `mesh_extrapolation`), for the rest and permanent deflections."""
    out = {}
    for code in ("barrierjax", "opensees"):
        for kind, key in (("step", "dt"), ("mesh", "n_elements")):
            if kind == "step":
                sub = [r for r in rows if r["n_elements"] == cfg["n_elements"]]
            else:
                sub = [r for r in rows if is_mesh_row(cfg, r)]
            sub = sorted(
                (r for r in sub if code in r and r[code]["converged"]),
                key=lambda r: r[key] if kind == "mesh" else -r[key],
            )
            for quantity in ("rest_deflection", "permanent_deflection") if sub else ():
                values = [r[code][quantity] for r in sub]
                entry = {"sizes": [r[key] for r in sub], "values": values}
                if kind == "mesh" and len(sub) >= 3:
                    entry.update(mesh_extrapolation(entry["sizes"], values))
                out[f"{code} {kind} {quantity}"] = entry
    print("    convergence (coarse to fine); mesh limits by Richardson extrapolation:")
    for name, entry in out.items():
        values = " ".join(f"{v:.5f}" for v in entry["values"])
        limit = (
            f" -> {entry['limit']:.4f} (order {entry['order']:.2f}, +-{entry['error']:.1e})"
            if "limit" in entry
            else ""
        )
        print(f"      {name:40s} {values}{limit}")
    return out


def section_speed(cfg, rows):
    """(b): the run at (`n_elements`, `dt`) from (a), both codes timed as the best of 3."""
    n, dt = cfg["n_elements"], cfg["dt"]
    row = next(r for r in rows if (r["n_elements"], r["dt"]) == (n, dt))
    bj = row["barrierjax"]
    out = {"barrierjax": bj}
    print(f"\n(b) one run, {n} elements, dt {dt:g} s, to {cfg['t_end']:g} s (best of 3)")
    print(
        f"    barrierjax 'newmark' ({bj['iterations']} Newton iterations, line search "
        f"{bj['line_search']}): {bj['seconds']:.2f} s, compile {bj['compile_s']:.1f} s"
        + ("" if bj["converged"] else " (NOT CONVERGED)")
    )
    if "opensees" in row:
        ops = row["opensees"]
        out["opensees"] = ops
        out["ratio"] = bj["seconds"] / ops["seconds"]
        print(
            f"    OpenSees: {ops['seconds']:.2f} s (model building {ops['build_s']:.3f} s); "
            f"barrierjax / OpenSees = {out['ratio']:.2f}"
        )
    return out


# --------------------------------------------------------------------------------------
# (c) vmap over 64 variants.


def section_vmap(cfg):
    """64 variants (yield stress, D, tip mass) of the rate-dependent Example 1 in one vmap."""
    k = cfg["vmap_grid"]
    data = EXAMPLES[1]
    sigma0 = data["sigma0"] * np.linspace(0.8, 1.2, k)
    D = np.geomspace(10.0, 160.0, k)
    tip_mass = data["tip_mass"] * np.linspace(0.75, 1.25, k)
    grid = [jnp.asarray(a.ravel()) for a in np.meshgrid(sigma0, D, tip_mass, indexing="ij")]
    step = data["dt"] / math.ceil(data["dt"] / data["max_substep"])  # the library's sub-step
    dts = jnp.full(cfg["vmap_steps"], step)

    def run(s0, d, m):
        model = example_model(1, sigma0=s0, D=d, tip_mass=m)
        h = integrate(model, dts, scheme="damped-newmark")
        return h.displacement[-1, -2], jnp.max(h.residual)

    scalars = (jnp.asarray(data["sigma0"]), jnp.asarray(40.0), jnp.asarray(data["tip_mass"]))
    single, single_compile = compile_timed(jax.jit(run), *scalars)
    _, single_s = call_timed(single, *scalars, repeats=3)
    batch, batch_compile = compile_timed(jax.jit(jax.vmap(run)), *grid)
    (tips, residuals), batch_s = call_timed(batch, *grid, repeats=2)
    check = single(*(g[-1] for g in grid))[0]
    out = {
        "variants": len(grid[0]),
        "steps": cfg["vmap_steps"],
        "step": step,
        "single_s": single_s,
        "single_compile_s": single_compile,
        "batch_s": batch_s,
        "batch_compile_s": batch_compile,
        "ratio": batch_s / single_s,
        "max_residual": float(jnp.max(residuals)),
        "tip_range": [float(jnp.min(tips)), float(jnp.max(tips))],
        "vmap_vs_single": float(abs(tips[-1] - check) / abs(check)),
        "grid": {"sigma0": sigma0.tolist(), "D": D.tolist(), "tip_mass": tip_mass.tolist()},
    }
    print(
        f"\n(c) vmap: {out['variants']} variants of the rate-dependent Example 1 (sigma0 "
        f"{sigma0[0]:.0f}..{sigma0[-1]:.0f} psi, D {D[0]:g}..{D[-1]:g} 1/s, tip mass "
        f"{tip_mass[0]:.5f}..{tip_mass[-1]:.5f}), 'damped-newmark', {cfg['vmap_steps']} steps "
        f"of {step:g} s"
    )
    print(
        f"    one run {single_s:.2f} s (compile {single_compile:.1f} s); {out['variants']} "
        f"vmapped {batch_s:.2f} s (compile {batch_compile:.1f} s): ratio {out['ratio']:.1f}, "
        f"{batch_s / single_s / out['variants']:.2f} of a loop"
    )
    print(
        f"    tip deflection at the end {out['tip_range'][0]:.4f}..{out['tip_range'][1]:.4f} in; "
        f"largest residual {out['max_residual']:.1e}; vmap vs single call "
        f"{out['vmap_vs_single']:.1e}"
    )
    return out


# --------------------------------------------------------------------------------------
# (d) Error against run time.


def observed_orders(sizes, values, reference):
    """Least-squares slope of log |value - reference| against log size, and the order from
    each successive pair."""
    sizes, errors = np.asarray(sizes, float), np.abs(np.asarray(values, float) - reference)
    keep = np.isfinite(errors) & (errors > 0)
    fit = (
        float(np.polyfit(np.log(sizes[keep]), np.log(errors[keep]), 1)[0])
        if keep.sum() > 1
        else None
    )
    pairs = [
        float(np.log(errors[i] / errors[i + 1]) / np.log(sizes[i] / sizes[i + 1]))
        for i in range(len(sizes) - 1)
        if keep[i] and keep[i + 1]
    ]
    return {"fit": fit, "pairs": pairs}


def mesh_extrapolation(meshes, values):
    """Richardson extrapolation in the element count from the three finest meshes (halving
    sizes): the observed order p and the limit; its error is estimated as the difference
    from the extrapolation of the three coarser meshes (or the last correction)."""
    n, w = np.asarray(meshes, float), np.asarray(values, float)

    def extrapolate(w1, w2, w3):
        p = np.log2((w2 - w1) / (w3 - w2))
        return w3 + (w3 - w2) / (2**p - 1), p

    limit, p = extrapolate(*w[-3:])
    if len(w) > 3:
        error = abs(limit - extrapolate(*w[-4:-1])[0])
    else:
        error = abs(limit - w[-1])
    return {"limit": float(limit), "order": float(p), "error": float(error), "meshes": n.tolist()}


def section_errors(cfg, opensees_rows):
    """(d), rate-independent: every scheme's step and mesh sweeps on the model of (a); the
    relative error of the rest deflection.

    References: in time, at `n_elements`, the linear-acceleration run at the smallest step
    (second order: its error estimated as a third of its difference from the next step's);
    in the mesh, the Richardson extrapolation of "newmark" over the meshes at `mesh_dt`
    (`mesh_extrapolation`). "newmark" reuses the runs of (a). Linear acceleration runs at
    fractions of its stable step (`top_stable_step`) at `n_elements`, and at 0.9 of it on
    the other meshes."""
    n0 = cfg["n_elements"]
    print("\n(d) error against run time, rate-independent Example 1 (the model of (a))")
    print(RUN_HEADER)
    newmark = [r["barrierjax"] for r in opensees_rows if "barrierjax" in r]
    damped = run_sweep("damped-newmark", sweep_cases(cfg), cfg["t_end"], "damped-newmark")
    stable = {n: top_stable_step(matched_model(n))[0] for n in {n0, *cfg["la_meshes"]}}
    la_cases = [(n0, f * stable[n0]) for f in sorted(cfg["la_fractions"])]
    la_cases += [(n, 0.9 * stable[n]) for n in cfg["la_meshes"] if n != n0]
    linear = run_sweep("linear-acceleration", la_cases, cfg["la_t_end"], "linear-accel.")
    twin = next(r for r in linear if (r["n_elements"], r["dt"]) == (n0, 0.9 * stable[n0]))
    report = converged_run(matched_model(n0), "report", twin["dt"], cfg["la_t_end"])
    print_run(report, "report")
    same = report["rest_deflection"] == twin["rest_deflection"]
    print(f"    'report' gives the rest deflection of 'linear-acceleration' on this law: {same}")

    finest = sorted(
        (r for r in linear if r["n_elements"] == n0 and r["converged"]), key=lambda r: r["dt"]
    )
    time_ref = finest[0]["rest_deflection"]
    time_error = abs(finest[1]["rest_deflection"] - time_ref) / 3 if len(finest) > 1 else np.nan
    print(
        f"    reference in time ({n0} elements): linear acceleration at dt {finest[0]['dt']:.3g}"
        f" s: {time_ref:.6f} in, estimated error {time_error:.1e} in"
    )
    mesh_rows = sorted(
        (r for r in newmark if is_mesh_row(cfg, r) and r["converged"]),
        key=lambda r: r["n_elements"],
    )
    mesh_ref = None
    if len(mesh_rows) >= 3:
        mesh_ref = mesh_extrapolation(
            [r["n_elements"] for r in mesh_rows], [r["rest_deflection"] for r in mesh_rows]
        )
        print(
            f"    reference in the mesh: 'newmark' at dt {cfg['mesh_dt']:g} s x 14 / elements over "
            f"{mesh_ref['meshes']} elements, extrapolated: {mesh_ref['limit']:.5f} in "
            f"(observed order {mesh_ref['order']:.2f}, estimated error {mesh_ref['error']:.1e} in)"
        )
    la_mesh = [r for r in linear if r["n_elements"] != n0] + [twin]
    sweeps = {
        "newmark": (newmark, [r for r in newmark if is_mesh_row(cfg, r)]),
        "damped-newmark": (damped, [r for r in damped if is_mesh_row(cfg, r)]),
        "linear-acceleration": (linear, la_mesh),
    }
    ops = [r["opensees"] for r in opensees_rows if "opensees" in r]
    if ops:  # OpenSees's time stepping, for comparison (barrierjax's references)
        sweeps["OpenSees"] = (ops, [r for r in ops if is_mesh_row(cfg, r)])
    out = {
        "time_reference": {"n_elements": n0, "rest_deflection": time_ref, "error": time_error},
        "mesh_reference": mesh_ref,
        "stable_steps": {str(n): s for n, s in stable.items()},
        "report_equals_linear_acceleration": same,
        "report_run": strip(report),
        "sweeps": {},
    }
    print(
        f"    {'scheme':20s} {'sweep':5s} {'sizes (dt or elements)':>36s}  relative errors, order"
    )
    for scheme, (step_rows, mesh_rows) in sweeps.items():
        step_rows = [r for r in step_rows if r["n_elements"] == n0]
        out["sweeps"][scheme] = {"step": sweep_errors(scheme, "step", step_rows, time_ref)}
        if mesh_ref and len(mesh_rows) > 1:
            out["sweeps"][scheme]["mesh"] = sweep_errors(
                scheme, "mesh", mesh_rows, mesh_ref["limit"]
            )
    return out


def sweep_errors(scheme, kind, rows, reference):
    """Relative errors (of the rest deflection) and observed orders of one sweep."""
    key = "dt" if kind == "step" else "n_elements"
    rows = sorted(rows, key=lambda r: r[key])
    values = [r["rest_deflection"] if r["converged"] else np.nan for r in rows]
    sizes = [r[key] if kind == "step" else 1.0 / r[key] for r in rows]
    orders = observed_orders(sizes, values, reference)
    errors = [abs(v / reference - 1) for v in values]
    fit = f"{orders['fit']:.2f}" if orders["fit"] is not None else "-"
    print(
        f"    {scheme:20s} {kind:5s} {' '.join(f'{r[key]:.3g}' for r in rows):>36s}  "
        + " ".join(f"{e:.1e}" for e in errors)
        + f", order {fit}"
    )
    return {
        "sizes": [r[key] for r in rows],
        "errors": errors,
        "seconds": [r["seconds"] for r in rows],
        "rows": [strip(r) for r in rows],
        "orders": orders,
    }


def strip(row) -> dict:
    return {k: v for k, v in row.items() if k != "history"}


def section_rate_dependent(cfg):
    """(d), rate-dependent: barrierjax's Example 1 (Cowper-Symonds), every scheme under step
    refinement at 14 elements, the tip deflection at `rd_horizon`. Reference: "report" (the
    alpha scheme: second order where the step resolves the relaxation time) at half its
    smallest step, its error estimated as a third of its difference from that step's."""
    horizon = cfg["rd_horizon"]
    stable, _ = top_stable_step(example_model(1))
    linear = [f * stable for f in sorted(cfg["rd_steps"]["linear"])]
    plan = {
        "newmark": sorted(cfg["rd_steps"]["implicit"]),
        "damped-newmark": sorted(cfg["rd_steps"]["implicit"]),
        "linear-acceleration": linear,
        "report": [linear[0] / 2, *linear],
    }
    print(
        f"\n(d) rate-dependent Example 1 (barrierjax's model, Cowper-Symonds), tip deflection "
        f"at {horizon * 1e3:g} ms; stable step of linear acceleration {stable:.3g} s"
    )
    print(RUN_HEADER)
    n0 = EXAMPLES[1]["n_elements"]
    build = lambda n: example_model(1, n_elements=n)
    rows = {
        scheme: run_sweep(scheme, [(n0, dt) for dt in steps], horizon, scheme, build=build)
        for scheme, steps in plan.items()
    }
    reference_row, *rows["report"] = rows["report"]
    reference = reference_row["tip_end"]
    error = abs(reference - rows["report"][0]["tip_end"]) / 3
    print(
        f"    reference: 'report' at dt {reference_row['dt']:.3g} s: {reference:.6f} in, "
        f"estimated error {error:.1e} in"
    )
    out = {"horizon": horizon, "stable_step": stable, "reference": reference, "error": error}
    out["sweeps"] = {}
    for scheme, sub in rows.items():
        values = [r["tip_end"] if r["converged"] else np.nan for r in sub]
        orders = observed_orders([r["dt"] for r in sub], values, reference)
        errors = [abs(v / reference - 1) for v in values]
        out["sweeps"][scheme] = {
            "step": {
                "sizes": [r["dt"] for r in sub],
                "errors": errors,
                "seconds": [r["seconds"] for r in sub],
                "rows": [strip(r) for r in sub],
                "orders": orders,
            }
        }
        fit = f"{orders['fit']:.2f}" if orders["fit"] is not None else "-"
        print(
            f"    {scheme:20s} relative errors {' '.join(f'{e:.1e}' for e in errors)}, order {fit}"
        )
    return out


# --------------------------------------------------------------------------------------
# (e) Stability of the report's scheme.


def energy_runner(model, n_steps):
    """jit of dt -> (all finite, largest kinetic energy / largest work of the load) over
    `n_steps` constant steps of the report's scheme (one Newton iteration, as the tests)."""

    def run(dt):
        h = integrate(model, jnp.full(n_steps, dt), scheme="report", iterations=1, line_search=1)
        masses = jax.vmap(lambda u: mass_matrix(model, u))(h.displacement)
        kinetic = 0.5 * jnp.einsum("ti,tij,tj->t", h.velocity, masses, h.velocity)
        finite = jnp.all(jnp.isfinite(h.displacement)) & jnp.all(jnp.isfinite(kinetic))
        return finite, jnp.max(kinetic) / jnp.max(h.external_work)

    return jax.jit(run)


def bisect_stability(compiled, estimate, bisections):
    """(largest stable step, smallest unstable step, bracketed) by bisection on
    [estimate / 2, 2 estimate] with the compiled `energy_runner`."""

    def stable(dt):
        finite, ratio = compiled(jnp.asarray(dt))
        return bool(finite) and float(ratio) <= 1.05

    lo, hi = 0.5 * estimate, 2.0 * estimate
    if not (stable(lo) and not stable(hi)):
        return lo, hi, False
    for _ in range(bisections):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if stable(mid) else (lo, mid)
    return lo, hi, True


def section_stability(cfg):
    """(e): bisection of the largest stable step of "report" against `stable_step`."""
    print(
        f"\n(e) the report's scheme: largest stable constant step ({cfg['stability_steps']} "
        f"steps; unstable: non-finite, or kinetic energy > 1.05 x the work of the load)"
    )
    print(
        f"    {'example':7s} {'omega_max':>10s} {'stable_step':>11s} {'found':>10s} "
        f"{'found/est.':>10s} {'report steps (s)':>22s} {'/ stable_step':>16s} {'report run':>12s}"
    )
    out = []
    for n in cfg["stability_examples"]:
        model = example_model(n)
        estimate, omega = top_stable_step(model)
        compiled, _ = compile_timed(
            energy_runner(model, cfg["stability_steps"]), jnp.asarray(estimate)
        )
        lo, hi, bracket = bisect_stability(compiled, estimate, cfg["bisections"])
        data = EXAMPLES[n]
        steps = (data["duration"] / data["pulse_steps"], data["dt"])
        report = report_example(n, scheme="report")
        # Blown up: non-finite, or Newton left a residual above the CLI's warning level.
        # Newton stops at its iteration cap, so a diverging run can stay finite (1.5e68 in
        # at the tip after Example 1's 130 report steps).
        finite = bool(np.all(np.isfinite(np.asarray(report.tip_displacement))))
        blown = not finite or float(np.max(np.asarray(report.residual))) > 1e-6
        row = {
            "example": n,
            "omega_max": omega,
            "stable_step": estimate,
            "largest_stable": lo if bracket else None,
            "first_unstable": hi if bracket else None,
            "bracketed": bracket,
            "report_steps": steps,
            "report_steps_over_stable": [s / estimate for s in steps],
            "report_run_blown_up": blown,
        }
        out.append(row)
        found = f"{lo:10.4g} {lo / estimate:10.3f}" if bracket else f"{'no bracket':>21s}"
        print(
            f"    {n:7d} {omega:10.4g} {estimate:11.4g} {found} "
            f"{'/'.join(f'{s:g}' for s in steps):>22s} "
            f"{'/'.join(f'{s / estimate:.0f}' for s in steps):>16s} "
            f"{'blown up' if blown else 'ok':>12s}"
        )
    return out


# --------------------------------------------------------------------------------------
# Plots, targets, main.


def plots(out, data):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    errors = data["errors"]
    panels = [
        ("step", errors["rate_independent"]["sweeps"], "rate-independent, 14 el.: step refinement"),
        ("mesh", errors["rate_independent"]["sweeps"], "rate-independent: mesh refinement"),
        ("step", errors["rate_dependent"]["sweeps"], "rate-dependent, 5 ms: step refinement"),
    ]
    fig, axes = plt.subplots(1, 3, figsize=(16, 4.5))
    for ax, (kind, sweeps, title) in zip(axes, panels):
        for scheme, color in zip((*SCHEMES, "OpenSees"), ("C0", "C1", "C2", "C3", "k")):
            sweep = sweeps.get(scheme, {}).get(kind)
            if not sweep:
                continue
            ax.loglog(sweep["seconds"], sweep["errors"], "o-", color=color, label=scheme)
        ax.set_xlabel("run time (s): one call after compilation; OpenSees's time stepping")
        ax.set_ylabel("relative error")
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=7)
    paths.append(save(fig, out / "beam_fe_error_vs_time.png"))
    speed = data["speed"]
    if "opensees" in speed and "history" in speed["barrierjax"]:
        fig, axes = plt.subplots(1, 2, figsize=(12, 4.2))
        tb, wb = speed["barrierjax"]["history"]
        to, wo = speed["opensees"]["history"]
        axes[0].plot(to, wo, "k-", lw=2.5, alpha=0.4, label="OpenSees")
        axes[0].plot(tb, wb, "C0--", label="barrierjax 'newmark'")
        axes[0].set_xlabel("time (s)")
        axes[0].set_ylabel("tip transverse deflection (in)")
        axes[0].set_title("Example 1, rate-independent, same model and step")
        axes[0].legend()
        n = min(len(tb), len(to))
        axes[1].plot(tb[:n], wb[:n] - wo[:n])
        axes[1].set_xlabel("time (s)")
        axes[1].set_ylabel("barrierjax - OpenSees (in)")
        axes[1].set_title("difference of the tip histories")
        for ax in axes:
            ax.grid(True, alpha=0.3)
        paths.append(save(fig, out / "beam_fe_tip_history.png"))
    return [str(p) for p in paths]


def verdict(ok):
    return "PASS" if ok else "FAIL"


def targets(data):
    out = {}
    both = [r for r in data["opensees"] if "opensees" in r and "barrierjax" in r]
    shared = [r for r in both if r["barrierjax"]["converged"]]
    if shared:
        worst = max(shared, key=lambda r: abs(r["rest_difference"]))
        missing = [[r["n_elements"], r["dt"]] for r in both if not r["barrierjax"]["converged"]]
        converges = {
            name: shrinking(entry["values"])
            for name, entry in data["convergence"].items()
            if name.endswith("rest_deflection")
        }
        limits = {
            name: entry["limit"] for name, entry in data["convergence"].items() if "limit" in entry
        }
        out["agreement"] = {
            "worst_rest_difference": worst["rest_difference"],
            "at": [worst["n_elements"], worst["dt"]],
            "barrierjax_not_converged_at": missing,
            "converges": converges,
            "mesh_limits": limits,
            "verdict": verdict(
                abs(worst["rest_difference"]) <= TARGET_AGREEMENT
                and all(c is not False for c in converges.values())
            ),
        }
    if "ratio" in data["speed"]:
        ratio = data["speed"]["ratio"]
        out["speed"] = {"ratio": ratio, "verdict": verdict(ratio <= TARGET_SPEED_RATIO)}
    ratio = data["vmap"]["ratio"]
    out["vmap"] = {"ratio": ratio, "verdict": verdict(ratio <= TARGET_VMAP_RATIO)}
    return out


def shrinking(values):
    """True if the successive differences of `values` (coarse to fine) shrink, None if there
    are fewer than 3."""
    steps = np.abs(np.diff(values))
    return bool(np.all(steps[1:] < steps[:-1])) if len(values) >= 3 else None


def print_summary(data):
    t = data["targets"]
    quick = data["meta"]["quick"]
    print("\n" + "=" * 78)
    print(
        "SUMMARY"
        + (" (quick run: sizes too small for the verdicts to mean anything)" if quick else "")
    )
    if "agreement" in t:
        a = t["agreement"]
        missing = a["barrierjax_not_converged_at"]
        print(
            f"[{a['verdict']}] rest deflection vs OpenSees (same model and step): worst "
            f"{a['worst_rest_difference']:+.2e} at {a['at'][0]} elements, dt {a['at'][1]:g} "
            f"(target |diff| <= {TARGET_AGREEMENT:.0%})"
            + (f"; barrierjax did not converge at (elements, dt) {missing}" if missing else "")
        )
        for name, ok in a["converges"].items():
            limit = a["mesh_limits"].get(name)
            print(
                f"    {name}: differences shrink under refinement: {ok}"
                + (f"; extrapolated limit {limit:.4f} in" if limit is not None else "")
            )
    else:
        print("[SKIP] agreement with OpenSees: openseespy not available")
    if "speed" in t:
        s, bj = t["speed"], data["speed"]["barrierjax"]
        print(
            f"[{s['verdict']}] one run barrierjax / OpenSees = {s['ratio']:.2f} (target <= "
            f"{TARGET_SPEED_RATIO:g}); barrierjax {bj['seconds']:.2f} s + compile "
            f"{bj['compile_s']:.1f} s, OpenSees {data['speed']['opensees']['seconds']:.2f} s"
        )
    v = t["vmap"]
    print(
        f"[{v['verdict']}] {data['vmap']['variants']} vmapped variants / one run = "
        f"{v['ratio']:.1f} (target <= {TARGET_VMAP_RATIO:g})"
    )
    for label, part in data["errors"].items():
        for scheme, sweeps in part["sweeps"].items():
            text = ", ".join(
                f"{kind} order {s['orders']['fit']:.2f}"
                if s["orders"]["fit"] is not None
                else f"{kind} order -"
                for kind, s in sweeps.items()
            )
            print(f"[measured] {label} {scheme}: {text}")
    for row in data["stability"]:
        found = f"{row['largest_stable']:.4g} s" if row["bracketed"] else "not bracketed"
        print(
            f"[measured] Example {row['example']}, report scheme: largest stable step {found}, "
            f"stable_step {row['stable_step']:.4g} s; the report's steps are "
            + " and ".join(f"{r:.0f}x" for r in row["report_steps_over_stable"])
            + " that"
        )


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    args.out.mkdir(parents=True, exist_ok=True)
    load_start, sources_start = os.getloadavg(), source_fingerprint()
    start = time.perf_counter()
    print(
        f"beam_fe benchmark ({'quick' if args.quick else 'full'}), jax {jax.__version__} on "
        f"{jax.devices()[0].platform}, {os.cpu_count()} CPU cores, load average "
        f"{load_start[0]:.1f}, OPENBLAS_NUM_THREADS={os.environ['OPENBLAS_NUM_THREADS']}"
    )
    have_opensees = opensees_available()
    data = {"opensees": section_opensees(cfg, have_opensees)}
    data["convergence"] = convergence(cfg, data["opensees"])
    data["speed"] = section_speed(cfg, data["opensees"])
    data["vmap"] = section_vmap(cfg)
    data["errors"] = {
        "rate_independent": section_errors(cfg, data["opensees"]),
        "rate_dependent": section_rate_dependent(cfg),
    }
    data["stability"] = section_stability(cfg)
    data["meta"] = {
        **meta(args, load_start, sources_start, sources_changed(sources_start)),
        "config": cfg,
        "newton_ladder": NEWTON_LADDER,
        "elapsed_s": time.perf_counter() - start,
        "openblas_num_threads": os.environ["OPENBLAS_NUM_THREADS"],
    }
    data["targets"] = targets(data)
    if not args.no_plots:
        data["plots"] = plots(args.out, data)
    print_summary(data)
    (args.out / "beam_fe.json").write_text(
        json.dumps(without_histories(data), indent=1, default=float)
    )
    print(f"wrote {args.out / 'beam_fe.json'} ({data['meta']['elapsed_s'] / 60:.1f} min)")


def without_histories(value):
    """The results without the tip histories (arrays), for the JSON file."""
    if isinstance(value, dict):
        return {k: without_histories(v) for k, v in value.items() if k != "history"}
    if isinstance(value, (list, tuple)):
        return [without_histories(v) for v in value]
    return value


if __name__ == "__main__":
    main()
