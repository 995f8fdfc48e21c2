r"""Brute-force reference for the sizing problem.

`grid_minimise` evaluates a formulation's objective and constraints on an n^dim grid,
uniform in the same log coordinates as the optimiser's, in one `jit(vmap)` call, then zooms
in on the best feasible point; see its docstring for why the zoom is needed to make the
comparison meaningful. `grid_search` does so for a `SizingProblem`.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .formulation import Formulation
from .model import sizing_formulation
from .optimizer import BOUNDARY_STEPS, to_boundary
from .problem import SizingProblem


class GridResult(eqx.Module):
    """Best feasible design of a brute-force grid: `x` (t, d, q0), its `objective` and
    `constraint`; `coarse_x`, `coarse_objective`: the same on the first, uniform grid
    (before refinement); `evaluations`: designs evaluated (each over all cases)."""

    x: Array
    objective: Array
    constraint: Array
    coarse_x: Array
    coarse_objective: Array
    evaluations: int = eqx.field(static=True)


@eqx.filter_jit
def _evaluate_box(form: Formulation, low, high, shape: tuple[int, ...]):
    """Objective and largest normalised constraint on the grid of `shape` points
    spanning [low, high] in unit coordinates, in one vmapped call; returns the best
    feasible point (objective inf if none)."""
    axes = [jnp.linspace(low[k], high[k], n) for k, n in enumerate(shape)]
    u = jnp.stack(jnp.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(shape))
    f, c = jax.vmap(form.evaluate)(u)
    masked = jnp.where(c <= 0.0, f, jnp.inf)
    k = jnp.argmin(masked)
    return u[k], masked[k], c[k]


def grid_minimise(
    form: Formulation,
    n: int = 40,
    *,
    refine: int = 8,
    refine_shape: tuple[int, ...] | None = None,
    shrink: float = 0.5,
) -> GridResult:
    """Brute force on a formulation: the best feasible point of an n^dim grid uniform
    in its unit cube, then `refine` zoom levels, each a `refine_shape` grid on a window
    centred on the best point so far (half-width two coarse cells, shrinking by
    `shrink` per level, clipped to the box). Default `refine_shape`: 15 points a
    coordinate, 61 along the stiffening one. The constraint is the largest normalised
    one.

    Why zoom, and why more points along the stiffening coordinate: with a constraint
    active, the best grid point is the one that happens to lie closest to the constraint
    surface, and the objective can change by several per cent per per cent of q0 there
    (the default sizing problem), so a uniform grid's best is several per cent above the
    true optimum whatever its n. The window moves with the best point, so it can follow
    the constraint surface to a corner of the box."""
    dimension = int(form.problem.lower.shape[0])
    if refine_shape is None:
        refine_shape = tuple(61 if k == form.stiffening else 15 for k in range(dimension))
    shape = tuple(int(k) for k in refine_shape)
    if int(n) < 2 or int(refine) < 0 or len(shape) != dimension or min(shape) < 2:
        raise ValueError(
            f"grid_search needs n >= 2, refine >= 0 and {dimension} refine_shape counts >= "
            f"2; got n={n}, refine={refine}, refine_shape={refine_shape}"
        )
    if not 0.0 < shrink < 1.0:
        raise ValueError(f"grid_search needs 0 < shrink < 1; got {shrink}")
    return _zoomed(
        form,
        lambda low, high, first: _evaluate_box(
            form, low, high, (int(n),) * dimension if first else shape
        ),
        first_count=int(n) ** dimension,
        count=int(np.prod(shape)),
        half=2.0 / (int(n) - 1),
        refine=int(refine),
        shrink=shrink,
    )


def _zoomed(form, search, *, first_count, count, half, refine, shrink) -> GridResult:
    """`search(low, high, first)` (the best feasible (u, objective, constraint) of a
    window of the unit cube) on the whole cube, then on `refine` windows centred on the
    best so far, of half-width `half` shrinking by `shrink`; `first_count` and `count`
    designs evaluated by the first search and each later one."""
    dimension = int(form.problem.lower.shape[0])
    dtype = form.problem.lower.dtype
    u, f, c = search(jnp.zeros(dimension, dtype), jnp.ones(dimension, dtype), True)
    coarse_u, coarse_f = u, f
    evaluations = first_count
    for _ in range(refine):
        if not np.isfinite(float(f)):
            break
        low, high = jnp.clip(u - half, 0.0, 1.0), jnp.clip(u + half, 0.0, 1.0)
        u_new, f_new, c_new = search(low, high, False)
        evaluations += count
        if float(f_new) <= float(f):
            u, f, c = u_new, f_new, c_new
        half *= shrink
    return GridResult(
        x=form.design(form.problem, u),
        objective=f,
        constraint=c,
        coarse_x=form.design(form.problem, coarse_u),
        coarse_objective=coarse_f,
        evaluations=evaluations,
    )


def grid_search(
    problem: SizingProblem,
    n: int = 40,
    *,
    refine: int = 8,
    refine_shape: tuple[int, int, int] = (15, 15, 61),
    shrink: float = 0.5,
) -> GridResult:
    """`grid_minimise` of the sizing problem (an n^3 grid uniform in the log coordinates
    of the box, all points x all cases in one jit(vmap) call, then zoomed in); the
    constraint in metres, max_k W_k - W_max."""
    grid = grid_minimise(
        sizing_formulation(problem), n, refine=refine, refine_shape=refine_shape, shrink=shrink
    )
    return eqx.tree_at(lambda g: g.constraint, grid, grid.constraint * problem.deflection_limit)


@eqx.filter_jit
def _boundary_points(form: Formulation, low, high, n: int):
    """The best feasible point found by `to_boundary` from each point of an n^(dim-1)
    grid spanning [low, high] in the other coordinates (the stiffening one at 1/2)."""
    others = [k for k in range(low.shape[0]) if k != form.stiffening]
    axes = [jnp.linspace(low[k], high[k], n) for k in others]
    grid = jnp.stack(jnp.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(others))
    u = jnp.full((grid.shape[0], low.shape[0]), 0.5, low.dtype).at[:, others].set(grid)
    u, f, c = jax.vmap(lambda v: to_boundary(form, v))(u)
    masked = jnp.where(c <= 0.0, f, jnp.inf)
    k = jnp.argmin(masked)
    return u[k], masked[k], c[k]


def grid_along_boundary(
    form: Formulation, n: int = 101, *, refine: int = 4, shrink: float = 0.5
) -> GridResult:
    """Brute force for a problem whose optimum lies on its constraints' boundary, as the
    robust sizing's does (the softer the backing, the less the crush, until a crash test
    deflects too far): the other coordinates on a uniform grid of n points each, and for
    every grid point the boundary along the stiffening one, found by regula falsi
    (`to_boundary`, to rounding); then `refine` zoom levels of n points a coordinate on a
    window centred on the best so far (half-width two cells, shrinking by `shrink`).

    Why not `grid_minimise`: a grid over the stiffening coordinate too is as good as its
    point nearest the constraint surface, where the objective changes steeply; on the
    robust TL-3 sizing, a 40 x 40 grid zoomed 8 times stayed 2 % above the optimum."""
    if int(n) < 2 or int(refine) < 0 or not 0.0 < shrink < 1.0:
        raise ValueError(
            "grid_along_boundary needs n >= 2, refine >= 0 and 0 < shrink < 1; got "
            f"n={n}, refine={refine}, shrink={shrink}"
        )
    lines = int(n) ** (int(form.problem.lower.shape[0]) - 1)
    per_line = 4 + BOUNDARY_STEPS  # the design, three ends of its line, the root search
    return _zoomed(
        form,
        lambda low, high, first: _boundary_points(form, low, high, int(n)),
        first_count=lines * per_line,
        count=lines * per_line,
        half=2.0 / (int(n) - 1),
        refine=int(refine),
        shrink=shrink,
    )
