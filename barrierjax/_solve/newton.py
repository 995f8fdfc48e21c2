"""Newton's method whose result carries the implicit function theorem's derivative, for the
implicit equilibrium of each step of the beam (report 4.2 (iii)) and the final hinge
distance of the normal impact (the root of (3.2.17)).

The iterations run on the parameters with their derivatives stopped, in a while loop that
ends when every member (under `vmap`) has converged or the budget is spent: no derivative
ever unrolls them. One more Newton step from the converged point x*, with the residual on
the live parameters and the Jacobian held constant,

    x = x* - J(x*)^-1 r(x*, theta),

then carries dx/dtheta = -J^-1 dr/dtheta, the implicit function theorem's (exact at the
root, first derivatives only). Its value reuses the last iteration's Jacobian and
residual; the residual on the live parameters is evaluated only for a derivative.
"""

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp


@eqx.filter_custom_jvp
def _implicit_step(x_star, J, r, params, *, residual, solve):
    """x* - J^-1 r, with r = residual(x*, params) already evaluated."""
    return x_star - solve(J, r)


@_implicit_step.def_jvp
def _implicit_step_jvp(primals, tangents, *, residual, solve):
    x_star, J, r, params = primals
    t_params = tangents[3]
    out = _implicit_step(x_star, J, r, params, residual=residual, solve=solve)
    if t_params is None:
        return out, None
    _, dr = eqx.filter_jvp(lambda p: residual(x_star, p), (params,), (t_params,))
    return out, -solve(J, dr)


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
    - `residual(x, params)`: r alone, for the line search and the derivative;
    - `solve(J, r)`: the Newton step J^-1 r;
    - `iterations`: the budget of Newton steps before the final one (0: the final step
      alone, from `x0`, a single linearised solve);
    - `halvings`: a backtracking line search (a nearly singular Jacobian, as at a plastic
      hinge, makes full Newton steps diverge): the full step first, halved while it does
      not lower the residual's sum of squares, at most `halvings` times.

    Each iteration linearises once, at the point it steps to: that residual judges the
    full step, and its Jacobian serves the next step (and the final one) unless the step
    was halved, when the point reached is linearised again.
    """
    frozen = jax.lax.stop_gradient(params)

    def line_search(x, r, step, linearised):
        current = jnp.sum(r**2)

        def halve(search):
            length, _, count = search
            length = 0.5 * length
            return length, jnp.sum(residual(x - length * step, frozen) ** 2), count + 1

        # (A NaN merit is not below the current one: it is halved too.)
        no_better = lambda search: ~(search[1] < current) & (search[2] < halvings)
        one = jnp.ones((), r.dtype)
        length, _, halved = jax.lax.while_loop(
            no_better, halve, (one, jnp.sum(linearised[1] ** 2), 0)
        )
        # The point reached by halving is linearised in a while loop run once or not at
        # all: under `vmap` it costs nothing unless some member halved, where a `cond`
        # would linearise every member twice.
        x_new, J, r_new, converged, _ = jax.lax.while_loop(
            lambda c: c[-1],
            lambda c: (c[0], *linearise(c[0], frozen), False),
            (x - length * step, *linearised, halved > 0),
        )
        return x_new, J, r_new, converged

    def iterate(carry):
        x, J, r, _, count = carry
        step = solve(J, r)
        linearised = linearise(x - step, frozen)
        if halvings > 0:
            return (*line_search(x, r, step, linearised), count + 1)
        return (x - step, *linearised, count + 1)

    x0 = jax.lax.stop_gradient(x0)
    x_star, J, r, _, _ = jax.lax.while_loop(
        lambda carry: ~carry[3] & (carry[4] < iterations),
        iterate,
        (x0, *linearise(x0, frozen), 0),
    )
    return _implicit_step(x_star, J, r, params, residual=residual, solve=solve)
