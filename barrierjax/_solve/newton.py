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
    merit: Callable[[Any, Any], Any] | None = None,
    step_lengths=(1.0,),
):
    """The root x of `residual(x, params) = 0` from `x0`, differentiable in `params`.

    - `linearise(x, params)`: (J, r, converged), the Jacobian and residual at x and whether
      x is converged (a boolean scalar; the iterations stop once it holds);
    - `residual(x, params)`: r alone, for the final step on the live parameters;
    - `solve(J, r)`: the Newton step J^-1 r;
    - `iterations`: the budget of iterations before the final step (0: the final step
      alone, from `x0`, a single linearised solve);
    - `merit`, `step_lengths`: with more than one length, a line search takes the step
      length of least `merit(x - length * step, params)` among `step_lengths` (a nearly
      singular Jacobian, as at a plastic hinge, makes full Newton steps diverge).
    """
    frozen = jax.lax.stop_gradient(params)
    lengths = jnp.asarray(step_lengths)

    def iterate(carry):
        x, _, count = carry
        J, r, converged = linearise(x, frozen)
        step = solve(J, r)
        if merit is not None and lengths.size > 1:
            merits = jax.vmap(lambda length: merit(x - length * step, frozen))(lengths)
            merits = jnp.where(jnp.isfinite(merits), merits, jnp.inf)
            step = lengths[jnp.argmin(merits)] * step
        return jnp.where(converged, x, x - step), converged, count + 1

    x_star, _, _ = jax.lax.while_loop(
        lambda carry: ~carry[1] & (carry[2] < iterations),
        iterate,
        (jax.lax.stop_gradient(x0), jnp.asarray(False), 0),
    )
    J, _, _ = linearise(x_star, frozen)
    return x_star - solve(jax.lax.stop_gradient(J), residual(x_star, params))
