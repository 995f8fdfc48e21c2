r"""Brute-force reference for the sizing problem.

`grid_search` evaluates the same objective and constraint on an n^3 grid, uniform in the
same log coordinates, in one `jit(vmap)` call, then zooms in on the best feasible point;
see its docstring for why the zoom is needed to make the comparison meaningful.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .model import responses, to_design
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
def _evaluate_box(problem, low, high, shape: tuple[int, int, int]):
    """Objective and constraint on the grid of `shape` points spanning [low, high] in
    unit coordinates, all points x all cases in one vmapped call; returns the best
    feasible point (objective inf if none)."""
    axes = [jnp.linspace(low[k], high[k], shape[k]) for k in range(3)]
    u = jnp.stack(jnp.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    damage, deflection = jax.vmap(lambda v: responses(problem, v))(to_design(problem, u))
    f = jnp.mean(damage, axis=-1)
    c = jnp.max(deflection, axis=-1) - problem.deflection_limit
    masked = jnp.where(c <= 0.0, f, jnp.inf)
    k = jnp.argmin(masked)
    return u[k], masked[k], c[k]


def grid_search(
    problem: SizingProblem,
    n: int = 40,
    *,
    refine: int = 8,
    refine_shape: tuple[int, int, int] = (15, 15, 61),
    shrink: float = 0.5,
) -> GridResult:
    """Brute force: the best feasible point of an n^3 grid uniform in the log
    coordinates of the box (all points x all cases in one jit(vmap) call); then `refine`
    zoom levels, each a `refine_shape` grid on a window centred on the best point so far
    (half-width two coarse cells, shrinking by `shrink` per level, clipped to the box).

    Why zoom, and why more points along q0: with the deflection limit active the best
    grid point is the one that happens to lie closest to the constraint surface, and the
    crush changes by several per cent per per cent of q0 there (default problem), so a
    uniform grid's best is several per cent above the true optimum whatever its n. The
    window moves with the best point, so it can follow the constraint surface to a
    corner of the box."""
    shape = tuple(int(k) for k in refine_shape)
    if int(n) < 2 or int(refine) < 0 or len(shape) != 3 or min(shape) < 2:
        raise ValueError(
            "grid_search needs n >= 2, refine >= 0 and three refine_shape counts >= 2; "
            f"got n={n}, refine={refine}, refine_shape={refine_shape}"
        )
    if not 0.0 < shrink < 1.0:
        raise ValueError(f"grid_search needs 0 < shrink < 1; got {shrink}")
    dtype = problem.lower.dtype
    u, f, c = _evaluate_box(problem, jnp.zeros(3, dtype), jnp.ones(3, dtype), (int(n),) * 3)
    coarse_u, coarse_f = u, f
    evaluations = int(n) ** 3
    half = 2.0 / (int(n) - 1)
    for _ in range(int(refine)):
        if not np.isfinite(float(f)):
            break
        low, high = jnp.clip(u - half, 0.0, 1.0), jnp.clip(u + half, 0.0, 1.0)
        u_new, f_new, c_new = _evaluate_box(problem, low, high, shape)
        evaluations += int(np.prod(shape))
        if float(f_new) <= float(f):
            u, f, c = u_new, f_new, c_new
        half *= shrink
    return GridResult(
        x=to_design(problem, u),
        objective=f,
        constraint=c,
        coarse_x=to_design(problem, coarse_u),
        coarse_objective=coarse_f,
        evaluations=evaluations,
    )
