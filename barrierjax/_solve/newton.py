"""Newton's method whose result carries the implicit function theorem's derivative, for the
implicit equilibrium of each step of the beam (report 4.2 (iii)) and the final hinge
distance of the normal impact (the root of (3.2.17)).

The iterations run on the parameters with their derivatives stopped, in a while loop that
ends when every member (under `vmap`) has converged or the budget is spent: no derivative
ever unrolls them. One more Newton step from the converged point x*, with the residual on
the live parameters and the Jacobian J(x*) held constant,

    x = x* - J(x*)^-1 r(x*, theta),

then carries dx/dtheta = -J^-1 dr/dtheta, the implicit function theorem's (exact at the
root, first derivatives only). The residual on the live parameters is evaluated only for a
derivative.

A factorised Jacobian may be held across iterations, and across calls (`held`): a chord
step with it costs a residual and a back substitution where a Newton step costs a
linearisation and a factorisation. It is kept while its steps shrink the residual fast
(`contraction`) and refreshed at the current point as soon as one does not.
"""

from collections.abc import Callable
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp


@eqx.filter_custom_jvp
def _implicit_step(x_star, factors, r, params, *, residual, refresh, solve):
    """x* - J^-1 r, with r = residual(x*, params) already evaluated and J factorised; its
    derivative takes J afresh at x* (`refresh`, where the factors may be of a J held from
    elsewhere), exact whatever J served the step."""
    return x_star - solve(factors, r)


@_implicit_step.def_jvp
def _implicit_step_jvp(primals, tangents, *, residual, refresh, solve):
    x_star, factors, r, params = primals
    t_params = tangents[3]
    out = _implicit_step(
        x_star, factors, r, params, residual=residual, refresh=refresh, solve=solve
    )
    if t_params is None:
        return out, None
    _, dr = eqx.filter_jvp(lambda p: residual(x_star, p)[0], (params,), (t_params,))
    exact = factors if refresh is None else refresh(x_star, params)
    return out, -solve(exact, dr)


class NewtonRoot(eqx.Module):
    """The root, differentiable in the parameters, and the factorised Jacobian there (to
    hold for a nearby problem, such as the next time step's)."""

    root: Any
    factors: Any


def _once(run, body, operands):
    """`body(operands)` where `run`, else `operands`: a while loop run once or not at all.
    Under `vmap` it costs nothing unless some member runs it, where a `cond` would run the
    body for every member."""
    once = jax.lax.while_loop(lambda c: c[-1], lambda c: (*body(c[:-1]), False), (*operands, run))
    return once[:-1]


def newton(
    linearise: Callable[[Any, Any], tuple[Any, Any, Any]],
    residual: Callable[[Any, Any], tuple[Any, Any]],
    solve: Callable[[Any, Any], Any],
    x0,
    params,
    *,
    iterations: int,
    halvings: int = 0,
    factor: Callable[[Any], Any] = lambda J: J,
    held=None,
    contraction: float = 0.0,
    polish: float = 0.0,
) -> NewtonRoot:
    """The root x of `residual(x, params) = 0` from `x0`, differentiable in `params`.

    - `linearise(x, params)`: (J, r, error), the Jacobian and residual at x and the
      residual's size against the tolerance (a scalar: x is converged, and the iterations
      stop, where it is at most 1);
    - `residual(x, params)`: (r, error) alone, for the steps and the derivative;
    - `factor(J)`: J factorised (default: J itself), and `solve(factors, r)`: the step
      J^-1 r;
    - `iterations`: the budget of steps before the final one (0: the final step alone,
      from `x0`, a single linearised solve);
    - `halvings`: a backtracking line search (a nearly singular Jacobian, as at a plastic
      hinge, makes full Newton steps diverge): the full step first, halved while it does
      not lower the residual's sum of squares, at most `halvings` times;
    - `held`: (factors, r0, error0), a factorised Jacobian near x0, the residual at x0
      (or an estimate of it, with error0 = inf, which makes at least one step), from
      which the iterations start with chord steps. Without it (the default), Newton's
      method, each iteration linearising at the point it steps to (`_newton_steps`);
    - `contraction`: with `held`, a step that shrinks the residual's norm to at most this
      fraction keeps its Jacobian for the next step; any other step is taken with J at
      its start (a held Jacobian whose step fails is refreshed and the step taken again),
      and its successor too;
    - `polish`: the final step from a converged point takes the held Jacobian where the
      error times the weakest contraction of its steps after the first is at most
      `polish` (the error this predicts after the final step); from any other point it
      linearises there.

    The final step's factors are returned, to be held for a nearby problem.
    """
    x0 = jax.lax.stop_gradient(x0)
    if held is None:
        return _newton_steps(linearise, residual, solve, factor, x0, params, iterations, halvings)
    return _chord_steps(
        linearise,
        residual,
        solve,
        factor,
        x0,
        params,
        held,
        iterations,
        halvings=halvings,
        contraction=contraction,
        polish=polish,
    )


def _norm(r):
    return jnp.sqrt(jnp.sum(r**2))


def _backtrack(residual, x, r, step, reached, halvings):
    """The line search: the step's length halved from 1 while the residual (r, error) it
    reaches, `reached` at the full step, is no smaller than r, at most `halvings` times.
    Returns (length, r, error, halvings made). (A NaN norm is not below the current one:
    it is halved too.)"""

    def halve(search):
        length, _, _, count = search
        length = 0.5 * length
        return length, *residual(x - length * step), count + 1

    no_better = lambda search: ~(_norm(search[1]) < _norm(r)) & (search[3] < halvings)
    return jax.lax.while_loop(no_better, halve, (jnp.ones((), r.dtype), *reached, 0))


def _chord_steps(
    linearise,
    residual,
    solve,
    factor,
    x0,
    params,
    held,
    iterations,
    *,
    halvings,
    contraction,
    polish,
):
    """`newton` from a held Jacobian."""
    frozen = jax.lax.stop_gradient(params)
    refresh = lambda x, p: factor(linearise(x, p)[0])

    def attempt(x, factors, r):
        step = solve(factors, r)
        r_new, error = residual(x - step, frozen)
        fast = (error <= 1.0) | (_norm(r_new) <= contraction * _norm(r))
        return step, r_new, error, fast

    def iterate(carry):
        x, factors, r, _, count, current, slow, worst = carry

        def refreshed_attempt(_):
            factors = refresh(x, frozen)
            return factors, *attempt(x, factors, r)

        factors, current = _once(
            slow & ~current, lambda _: (refresh(x, frozen), True), (factors, current)
        )
        step, r_new, error, fast = attempt(x, factors, r)
        factors, step, r_new, error, fast = _once(
            ~current & ~fast, refreshed_attempt, (factors, step, r_new, error, fast)
        )
        at = lambda y: residual(y, frozen)
        length, r_new, error, _ = _backtrack(at, x, r, step, (r_new, error), halvings)
        # The first step's contraction says little of J: the start is often far off along
        # the directions J captures best (the beam's inertia).
        worst = jnp.where(count > 0, jnp.maximum(worst, _norm(r_new) / _norm(r)), worst)
        x_new = x - length * step
        return x_new, factors, r_new, error, count + 1, jnp.asarray(False), ~fast, worst

    held = jax.lax.stop_gradient(held)
    false, no_step = jnp.asarray(False), jnp.zeros((), jnp.result_type(held[1]))
    x_star, factors, r, error, count, _, _, worst = jax.lax.while_loop(
        lambda carry: ~(carry[3] <= 1.0) & (carry[4] < iterations),
        iterate,
        (x0, *held, 0, false, false, no_step),
    )
    sharp = (error <= 1.0) & (count >= 2) & (worst * error <= polish)

    def relinearised(_):
        J, r, _ = linearise(x_star, frozen)
        return factor(J), r

    factors, r = _once(~sharp, relinearised, (factors, r))
    root = _implicit_step(
        x_star, factors, r, params, residual=residual, refresh=refresh, solve=solve
    )
    return NewtonRoot(root, factors)


def _newton_steps(linearise, residual, solve, factor, x0, params, iterations, halvings):
    """`newton` without a held Jacobian: Newton's method, each iteration linearising once,
    at the point it steps to. That residual judges the full step, and its Jacobian serves
    the next step (and the final one, and the derivative) unless the step was halved,
    when the point reached is linearised again."""
    frozen = jax.lax.stop_gradient(params)

    def linearised(x):
        J, r, error = linearise(x, frozen)
        return factor(J), r, error

    def iterate(carry):
        x, factors, r, _, count = carry
        step = solve(factors, r)
        reached = linearised(x - step)
        if halvings > 0:
            at = lambda y: residual(y, frozen)
            length, _, _, halved = _backtrack(at, x, r, step, reached[1:], halvings)
            x_new = x - length * step
            reached = _once(halved > 0, lambda _: linearised(x_new), reached)
            return (x_new, *reached, count + 1)
        return (x - step, *reached, count + 1)

    x_star, factors, r, _, _ = jax.lax.while_loop(
        lambda carry: ~(carry[3] <= 1.0) & (carry[4] < iterations),
        iterate,
        (x0, *linearised(x0), 0),
    )
    root = _implicit_step(x_star, factors, r, params, residual=residual, refresh=None, solve=solve)
    return NewtonRoot(root, factors)
