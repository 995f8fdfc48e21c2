"""A guardrail under a static lateral point load, raised in increments (a pushover): the
rail's chapter 4 elements, the posts and the anchors of `barrier.py` in equilibrium with
the load at each increment, by Newton's method on the same internal forces that the impact
integrates.

The load acts on the rail's face at `x` (m along the rail), towards the field side (+y),
as the consistent nodal forces of the element under it (the cubic shape functions of
`barrierjax.beam.element`: the nodes' deflections are exact in the elastic,
small-deflection limit; under a load between nodes, `displacement` is the cubic's
interpolation, short of the exact one by the element's own bending under the load: load
at a node where that matters). Each increment's sections and posts are stepped from the last converged state, so
the rail's plastic strains and the posts' yielding follow the loading path. Load control:
past the largest load the guardrail carries (the posts near the load yielded or failed
and the rail's hinges formed), Newton finds no equilibrium and the call raises, naming the
increment. Concrete inputs only (it is a design check, not a model to vmap).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import positive
from ..beam.element import hermite_shape
from ..beam.model import init_sections, internal_forces
from .barrier import Guardrail, anchor_forces, post_forces


class StaticPushover(eqx.Module):
    """The guardrail at each load increment (SI)."""

    load: jnp.ndarray  # (n,) N
    displacement: jnp.ndarray  # (n,) m, the rail's lateral displacement under the load
    rail_deflection: jnp.ndarray  # (n, n_nodes) lateral displacement of every node
    post_force: jnp.ndarray  # (n, n_posts) lateral
    failed_posts: jnp.ndarray  # (n_posts,) bool, at the last increment


def static_pushover(
    g: Guardrail, force, x, *, increments: int = 10, time_per_increment=1.0, rtol=1e-10
) -> StaticPushover:
    """The guardrail `g` under a lateral point load raised in `increments` equal steps to
    `force` (N) at `x` (m along the rail, strictly inside it), each increment taken as
    `time_per_increment` seconds (what a rate-dependent law sees). Newton's iterations
    (optimistix) stop at `rtol` of the displacement; a load the guardrail cannot carry
    raises."""
    force = positive("force", force)
    length = float(np.asarray(g.rail.coords)[-1, 0])
    if not 0 < float(x) < length:
        raise ValueError(f"x must lie on the rail, in (0, {length:g}) m; got {x!r}")
    if int(increments) != increments or increments < 1:
        raise ValueError(f"increments must be a positive integer; got {increments!r}")
    dt = positive("time_per_increment", time_per_increment)
    pattern, dofs, shape = _point_load(g, float(x))
    factors = jnp.arange(1, int(increments) + 1, dtype=force.dtype) / increments
    result, converged = _pushover(g, force, pattern, dofs, shape, factors, dt, rtol)
    failed = np.flatnonzero(~np.asarray(converged))
    if failed.size:
        load = float(force) * float(factors[failed[0]])
        raise ValueError(
            f"force {float(force):g} N at x = {float(x):g} m is more than the guardrail "
            f"carries: Newton's iterations found no equilibrium at increment {failed[0] + 1} "
            f"({load:g} N; load control stops at the peak of the load-deflection curve)"
        )
    return result


def _point_load(g: Guardrail, x):
    """The consistent nodal forces of a unit lateral load at x (3 n_nodes,), and the dofs
    and shape functions that read the rail's lateral displacement there."""
    coords = np.asarray(g.rail.coords)[:, 0]
    dx = coords[1] - coords[0]
    element = min(int(x // dx), len(coords) - 2)
    xi = x / dx - element
    dofs = 3 * element + np.array([1, 2, 4, 5])
    shape, _ = hermite_shape(jnp.asarray(xi, g.rail.coords.dtype), jnp.asarray(dx))
    pattern = jnp.zeros(3 * len(coords), g.rail.coords.dtype).at[dofs].set(shape)
    return pattern, jnp.asarray(dofs), shape


@eqx.filter_jit
def _pushover(g: Guardrail, force, pattern, dofs, shape, factors, dt, rtol):
    import optimistix as optx  # (on first use: see `_solve.phases`)

    stress, state = init_sections(g.rail)
    n_posts = len(g.post_nodes)
    solver = optx.Newton(rtol=rtol, atol=rtol)

    def increment(carry, factor):
        u_old, stress, state, plastic, failed = carry

        def residual(u, _):
            f_rail, _ = internal_forces(g.rail, u, u_old, stress, state, dt)
            f_post, _, _ = post_forces(g, u, plastic, failed)
            return (f_rail + f_post + anchor_forces(g, u)) / force - factor * pattern

        solution = optx.root_find(residual, solver, u_old, max_steps=64, throw=False)
        u, converged = solution.value, solution.result == optx.RESULTS.successful
        _, (stress, state, *_) = internal_forces(g.rail, u, u_old, stress, state, dt)
        f_post, plastic, failed = post_forces(g, u, plastic, failed)
        out = (
            converged,
            factor * force,
            jnp.dot(shape, u[dofs]),
            u[1::3],
            f_post[3 * np.asarray(g.post_nodes) + 1],
        )
        return (u, stress, state, plastic, failed), out

    u0 = jnp.zeros_like(pattern)
    start = (u0, stress, state, jnp.zeros((n_posts, 2), u0.dtype), jnp.zeros(n_posts, bool))
    final, (converged, *outs) = jax.lax.scan(increment, start, factors)
    return StaticPushover(*outs, final[-1]), jnp.cumprod(converged).astype(bool)
