"""Sizing report: `optimize` solves a `SizingProblem` by gradients (`solve`), checks the
result against the brute-force grid (`grid_search`) and returns a `DesignReport`
(`summary()`, `as_dict()`); `optimize_default()` does so for the default problem
(`SizingProblem()`, see `barrierjax.design.problem`).
"""

import dataclasses
import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .grid import grid_search
from .model import responses
from .optimizer import solve
from .problem import SizingProblem


class DesignReport(eqx.Module):
    """The optimum by gradients next to the brute-force grid's best, in SI units.

    Design: `t`, `d` (m), `q0` (N/m), derived `plastic_moment` M0 (N m) and
    `mass_per_length` m (kg/m), `compact` (AISC flexure limits met). Performance:
    `objective` (mean crush, m), per-case `damages` and `deflections` (m),
    `max_deflection`, `deflection_limit`, `constraint` = max_deflection - limit (m, <= 0
    feasible), `feasible`. Grid: `grid_t`, `grid_d`, `grid_q0`, `grid_objective`,
    `grid_constraint` (refined grid), `coarse_grid_objective`, `grid_evaluations`;
    `relative_difference` = objective / grid_objective - 1 (negative: gradients found a
    better design than the grid), `relative_difference_coarse` likewise against the
    coarse grid. Solver: `iterations` (outer augmented-Lagrangian iterations of the
    winning start), `adam_steps`, `converged`, `n_starts`, `starts_near_best` (starts
    within 1 % of the best). Wall times (s): `time_optimize_s`, `time_grid_s` (first call,
    including compilation unless already cached in this process) and
    `time_optimize_warm_s`, `time_grid_warm_s` (the same call again, compiled).
    """

    t: float
    d: float
    q0: float
    plastic_moment: float
    mass_per_length: float
    compact: bool
    objective: float
    damages: tuple[float, ...]
    deflections: tuple[float, ...]
    case_names: tuple[str, ...]
    max_deflection: float
    deflection_limit: float
    constraint: float
    feasible: bool
    grid_t: float
    grid_d: float
    grid_q0: float
    grid_objective: float
    grid_constraint: float
    coarse_grid_objective: float
    grid_evaluations: int
    relative_difference: float
    relative_difference_coarse: float
    iterations: int
    adam_steps: int
    converged: bool
    n_starts: int
    starts_near_best: int
    time_optimize_s: float
    time_optimize_warm_s: float
    time_grid_s: float
    time_grid_warm_s: float

    def as_dict(self) -> dict:
        """Plain JSON-serialisable values: floats, ints, bools, strings and lists of them;
        a non-finite float (e.g. the grid's objective when no grid point is feasible)
        becomes None."""

        return {
            field.name: json_plain(getattr(self, field.name)) for field in dataclasses.fields(self)
        }

    def summary(self) -> str:
        """Readable multi-line text, in engineering units."""
        status = "feasible" if self.feasible else "INFEASIBLE"
        section = "compact" if self.compact else "NOT compact"
        rd = self.relative_difference
        verdict = (
            "n/a (no feasible grid point)" if math.isnan(rd) else "yes" if rd <= 0.01 else "NO"
        )
        lines = [
            "Barrier sizing: tube rail on a crushable backing (report 3.2, closed form)",
            "Design (augmented Lagrangian + projected optax.adam, polished):",
            f"  wall thickness t        {1e3 * self.t:12.3f} mm",
            f"  depth d                 {1e3 * self.d:12.3f} mm",
            f"  backing strength q0     {1e-3 * self.q0:12.3f} kN/m",
            f"  plastic moment M0       {1e-3 * self.plastic_moment:12.3f} kN*m",
            f"  rail mass m             {self.mass_per_length:12.3f} kg/m ({section} section)",
            "Performance:",
            f"  objective (mean crush)  {1e3 * self.objective:12.3f} mm of crush",
        ]
        for name, damage, w in zip(self.case_names, self.damages, self.deflections):
            lines.append(f"    {name:<22}{1e3 * damage:12.3f} mm of crush, deflection {w:.4f} m")
        lines += [
            f"  max deflection          {self.max_deflection:12.6f} m"
            f" (limit {self.deflection_limit:g} m)",
            f"  constraint W - W_max    {self.constraint:12.3e} m ({status})",
            f"Grid search ({self.grid_evaluations} designs: a uniform grid, then zoomed in):",
            f"  best design             t {1e3 * self.grid_t:.3f} mm, d {1e3 * self.grid_d:.3f} mm,"
            f" q0 {1e-3 * self.grid_q0:.3f} kN/m",
            f"  best objective          {1e3 * self.grid_objective:12.3f} mm of crush"
            f" (constraint {self.grid_constraint:.3e} m)",
            f"  uniform grid's best     {1e3 * self.coarse_grid_objective:12.3f} mm of crush",
            f"Relative difference, gradient / grid - 1: {100 * self.relative_difference:+.4f} %"
            f" (against the uniform grid {100 * self.relative_difference_coarse:+.4f} %)",
            f"  gradient optimum not worse than the grid's best by more than 1 %: {verdict}",
            f"Solver: {self.iterations} outer iterations, {self.adam_steps} adam steps,"
            f" converged: {self.converged}; {self.starts_near_best} of {self.n_starts} starts"
            " within 1 % of the best",
            f"Wall time: optimize {self.time_optimize_s:.3f} s"
            f" (again, compiled: {self.time_optimize_warm_s:.3f} s),"
            f" grid {self.time_grid_s:.3f} s (again: {self.time_grid_warm_s:.3f} s)",
        ]
        return "\n".join(lines)


def json_plain(value):
    """`value` for JSON: tuples as lists, dicts value by value, a non-finite float as None."""
    if isinstance(value, tuple | list):
        return [json_plain(v) for v in value]
    if isinstance(value, dict):
        return {k: json_plain(v) for k, v in value.items()}
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def timed(fn):
    """(fn()'s result, once JAX has computed it; the wall time it took, s)."""
    start = time.perf_counter()
    out = jax.block_until_ready(fn())
    return out, time.perf_counter() - start


def optimize(
    problem: SizingProblem,
    *,
    grid_n: int = 40,
    grid_refine: int = 8,
    **solve_options,
) -> DesignReport:
    """Solve `problem` by gradients (`solve`), check it against `grid_search`, and report."""
    inner_steps = solve_options.get("inner_steps", 100)
    run_solve = lambda: solve(problem, **solve_options)
    run_grid = lambda: grid_search(problem, grid_n, refine=grid_refine)
    sol, time_solve = timed(run_solve)
    grid, time_grid = timed(run_grid)
    # The same calls again, compiled: the run times without compilation.
    _, warm_solve = timed(run_solve)
    _, warm_grid = timed(run_grid)

    k = int(sol.best)
    x = np.asarray(sol.x[k])
    t, d, q0 = (float(v) for v in x)
    damages, deflections = (np.asarray(a) for a in responses(problem, jnp.asarray(x)))
    flange, web = problem.section.compactness(t, d)
    f_best = float(sol.objective[k])
    good = np.asarray(sol.feasible) & (np.asarray(sol.objective) <= 1.01 * f_best)
    grid_f = float(grid.objective)
    coarse_f = float(grid.coarse_objective)
    relative = lambda reference: f_best / reference - 1.0 if math.isfinite(reference) else math.nan
    return DesignReport(
        t=t,
        d=d,
        q0=q0,
        plastic_moment=float(problem.section.plastic_moment(t, d)),
        mass_per_length=float(problem.section.mass_per_length(t, d)),
        compact=bool(float(flange) <= 1.0 and float(web) <= 1.0),
        objective=f_best,
        damages=tuple(float(v) for v in damages),
        deflections=tuple(float(v) for v in deflections),
        case_names=problem.cases.names,
        max_deflection=float(np.max(deflections)),
        deflection_limit=float(problem.deflection_limit),
        constraint=float(sol.constraint[k]),
        feasible=bool(sol.feasible[k]),
        grid_t=float(grid.x[0]),
        grid_d=float(grid.x[1]),
        grid_q0=float(grid.x[2]),
        grid_objective=grid_f,
        grid_constraint=float(grid.constraint),
        coarse_grid_objective=coarse_f,
        grid_evaluations=int(grid.evaluations),
        relative_difference=relative(grid_f),
        relative_difference_coarse=relative(coarse_f),
        iterations=int(sol.outer[k]),
        adam_steps=int(sol.outer[k]) * int(inner_steps),
        converged=bool(sol.converged[k]),
        n_starts=int(sol.x.shape[0]),
        starts_near_best=int(np.sum(good)),
        time_optimize_s=time_solve,
        time_optimize_warm_s=warm_solve,
        time_grid_s=time_grid,
        time_grid_warm_s=warm_grid,
    )


def optimize_default() -> DesignReport:
    """`optimize(SizingProblem())`: the default problem (see `barrierjax.design.problem`)."""
    return optimize(SizingProblem())
