"""Newton's method whose result carries the implicit function theorem's derivative, for the
implicit equilibrium of each step of the beam (report 4.2 (iii)) and the final hinge
distance of the normal impact (the root of (3.2.17)).

The iterations run on the parameters with their derivatives stopped, in a while loop that
ends when every member (under `vmap`) has converged or the budget is spent: no derivative
ever unrolls them. One more Newton step from the converged point x*, with the residual on
the live parameters and the Jacobian held constant,

    x = x* - J(x*)^-1 r(x*, theta),

then carries dx/dtheta = -J^-1 dr/dtheta, the implicit function theorem's (exact at the
root, first derivatives only), at the cost of one residual and one linear solve.
"""

from collections.abc import Callable
from typing import Any

import jax
import jax.numpy as jnp


def newton(
    linearise: Callable[[Any, Any], tuple[Any, Any, Any]],
    residual: Callable[[Any, Any], Any],
    solve: Callable[[Any, Any], Any],
    x0,
    params,
    *,
    iterations: int,
    halvings: int = 0,
):
    """The root x of `residual(x, params) = 0` from `x0`, differentiable in `params`.

    - `linearise(x, params)`: (J, r, converged), the Jacobian and residual at x and whether
      x is converged (a boolean scalar; the iterations stop once it holds);
    - `residual(x, params)`: r alone, for the line search and the final step on the live
      parameters;
    - `solve(J, r)`: the Newton step J^-1 r;
    - `iterations`: the budget of iterations before the final step (0: the final step
      alone, from `x0`, a single linearised solve);
    - `halvings`: a backtracking line search (a nearly singular Jacobian, as at a plastic
      hinge, makes full Newton steps diverge): the full step first, halved while it does
      not lower the residual's sum of squares, at most `halvings` times. Where the full
      step is good, as in most iterations, it costs one residual.
    """
    frozen = jax.lax.stop_gradient(params)

    def line_search(x, r, step):
        current = jnp.sum(r**2)
        merit = lambda length: jnp.sum(residual(x - length * step, frozen) ** 2)

        def halve(search):
            length, _, count = search
            return 0.5 * length, merit(0.5 * length), count + 1

        # (A NaN merit is not below the current one: it is halved too.)
        no_better = lambda search: ~(search[1] < current) & (search[2] < halvings)
        one = jnp.ones((), r.dtype)
        length, _, _ = jax.lax.while_loop(no_better, halve, (one, merit(one), 0))
        return length * step

    def iterate(carry):
        x, _, count = carry
        J, r, converged = linearise(x, frozen)
        step = solve(J, r)
        if halvings > 0:
            step = line_search(x, r, step)
        return jnp.where(converged, x, x - step), converged, count + 1

    x_star, _, _ = jax.lax.while_loop(
        lambda carry: ~carry[1] & (carry[2] < iterations),
        iterate,
        (jax.lax.stop_gradient(x0), jnp.asarray(False), 0),
    )
    J, _, _ = linearise(x_star, frozen)
    return x_star - solve(jax.lax.stop_gradient(J), residual(x_star, params))
