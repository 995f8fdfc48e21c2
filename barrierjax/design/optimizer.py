r"""The gradient optimiser of the sizing problems: an augmented Lagrangian with projected
optax.adam from many starts at once (`minimise`, and `solve` for a `SizingProblem`), and
the polish onto the constraint boundary (`polish`). A problem reaches the optimiser as a
`Formulation`: its objective and normalised constraints on the unit cube.

Method (`solve`): the box is mapped to the unit cube in log coordinates, x = lo (hi/lo)^u,
so each variable is scaled by its own range; iterates stay in the cube by projection
(clipping after each optax.adam step), which also lets a variable settle exactly on a
bound, as t and d do in the default problem (a sigmoid map would only approach it).
The constraints are handled by an augmented Lagrangian (Powell-Hestenes-Rockafellar for
inequalities, one multiplier per constraint):

    Phi(u) = f/f_ref + (1/(2 rho)) sum_k [max(0, lam_k + rho g_k)^2 - lam_k^2],

with each constraint normalised by its limit, g_k = value_k / limit_k - 1 (the sizing
problem: the deflection W_k of case k over W_max), and f_ref the objective's scale (the
sizing problem: the mean rigid-wall crush M v^2 / (2 P0)),

minimised by `inner_steps` projected adam steps per outer iteration, then
lam_k <- max(0, lam_k + rho g_k), rho x10 (capped at `rho_max`) when the violation has
not fallen by 4, and the step size x `decay`. A start stops when the design moved less
than `xtol` (in u) over an outer iteration with the violation below `feas_tol`, or after
`max_outer` outer iterations. Its result is then polished to exact feasibility: a root
search (regula falsi, `to_boundary`) along the formulation's `stiffening` coordinate (q0:
more backing strength, less deflection) onto the constraint boundary, keeping the feasible
end (a feasible design with slack is likewise moved down that coordinate onto the boundary
when that lowers the objective). This is repeated for `rounds` rounds, each
restarting from the last polished design with the step size x `round_factor`, keeping a
start's best feasible design. The gradient is forward mode (`jax.jacfwd`, two or three
design variables), which also compiles faster than reverse mode through the closed form's
quadrature. 3^n starts (a 3 x ... x 3 pattern) run at once under `jax.vmap`; the best
feasible one wins. Starts where no vehicle yields the barrier and the constraint is
inactive have a zero gradient and stop at once; the polish still moves them to the
boundary, and the next round goes on from there.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array

from .formulation import Formulation
from .model import sizing_formulation, to_design, to_unit
from .problem import SizingProblem

if TYPE_CHECKING:
    import optax


class _State(eqx.Module):
    u: Array  # design in the unit cube
    opt_state: optax.OptState
    lam: Array  # multipliers, one per constraint
    rho: Array  # penalty parameter
    anchor: Array  # u at the last multiplier update
    violation: Array  # max(g, 0) at the last multiplier update
    step_size: Array
    steps: Array  # gradient evaluations so far
    outer: Array  # multiplier updates so far
    done: Array


class Solution(eqx.Module):
    """The gradient optimiser's result for every start (leading axis: start).

    `x`: polished designs; `objective`, `constraint`: of the polished designs (the
    constraint in the problem's own terms: `solve` gives metres of deflection,
    `minimise` the largest normalised constraint); `outer`: outer iterations;
    `converged`: met the stopping test before `max_outer`; `feasible`: constraint <= 0;
    `best`: index of the best feasible start (or of the least infeasible one if none is
    feasible)."""

    x: Array
    objective: Array
    constraint: Array
    outer: Array
    converged: Array
    feasible: Array
    best: Array


def default_starts(dimension: int = 3) -> Array:
    """3^dimension starts: the cell centres of a 3 x ... x 3 partition of the unit cube
    (each coordinate 1/6, 1/2 or 5/6)."""
    levels = np.array([1.0, 3.0, 5.0]) / 6.0
    grid = np.meshgrid(*([levels] * int(dimension)), indexing="ij")
    return jnp.asarray(np.array(grid).reshape(int(dimension), -1).T)


def _merit(form: Formulation, u, lam, rho):
    """Augmented Lagrangian (PHR) of the scaled problem, and the normalised constraints."""
    f, g = form.measure(form.problem, u)
    penalty = jnp.sum(jnp.maximum(0.0, lam + rho * g) ** 2 - lam**2) / (2.0 * rho)
    return f / form.scale + penalty, g


def _augmented_lagrangian(
    form, u0, *, learning_rate, inner_steps, max_outer, xtol, feas_tol, rho0, rho_max, decay
):
    """One start. A single flat loop with one gradient evaluation per pass (so the model
    is compiled once, forward and backward): `inner_steps` projected adam steps on the
    augmented Lagrangian, then, on the pass that would take the next step, the
    multiplier, penalty and step-size updates and the stopping test, from the
    constraint values that the same gradient evaluation returns."""
    import optax  # (on first use: see `_solve.phases`)

    optimizer = optax.inject_hyperparams(optax.adam)(learning_rate=learning_rate)
    merit = jax.jacfwd(_merit, argnums=1, has_aux=True)
    n_constraints = jax.eval_shape(lambda u: form.measure(form.problem, u)[1], u0).shape[0]

    def body(state):
        grad, g = merit(form, state.u, state.lam, state.rho)
        # Adam step (projected onto the unit cube).
        hyperparams = {**state.opt_state.hyperparams, "learning_rate": state.step_size}
        # optax's bias correction mixes its int32 step count with float64 moments, which
        # strict dtype promotion (the test suite's setting) refuses; allow it here only.
        with jax.numpy_dtype_promotion("standard"):
            updates, opt_state = optimizer.update(
                grad, state.opt_state._replace(hyperparams=hyperparams), state.u
            )
        u = jnp.clip(optax.apply_updates(state.u, updates), 0.0, 1.0)
        stepped = eqx.tree_at(
            lambda s: (s.u, s.opt_state, s.steps), state, (u, opt_state, state.steps + 1)
        )
        # Multiplier update at the end of an inner block (no step on this pass: the
        # gradient above used the old multipliers).
        violation = jnp.max(jnp.maximum(g, 0.0))
        stalled = (violation > 0.25 * state.violation) & (violation > feas_tol)
        updated = _State(
            u=state.u,
            opt_state=state.opt_state,
            lam=jnp.maximum(0.0, state.lam + state.rho * g),
            rho=jnp.where(stalled, jnp.minimum(10.0 * state.rho, rho_max), state.rho),
            anchor=state.u,
            violation=violation,
            step_size=state.step_size * decay,
            steps=state.steps + 1,
            outer=state.outer + 1,
            done=(jnp.max(jnp.abs(state.u - state.anchor)) <= xtol) & (violation <= feas_tol),
        )
        at_update = (state.steps + 1) % (inner_steps + 1) == 0
        return jax.tree.map(lambda a, b: jnp.where(at_update, a, b), updated, stepped)

    def cond(state):
        return (~state.done) & (state.outer < max_outer)

    dtype = u0.dtype
    init = _State(
        u=u0,
        opt_state=optimizer.init(u0),
        lam=jnp.zeros(n_constraints, dtype),
        rho=jnp.asarray(rho0, dtype),
        anchor=u0,
        violation=jnp.asarray(jnp.inf, dtype),
        step_size=jnp.asarray(learning_rate, dtype),
        steps=jnp.asarray(0),
        outer=jnp.asarray(0),
        done=jnp.asarray(False),
    )
    return jax.lax.while_loop(cond, body, init)


# `to_boundary` evaluates the design and three ends of its line, then takes this many
# regula falsi steps. On the robust sizings' formulations (the test suite's and the TL-3
# default), 89 points: 16 steps land within 6.3e-15 of bisection's boundary in u, 20 within
# 5.6e-16, as close as 52 bisections' own rounding. Where two terms of the constraint cross
# at the boundary, with slopes 8 to 1 (tests/test_design_formulation.py), the secant closes
# in linearly: 1e-4 off after 16 steps, 1e-12 after 24, to rounding after 28.
BOUNDARY_STEPS = 28


def to_boundary(form: Formulation, u):
    """`polish` in unit coordinates, for any formulation: (u, objective, largest
    normalised constraint) of the point reached along its `stiffening` coordinate.

    The boundary is bracketed by a feasible end and an infeasible one and found by regula
    falsi with the Illinois modification (a bracket's end kept twice in a row has its
    constraint value halved, so that both ends close in, superlinearly where the
    constraint is smooth at the boundary; where its largest term changes there, linearly,
    but within the bracket, whose feasible end is the point returned). The design and the
    line's three ends are evaluated in the same loop, one point a pass: the program holds
    one copy of the model, where a `vmap` over the ends beside the loop held two
    (compiling `minimise` 2 s longer)."""
    axis = form.stiffening
    # The design, the stiff end of its line, the stiffest corner, the soft end.
    ends = jnp.stack([u, u.at[axis].set(1.0), jnp.ones_like(u), u.at[axis].set(0.0)])
    n_ends = ends.shape[0]

    def bracket(f, c):
        """[feasible end a, infeasible end b], (f, c) at a, the constraint at a and b as
        the secant reads them, and which end moved last (none). Infeasible: stiffer along
        the axis (or the stiffest corner), onto the boundary. Feasible with slack: softer
        along the axis, onto the boundary."""
        infeasible = c[0] > 0.0
        pick = lambda values: jnp.where(
            infeasible, jnp.where(c[1] <= 0.0, values[1], values[2]), values[3]
        )
        target, f_target, c_target = pick(ends), pick(f), pick(c)
        a = jnp.where(infeasible, target, u)
        b = jnp.where(infeasible, u, target)
        fa = jnp.where(infeasible, f_target, f[0])
        ca = jnp.where(infeasible, c_target, c[0])
        cb = jnp.where(infeasible, c[0], c_target)
        return a, b, fa, ca, ca, cb, jnp.zeros((), jnp.int32)

    def body(k, carry):
        f, c, a, b, fa, ca, secant_a, secant_b, moved = carry
        at_end, end = k < n_ends, jnp.minimum(k, n_ends - 1)
        # Where the secant through the ends crosses zero (ca <= 0 < cb); halfway where the
        # line has no bracket (its points are then not taken, `take` below).
        t = jnp.where(secant_b > secant_a, secant_a / (secant_a - secant_b), 0.5)
        t = jnp.where(jnp.isfinite(t), jnp.clip(t, 0.0, 1.0), 0.5)
        point = jnp.where(at_end, ends[end], a + t * (b - a))
        f_k, c_k = form.evaluate(point)
        f = jnp.where(at_end, f.at[end].set(f_k), f)
        c = jnp.where(at_end, c.at[end].set(c_k), c)
        feasible, infeasible = ~at_end & (c_k <= 0.0), ~at_end & (c_k > 0.0)
        stepped = (
            jnp.where(feasible, point, a),
            jnp.where(infeasible, point, b),
            jnp.where(feasible, f_k, fa),
            jnp.where(feasible, c_k, ca),
            jnp.where(feasible, c_k, jnp.where(infeasible & (moved == 1), 0.5, 1.0) * secant_a),
            jnp.where(infeasible, c_k, jnp.where(feasible & (moved == -1), 0.5, 1.0) * secant_b),
            jnp.where(feasible, -1, jnp.where(infeasible, 1, moved)),
        )
        started = bracket(f, c)
        first = k == n_ends - 1
        return f, c, *(jnp.where(first, s0, s1) for s0, s1 in zip(started, stepped))

    zeros = jnp.zeros(n_ends, u.dtype)
    zero = zeros[0]
    carry = (zeros, zeros, u, u, zero, zero, zero, zero, jnp.zeros((), jnp.int32))
    f, c, a, _, fa, ca, *_ = jax.lax.fori_loop(0, n_ends + BOUNDARY_STEPS, body, carry)
    infeasible = c[0] > 0.0
    # Feasible all the way down the axis: the constraint is not active along this line.
    slack_line = ~infeasible & (c[3] <= 0.0)
    a = jnp.where(slack_line, ends[3], a)
    fa = jnp.where(slack_line, f[3], fa)
    ca = jnp.where(slack_line, c[3], ca)
    take = (ca <= 0.0) & (infeasible | (fa < f[0]))
    return jnp.where(take, a, u), jnp.where(take, fa, f[0]), jnp.where(take, ca, c[0])


def polish(problem: SizingProblem, x):
    """Make design x feasible, or better if feasible with slack, by moving along q0
    (or, if q0 alone cannot make it feasible, towards the stiffest corner of the box)
    onto the constraint boundary (`to_boundary`), and return the feasible end. If even
    the stiffest corner is infeasible, x is returned unchanged."""
    u = jnp.clip(to_unit(problem, x), 0.0, 1.0)
    return to_design(problem, to_boundary(sizing_formulation(problem), u)[0])


@eqx.filter_jit
def minimise(
    form: Formulation,
    starts,
    *,
    learning_rate: float = 0.05,
    inner_steps: int = 100,
    max_outer: int = 40,
    xtol: float = 1e-6,
    feas_tol: float = 1e-6,
    rho0: float = 10.0,
    rho_max: float = 1e6,
    decay: float = 0.7,
    rounds: int = 2,
    round_factor: float = 0.1,
) -> Solution:
    """Minimise `form`'s objective under its constraints from every start (points of
    the unit cube) by the augmented Lagrangian with projected optax.adam described in
    the module docstring; polish each result onto the feasible side of the constraints
    and pick the best feasible one. The `Solution`'s constraint is the largest
    normalised one."""
    u0 = jnp.clip(jnp.asarray(starts), 0.0, 1.0)
    run = lambda u, lr: _augmented_lagrangian(
        form,
        u,
        learning_rate=lr,
        inner_steps=inner_steps,
        max_outer=max_outer,
        xtol=xtol,
        feas_tol=feas_tol,
        rho0=rho0,
        rho_max=rho_max,
        decay=decay,
    )

    def round_(r, carry):
        u, best_u, f, c, outer, converged = carry
        lr = learning_rate * round_factor ** jnp.asarray(r, u.dtype)
        final = jax.vmap(run, in_axes=(0, None))(u, lr)
        u_new, f_new, c_new = jax.vmap(lambda v: to_boundary(form, v))(final.u)
        better = jnp.where(c <= 0.0, (c_new <= 0.0) & (f_new < f), c_new < c)
        keep = lambda new, old: jnp.where(
            better.reshape(better.shape + (1,) * (new.ndim - 1)), new, old
        )
        return (
            u_new,
            keep(u_new, best_u),
            keep(f_new, f),
            keep(c_new, c),
            outer + final.outer,
            keep(final.done, converged),
        )

    inf = jnp.full(u0.shape[:1], jnp.inf, u0.dtype)
    init = (u0, u0, inf, inf, jnp.zeros(u0.shape[:1], int), jnp.zeros(u0.shape[:1], bool))
    _, u, f, c, outer, converged = jax.lax.fori_loop(0, rounds, round_, init)
    feasible = c <= 0.0
    best = jnp.where(jnp.any(feasible), jnp.argmin(jnp.where(feasible, f, jnp.inf)), jnp.argmin(c))
    return Solution(
        x=jax.vmap(lambda v: form.design(form.problem, v))(u),
        objective=f,
        constraint=c,
        outer=outer,
        converged=converged,
        feasible=feasible,
        best=best,
    )


def solve(problem: SizingProblem, starts=None, **options) -> Solution:
    """Minimise the mean crush under the deflection limit (`minimise` of the sizing
    problem's formulation, with its options) from every start (default
    `default_starts()`); the constraint is returned in metres, max_k W_k - W_max."""
    u0 = default_starts() if starts is None else jnp.asarray(starts)
    solution = minimise(sizing_formulation(problem), u0.astype(problem.lower.dtype), **options)
    return eqx.tree_at(
        lambda s: s.constraint, solution, solution.constraint * problem.deflection_limit
    )
