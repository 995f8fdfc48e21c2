"""Benchmark of the beam finite element of report 4.2 (`barrierjax.beam`) on Example 1 of 4.3,
side by side with OpenSees (`_opensees_cantilever.py`; skipped, saying so, without openseespy).

    python benchmarks/beam_fe.py [--quick] [--out DIR] [--seed N] [--no-plots]

Tables: (1) the rate-independent Example 1 built as OpenSees builds it (20 midpoint layers,
3 Lobatto points per element, co-rotational strains without the shallow-arch term,
consistent mass, tip mass, Newmark's average acceleration at the same constant step) in
both codes: the tip's rest deflection (at the first zero of its velocity after the pulse)
and permanent deflection (the middle of the first elastic swing after it), from the
histories by one helper (`rest_and_permanent`) for both, the largest difference of the tip
histories, and each code's run time (best of 3 runs: barrierjax after compilation,
OpenSees's time stepping, model building apart; on a shared 2-core machine XLA's timings
drift by some 30 % over minutes, OpenSees's single thread's by 5 %). Left different: barrierjax's
consistent mass carries the rotary inertia rho I, and it averages the rectangular pulse over
each step where OpenSees scales it to an exact trapezoidal impulse (an O(dt) difference).
(2) Error against run time of each time-stepping scheme under step refinement on that model
(reference: linear acceleration at its smallest step). (3) Throughput: variants of the
rate-dependent Example 1 (yield stress, Cowper-Symonds D, tip mass) in one `jax.vmap`
against one run. (4) The first call in a fresh process: a run and its gradient with respect
to the yield stress. Writes `beam_fe.json` and `beam_fe_error_vs_time.png` to `--out`.
"""

import os

# jaxlib's LAPACK calls go to scipy's OpenBLAS, whose threads fight XLA's on a few cores.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import jax

jax.config.update("jax_enable_x64", True)

import dataclasses
import math

import _opensees_cantilever as opensees
import jax.numpy as jnp
import numpy as np
import scipy.linalg
from harness import argument_parser, first_calls, pyplot, save_figure, steady, table, write_json

from barrierjax.beam.examples import EXAMPLES, example_model
from barrierjax.beam.integrate import SCHEME_PARAMETERS, integrate, stable_step
from barrierjax.beam.layered import rectangular_section
from barrierjax.beam.model import cantilever, linear_matrices
from barrierjax.materials.plasticity import RateIndependentPlasticity

P = opensees.EXAMPLE_1
CONVERGED = 1e-5  # largest relative Newton residual of a converged step (`BeamHistory.residual`)
NEWTON_LADDER = ((2, 1), (4, 1), (8, 4), (16, 8), (32, 8))  # (iterations, line_search)
HELD_CHORD = 0.1  # `integrate(..., chord=...)` of the held-tangent runs


def config(quick: bool) -> dict:
    if quick:
        return {"n_elements": 4, "t_end": 0.12, "steps": (2.5e-5,), "meshes": (), "la_fractions": (0.9,), "la_t_end": 0.11,
                    "vmap_grid": 2, "vmap_steps": 4, "first_steps": 4}
    return {"n_elements": 14, "t_end": 0.18, "steps": (2e-4, 1e-4, 5e-5, 2.5e-5), "meshes": (7, 28), "mesh_dt": 1e-4,
                "la_fractions": (0.9, 0.45, 0.225), "la_t_end": 0.11, "vmap_grid": 4, "vmap_steps": 50, "first_steps": 50}


def rest_and_permanent(times, transverse, velocity, pulse_end) -> dict:
    """The tip's first rest after the pulse and its permanent deflection, from a history: the
    first step after `pulse_end` whose transverse velocity is <= 0, the rest time and
    deflection interpolated linearly between it and the step before; the permanent deflection
    is the middle of the first elastic swing after the rest, (largest deflection from the rest
    on + smallest before the velocity turns positive again) / 2. NaN where the history ends."""
    times, transverse, velocity = (np.asarray(a, dtype=float) for a in (times, transverse, velocity))
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
        out["permanent_deflection"] = float((np.max(transverse[k - 1 :]) + np.min(transverse[k : back[0]])) / 2)
    return out


def matched_model(n_elements):
    """Example 1 as `_opensees_cantilever` builds it (see the module docstring)."""
    law = RateIndependentPlasticity(P["E"], P["sigma0"])
    section = rectangular_section(P["width"], P["height"], law, points=20, rule="midpoint")
    model = cantilever(P["length"], n_elements, section, P["rho"], tip_mass=P["tip_mass"], tip_impulse=P["impulse"],
                       duration=P["pulse_duration"])
    return dataclasses.replace(model, shallow=False)


def top_stable_step(model, scheme="linear-acceleration"):
    """`stable_step` of `scheme` from the top eigenfrequency of the linear (K, M) on the free dofs."""
    K, M = (np.asarray(a) for a in linear_matrices(model))
    free = model.free()
    omega_max = float(np.sqrt(scipy.linalg.eigh(K[np.ix_(free, free)], M[np.ix_(free, free)], eigvals_only=True)[-1]))
    beta, gamma, _ = SCHEME_PARAMETERS[scheme]
    return float(stable_step(omega_max, beta, gamma))


def converged_run(model, scheme, dt, t_end, start=0, chord=0.0) -> dict:
    """Run `model` in equal steps of at most `dt` to `t_end` with the first `NEWTON_LADDER`
    setting (from index `start`) under which every step converges; the tip's deflections and
    the run time after compilation. `chord` as in `integrate` (> 0: the held tangent)."""
    dts = jnp.full(math.ceil(t_end / dt - 1e-9), t_end / math.ceil(t_end / dt - 1e-9))
    row = {}
    for rung in range(start, len(NEWTON_LADDER)):
        iterations, line_search = NEWTON_LADDER[rung]

        def run(dts, iterations=iterations, line_search=line_search):
            options = {"iterations": iterations, "line_search": line_search, "chord": chord}
            h = integrate(model, dts, scheme=scheme, **options)
            finite = jnp.all(jnp.isfinite(h.displacement))
            return h.times, h.displacement[:, -2], h.velocity[:, -2], jnp.max(h.residual), finite

        run = jax.jit(run)
        times, w, v, residual, finite = run(dts)
        row = dict(scheme=scheme, n_elements=len(model.connectivity), dt=float(t_end / dts.shape[0]),
                   steps=int(dts.shape[0]), rung=rung, iterations=iterations, line_search=line_search,
                   converged=bool(finite) and float(residual) < CONVERGED, max_residual=float(residual),
                   seconds=steady(run, dts, reps=3, slow=math.inf), **rest_and_permanent(times, w, v, P["pulse_duration"]))
        if row["converged"]:
            row["history"] = (np.asarray(times), np.asarray(w))
            return row
    return row


def opensees_available():
    try:
        opensees.import_opensees()
    except ImportError as error:
        return f"OpenSees skipped: {error}"
    return None


def opensees_run(n_elements, dt, t_end, repeats=1) -> dict:
    runs = [opensees.run_example_1(dt, t_end, n_elements) for _ in range(repeats)]
    r = runs[0]
    return dict(converged=bool(r.converged), seconds=min(x.analysis_seconds for x in runs),
                history=(r.times, r.transverse),
                **rest_and_permanent(r.times, r.transverse, r.transverse_velocity, P["pulse_duration"]))


def cases(cfg):
    """(elements, dt): the step sweep at `n_elements`, then the meshes at `mesh_dt` x
    `n_elements` / elements (the step in proportion to the element's length)."""
    out = [(cfg["n_elements"], dt) for dt in sorted(cfg["steps"])]
    return out + [(n, cfg["mesh_dt"] * cfg["n_elements"] / n) for n in cfg["meshes"]]


def against_opensees(cfg, skipped) -> list:
    rows, rung = [], 0
    for n, dt in cases(cfg):
        bj = converged_run(matched_model(n), "newmark", dt, cfg["t_end"], start=rung if n == cfg["n_elements"] else 0)
        rung = bj["rung"] if n == cfg["n_elements"] and bj["converged"] else rung
        held = converged_run(matched_model(n), "newmark", dt, cfg["t_end"], chord=HELD_CHORD)
        row = {"n_elements": n, "dt": dt, "barrierjax": bj, "bj_rest": bj["rest_deflection"],
                   "bj_permanent": bj["permanent_deflection"], "bj_s": bj["seconds"], "newton": f"{bj['iterations']}/{bj['line_search']}",
                   "held": held, "held_rest": held["rest_deflection"], "held_s": held["seconds"],
                   "held_newton": f"{held['iterations']}/{held['line_search']}"}
        if not skipped:
            ops = opensees_run(n, dt, cfg["t_end"], repeats=3)
            (tb, wb), (to, wo) = bj.get("history", ([], [])), ops["history"]
            m = min(len(tb), len(to))
            row.update(opensees=ops, ops_rest=ops["rest_deflection"], ops_permanent=ops["permanent_deflection"],
                       ops_s=ops["seconds"], rest_difference=bj["rest_deflection"] / ops["rest_deflection"] - 1,
                       held_rest_difference=held["rest_deflection"] / ops["rest_deflection"] - 1,
                       speed_vs_opensees=ops["seconds"] / bj["seconds"], held_speed_vs_opensees=ops["seconds"] / held["seconds"],
                       history_difference=float(np.max(np.abs(wb[:m] - wo[:m])) / np.max(np.abs(wo[:m]))) if m else None)
        rows.append(row)
    return rows


def error_vs_time(cfg, newmark_rows) -> dict:
    """Each scheme under step refinement at `n_elements` on the matched model; the relative
    error of the rest deflection against linear acceleration at its smallest step ("report"
    is linear acceleration on a rate-independent law: one run checks that)."""
    n0 = cfg["n_elements"]
    model, stable = matched_model(n0), top_stable_step(matched_model(n0))
    runs = [r["barrierjax"] for r in newmark_rows if r["n_elements"] == n0]
    runs += [converged_run(model, "damped-newmark", dt, cfg["t_end"]) for dt in sorted(cfg["steps"])]
    linear = [converged_run(model, "linear-acceleration", f * stable, cfg["la_t_end"]) for f in sorted(cfg["la_fractions"])]
    report = converged_run(model, "report", linear[-1]["dt"], cfg["la_t_end"])
    reference = linear[0]["rest_deflection"]
    rows = [dict(r, error=abs(r["rest_deflection"] / reference - 1)) for r in runs + linear[1:] + [report]]
    return {"rows": [{k: v for k, v in r.items() if k != "history"} for r in rows], "stable_step": stable,
                "reference": {"dt": linear[0]["dt"], "rest_deflection": reference,
                               "error": abs(linear[1]["rest_deflection"] - reference) / 3 if len(linear) > 1 else None},
                "report_equals_linear_acceleration": report["rest_deflection"] == linear[-1]["rest_deflection"]}


def vmap_variants(cfg) -> dict:
    """A k x k x k grid of yield stress, D and tip mass around the rate-dependent Example 1,
    'damped-newmark' at the library's sub-step, as one vmap against one run."""
    k, data = cfg["vmap_grid"], EXAMPLES[1]
    axes = (data["sigma0"] * np.linspace(0.8, 1.2, k), np.geomspace(10.0, 160.0, k),
            data["tip_mass"] * np.linspace(0.75, 1.25, k))
    grid = [jnp.asarray(a.ravel()) for a in np.meshgrid(*axes, indexing="ij")]
    dts = jnp.full(cfg["vmap_steps"], data["dt"] / math.ceil(data["dt"] / data["max_substep"]))

    def run(s0, d, m):
        h = integrate(example_model(1, sigma0=s0, D=d, tip_mass=m), dts, scheme="damped-newmark")
        return h.displacement[-1, -2], jnp.max(h.residual)

    single, batch = jax.jit(run), jax.jit(jax.vmap(run))
    one = tuple(g[-1] for g in grid)
    single_s, batch_s = steady(single, *one, reps=3), steady(batch, *grid, reps=2)
    tips, residuals = batch(*grid)
    return {"variants": len(grid[0]), "steps": cfg["vmap_steps"], "single_s": single_s, "batch_s": batch_s,
                "ratio": batch_s / single_s, "per_variant_of_single": batch_s / single_s / len(grid[0]),
                "max_residual": float(jnp.max(residuals)),
                "vmap_vs_single": float(abs(tips[-1] - single(*one)[0]) / abs(single(*one)[0]))}


def first_call_cases(steps) -> dict:
    setup = f"""
        import math, jax, jax.numpy as jnp
        from barrierjax.beam.examples import EXAMPLES, example_model
        from barrierjax.beam.integrate import integrate
        data = EXAMPLES[1]
        dts = jnp.full({steps}, data["dt"] / math.ceil(data["dt"] / data["max_substep"]))
        tip = lambda s0: integrate(example_model(1, sigma0=s0), dts, scheme="damped-newmark").displacement[-1, -2]
        s0 = jnp.asarray(float(data["sigma0"]))
    """
    return {f"Example 1, {steps} steps": (setup, "tip(s0)"),
            f"gradient w.r.t. sigma0, {steps} steps": (setup, "jax.grad(tip)(s0)")}


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    cfg = config(args.quick)
    skipped = opensees_available()
    print(f"beam_fe: Example 1 of report 4.3; {skipped or 'OpenSees ' + opensees.__name__ + ' available'}")
    data = {"opensees": against_opensees(cfg, skipped), "opensees_skipped": skipped}
    table(f"Rate-independent Example 1, barrierjax 'newmark' and OpenSees, same model and step, to {cfg['t_end']} s"
          + (f" ({skipped})" if skipped else ""), data["opensees"],
          [("elements", "n_elements", "d"), ("dt s", "dt", ".3g"), ("Newton", "newton", "s"),
           ("barrierjax rest (in)", "bj_rest", ".5f"), ("perm. (in)", "bj_permanent", ".5f"), ("run s", "bj_s", ".2f"),
           ("OpenSees rest (in)", "ops_rest", ".5f"), ("perm. (in)", "ops_permanent", ".5f"), ("run s", "ops_s", ".2f"),
           ("rest diff.", "rest_difference", "+.1e"), ("history diff.", "history_difference", ".1e")])
    table("SUMMARY: the same runs with Newton's tangent held from step to step (chord "
          f"{HELD_CHORD}), and each barrierjax run's speed against OpenSees's", data["opensees"],
          [("elements", "n_elements", "d"), ("dt s", "dt", ".3g"), ("Newton", "held_newton", "s"),
           ("held rest (in)", "held_rest", ".5f"), ("rest diff.", "held_rest_difference", "+.1e"),
           ("held run s", "held_s", ".2f"), ("OpenSees / held", "held_speed_vs_opensees", ".2f"),
           ("OpenSees / Newton", "speed_vs_opensees", ".2f")])
    data["errors"] = error_vs_time(cfg, data["opensees"])
    table(f"Error against run time, {cfg['n_elements']} elements: rest deflection against linear acceleration at "
          f"dt {data['errors']['reference']['dt']:.3g} s; report == linear acceleration on this law: "
          f"{data['errors']['report_equals_linear_acceleration']}", data["errors"]["rows"],
          [("scheme", "scheme", "s"), ("dt s", "dt", ".3g"), ("rest (in)", "rest_deflection", ".6f"),
           ("rel. error", "error", ".1e"), ("run s", "seconds", ".2f"), ("converged", "converged", "s")])
    data["vmap"] = vmap_variants(cfg)
    table(f"SUMMARY: {data['vmap']['variants']} variants of the rate-dependent Example 1 in one vmap "
          f"({cfg['vmap_steps']} steps) against one run", [data["vmap"]],
          [("variants", "variants", "d"), ("one run s", "single_s", ".3f"), ("vmapped s", "batch_s", ".3f"),
           ("vmapped / one run", "ratio", ".1f"), ("per variant / one run", "per_variant_of_single", ".2f"),
           ("vmap vs single", "vmap_vs_single", ".1e")])
    data["first_call"] = first_calls(first_call_cases(cfg["first_steps"]))
    for row in data["opensees"]:
        for code in ("barrierjax", "held", "opensees"):
            row.get(code, {}).pop("history", None)
    if not args.no_plots:
        plt = pyplot()
        fig, ax = plt.subplots(figsize=(7, 5))
        for scheme in dict.fromkeys(r["scheme"] for r in data["errors"]["rows"]):
            sub = [r for r in data["errors"]["rows"] if r["scheme"] == scheme and r["converged"]]
            ax.loglog([r["seconds"] for r in sub], [max(r["error"], 1e-16) for r in sub], "o-", label=scheme)
        ax.set(xlabel="run time (s)", ylabel="relative error of the rest deflection",
               title="beam element, rate-independent Example 1: step refinement")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        save_figure(fig, args, "beam_fe_error_vs_time")
    write_json(args, "beam_fe", data, config=cfg, newton_ladder=NEWTON_LADDER,
               openblas_num_threads=os.environ["OPENBLAS_NUM_THREADS"])


if __name__ == "__main__":
    main()
