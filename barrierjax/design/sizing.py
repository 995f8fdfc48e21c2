r"""Sizing a tube rail on a crushable backing for least vehicle damage, by gradients.

The problem (report 3.2 physics, `barrierjax.simulate` with the closed form):

    minimise    f(t, d, q0) = mean over impact cases of the vehicle's crush D
    subject to  W_k(t, d, q0) <= W_max for every case k     (barrier's final deflection)
                (t, d, q0) in a box

with t, d the rail's wall thickness and depth (`SteelTube`: M0 = Fy Z, m = rho A) and q0
the backing's crush strength per unit length. The constraint is reported as
`max_k W_k - W_max` (<= 0: feasible), the same as one constraint per case.

Physics of the trade-off: a vehicle crushes least against a soft, light barrier that it
can set moving and yield (force ratio phi = P0 / (4 (M0 q0)^(1/2)) > 1 and mass ratio
mu = M/(m L) large); a barrier that the vehicle cannot yield (phi <= 1) acts as a rigid
wall and the vehicle alone absorbs its kinetic energy, D = M v^2 / (2 P0), whatever the
barrier. The same softness lets the heavier vehicle push the barrier further, so the
deflection limit is active at the optimum. The objective is continuous across phi = 1 but
has a kink there and is flat on the rigid side (no gradient), and it falls steeply just
above phi = 1; the landscape can have a second basin where the light vehicle sees a rigid
barrier. Hence the deterministic multi-start below.

Default problem (`SizingProblem()`, SI units; every number is a choice, stated here):
- cases: a 1100 kg car crushing at P0 = 250 kN and a 2270 kg pickup crushing at 450 kN
  (the MASH 1100C and 2270P test masses), both at 40 km/h (11.1 m/s) and normal to the
  barrier (the closed form of report 3.2: `barrierjax.hinge.oblique_impact` has none,
  and its gradients cost milliseconds per scenario, see the README). Against
  a rigid wall they would crush M v^2 / (2 P0) = 272 mm and 311 mm;
- bounds: t in [5.2, 12.7] mm, d in [102, 305] mm with the face width b = 152 mm, so every
  section in the box is compact (AISC 360-16 Table B4.1b: the flange limit
  (b - 3t)/t <= 1.12 (E/Fy)^(1/2) needs t >= 5.07 mm, and the web limit holds for
  d <= 61 t) and M0 = Fy Z is attainable; q0 in [5, 300] kN/m;
- deflection limit W_max = 0.6 m, which is active at the optimum. The optimum is then the
  lightest, weakest rail of the box (t and d on their lower bounds) on the backing just
  strong enough to hold the pickup to 0.6 m: the car yields that barrier and crushes
  about 42 mm instead of 272 mm. With a tighter limit the optimum changes character: at
  0.5 m no feasible barrier lets the car crush much less than on a rigid wall (best mean
  crush about 131 mm, against 137.6 mm in the basin where the car sees a rigid barrier),
  and between about 0.5 and 0.58 m the landscape has many local minima near the car's
  phi = 1 kink (see `solve`).

Method (`solve`): the box is mapped to the unit cube in log coordinates, x = lo (hi/lo)^u,
so each variable is scaled by its own range; iterates stay in the cube by projection
(clipping after each optax.adam step), which also lets a variable settle exactly on a
bound, as t and d do in the default problem (a sigmoid map would only approach it).
The deflection constraints are handled by an augmented Lagrangian (Powell-Hestenes-
Rockafellar for inequalities, one multiplier per case):

    Phi(u) = f/f_ref + (1/(2 rho)) sum_k [max(0, lam_k + rho g_k)^2 - lam_k^2],
    g_k = W_k / W_max - 1,   f_ref = mean M v^2 / (2 P0) (the rigid-wall crush),

minimised by `inner_steps` projected adam steps per outer iteration, then
lam_k <- max(0, lam_k + rho g_k), rho x10 (capped at `rho_max`) when the violation has
not fallen by 4, and the step size x `decay`. A start stops when the design moved less
than `xtol` (in u) over an outer iteration with the violation below `feas_tol`, or after
`max_outer` outer iterations. Its result is then polished to exact feasibility: a
bisection along q0 (more backing strength, less deflection) onto the constraint boundary,
keeping the feasible end (a feasible design with slack is likewise moved down in q0 onto
the boundary when that lowers the crush). This is repeated for `rounds` rounds, each
restarting from the last polished design with the step size x `round_factor`, keeping a
start's best feasible design. The gradient is forward mode (`jax.jacfwd`, three design
variables), which also compiles faster than reverse mode through the closed form's
quadrature. 27 starts (a 3 x 3 x 3 pattern) run at once under `jax.vmap`; the best
feasible one wins. Starts where no vehicle yields the barrier and the constraint is
inactive have a zero gradient and stop at once; the polish still moves them to the
boundary, and the next round goes on from there.

`grid_search` evaluates the same objective and constraint on an n^3 grid, uniform in the
same log coordinates, in one `jit(vmap)` call, then zooms in on the best feasible point;
see its docstring for why the zoom is needed to make the comparison meaningful.
"""

import dataclasses
import math
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import optax
from jaxtyping import Array, Float

from .. import _checks
from ..scene import Barrier, Impact, Scene, Vehicle
from ..simulate import simulate
from .section import SteelTube

Vector = Float[Array, " n"]

KMH = 1.0 / 3.6


def _bounds(name, value) -> Array:
    if np.asarray(value).size != 2:
        raise ValueError(f"{name} must be a pair (low, high); got {np.asarray(value).tolist()!r}")
    low, high = (float(v) for v in np.asarray(value, dtype=float).reshape(-1))
    if not (0.0 < low < high < np.inf):
        raise ValueError(f"{name} must satisfy 0 < low < high < inf; got {(low, high)!r}")
    return jnp.asarray([low, high], dtype=jnp.result_type(float))


class ImpactCases(eqx.Module):
    """Normal impacts the barrier must take: vehicle `mass` (kg), `crush_force` P0 (N)
    and `speed` (m/s), one entry per case, with static `names`."""

    mass: Vector
    crush_force: Vector
    speed: Vector
    names: tuple[str, ...] = eqx.field(static=True)

    def __init__(self, mass, crush_force, speed, names=None):
        arrays = [np.atleast_1d(np.asarray(v, dtype=float)) for v in (mass, crush_force, speed)]
        n = arrays[0].shape[0]
        for label, a in zip(("mass", "crush_force", "speed"), arrays):
            if a.ndim != 1 or a.shape[0] != n:
                raise ValueError(
                    f"ImpactCases.{label} must be a 1-D sequence of {n} values; got shape {a.shape}"
                )
        self.mass = _checks.positive("ImpactCases.mass", arrays[0])
        self.crush_force = _checks.positive("ImpactCases.crush_force", arrays[1])
        self.speed = _checks.positive("ImpactCases.speed", arrays[2])
        names = tuple(f"case {k}" for k in range(n)) if names is None else tuple(names)
        if len(names) != n:
            raise ValueError(f"ImpactCases.names must have {n} entries; got {len(names)}")
        self.names = names


def default_cases() -> ImpactCases:
    """A 1100 kg car (P0 = 250 kN) and a 2270 kg pickup (P0 = 450 kN), both at 40 km/h."""
    return ImpactCases(
        mass=(1100.0, 2270.0),
        crush_force=(250e3, 450e3),
        speed=(40.0 * KMH, 40.0 * KMH),
        names=("1100 kg car", "2270 kg pickup"),
    )


class SizingProblem(eqx.Module):
    """Choose the rail's wall thickness t (m), depth d (m) and the backing strength q0
    (N/m) in their bounds to minimise the mean vehicle crush over `cases`, keeping the
    barrier's deflection at most `deflection_limit` (m) in every case. See the module
    docstring for the defaults and why. `rtol` is the closed form's quadrature target."""

    section: SteelTube
    thickness_bounds: Float[Array, "2"]
    depth_bounds: Float[Array, "2"]
    backing_bounds: Float[Array, "2"]
    cases: ImpactCases
    deflection_limit: Float[Array, ""]
    rtol: float = eqx.field(static=True)

    def __init__(
        self,
        section: SteelTube | None = None,
        thickness_bounds=(5.2e-3, 12.7e-3),
        depth_bounds=(0.102, 0.305),
        backing_bounds=(5e3, 300e3),
        cases: ImpactCases | None = None,
        deflection_limit=0.6,
        rtol: float = 1e-8,
    ):
        self.section = SteelTube() if section is None else section
        if not isinstance(self.section, SteelTube):
            raise ValueError("SizingProblem.section must be a barrierjax.design.SteelTube")
        self.thickness_bounds = _bounds("SizingProblem.thickness_bounds", thickness_bounds)
        self.depth_bounds = _bounds("SizingProblem.depth_bounds", depth_bounds)
        self.backing_bounds = _bounds("SizingProblem.backing_bounds", backing_bounds)
        t_high = float(self.thickness_bounds[1])
        if not 2.0 * t_high < float(self.section.width):
            raise ValueError(
                "SizingProblem.thickness_bounds: the upper thickness must be less than half "
                f"the section width {float(self.section.width):g}; got {t_high:g}"
            )
        if not float(self.depth_bounds[0]) > 2.0 * t_high:
            raise ValueError(
                "SizingProblem.depth_bounds: the lower depth must exceed twice the upper "
                f"thickness {2.0 * t_high:g}; got {float(self.depth_bounds[0]):g}"
            )
        self.cases = default_cases() if cases is None else cases
        if not isinstance(self.cases, ImpactCases):
            raise ValueError("SizingProblem.cases must be a barrierjax.design.ImpactCases")
        self.deflection_limit = _checks.positive("SizingProblem.deflection_limit", deflection_limit)
        if not 0.0 < rtol < 1.0:
            raise ValueError(f"SizingProblem.rtol must be in (0, 1); got {rtol!r}")
        self.rtol = float(rtol)

    @property
    def lower(self) -> Float[Array, "3"]:
        """Lower bounds of (t, d, q0)."""
        return jnp.stack([self.thickness_bounds[0], self.depth_bounds[0], self.backing_bounds[0]])

    @property
    def upper(self) -> Float[Array, "3"]:
        """Upper bounds of (t, d, q0)."""
        return jnp.stack([self.thickness_bounds[1], self.depth_bounds[1], self.backing_bounds[1]])


# --------------------------------------------------------------------------------------
# The model: design vector x = (t, d, q0) in SI units.


def to_design(problem: SizingProblem, u):
    """x = lo (hi/lo)^u: the unit cube onto the box, uniform in log coordinates."""
    lo, hi = problem.lower, problem.upper
    return lo * jnp.exp(u * jnp.log(hi / lo))


def to_unit(problem: SizingProblem, x):
    """Inverse of `to_design`."""
    lo, hi = problem.lower, problem.upper
    return jnp.log(x / lo) / jnp.log(hi / lo)


def barrier(problem: SizingProblem, x) -> Barrier:
    """The `Barrier` of design x = (t, d, q0)."""
    t, d, q0 = x[..., 0], x[..., 1], x[..., 2]
    moment, mass_per_length = problem.section.properties(t, d)
    return Barrier(moment, mass_per_length, q0)


def responses(problem: SizingProblem, x) -> tuple[Vector, Vector]:
    """(crush D_k, deflection W_k) of design x in every case (m), by the closed form."""
    b = barrier(problem, x)

    def one(mass, crush_force, speed):
        scene = Scene(b, Vehicle(mass, crush_force), Impact(speed))
        r = simulate(scene, method="closed_form", rtol=problem.rtol, n_history=0)
        return r.damage, r.max_deflection

    c = problem.cases
    return jax.vmap(one)(c.mass, c.crush_force, c.speed)


def objective(problem: SizingProblem, x):
    """Mean vehicle crush over the cases (m)."""
    return jnp.mean(responses(problem, x)[0])


def constraint(problem: SizingProblem, x):
    """max_k W_k - W_max (m): <= 0 is feasible."""
    return jnp.max(responses(problem, x)[1]) - problem.deflection_limit


def rigid_wall_crush(problem: SizingProblem):
    """Mean crush M v^2 / (2 P0) against a rigid wall (m): the objective's scale."""
    c = problem.cases
    return jnp.mean(0.5 * c.mass * c.speed**2 / c.crush_force)


# --------------------------------------------------------------------------------------
# Augmented Lagrangian with optax.adam, many starts at once.


class _State(eqx.Module):
    u: Array  # design in the unit cube
    opt_state: optax.OptState
    lam: Array  # multipliers, one per case
    rho: Array  # penalty parameter
    anchor: Array  # u at the last multiplier update
    violation: Array  # max(g, 0) at the last multiplier update
    step_size: Array
    steps: Array  # gradient evaluations so far
    outer: Array  # multiplier updates so far
    done: Array


class Solution(eqx.Module):
    """The gradient optimiser's result for every start (leading axis: start).

    `x`: polished designs (t, d, q0); `objective`,
    `constraint`: of the polished designs; `outer`: outer iterations; `converged`:
    met the stopping test before `max_outer`; `feasible`: constraint <= 0; `best`: index
    of the best feasible start (or of the least infeasible one if none is feasible)."""

    x: Array
    objective: Array
    constraint: Array
    outer: Array
    converged: Array
    feasible: Array
    best: Array


def default_starts() -> Array:
    """27 starts: the cell centres of a 3 x 3 x 3 partition of the unit cube (each
    coordinate 1/6, 1/2 or 5/6)."""
    levels = np.array([1.0, 3.0, 5.0]) / 6.0
    return jnp.asarray(
        np.array(np.meshgrid(levels, levels, levels, indexing="ij")).reshape(3, -1).T
    )


def _merit(problem, u, lam, rho, scale):
    """Augmented Lagrangian (PHR) of the scaled problem, and the scaled constraints."""
    damage, deflection = responses(problem, to_design(problem, u))
    g = deflection / problem.deflection_limit - 1.0
    penalty = jnp.sum(jnp.maximum(0.0, lam + rho * g) ** 2 - lam**2) / (2.0 * rho)
    return jnp.mean(damage) / scale + penalty, g


def _augmented_lagrangian(
    problem, u0, *, learning_rate, inner_steps, max_outer, xtol, feas_tol, rho0, rho_max, decay
):
    """One start. A single flat loop with one gradient evaluation per pass (so the model
    is compiled once, forward and backward): `inner_steps` projected adam steps on the
    augmented Lagrangian, then, on the pass that would take the next step, the
    multiplier, penalty and step-size updates and the stopping test, from the
    constraint values that the same gradient evaluation returns."""
    scale = rigid_wall_crush(problem)
    optimizer = optax.inject_hyperparams(optax.adam)(learning_rate=learning_rate)
    merit = jax.jacfwd(_merit, argnums=1, has_aux=True)
    n_cases = problem.cases.mass.shape[0]

    def body(state):
        grad, g = merit(problem, state.u, state.lam, state.rho, scale)
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
        lam=jnp.zeros(n_cases, dtype),
        rho=jnp.asarray(rho0, dtype),
        anchor=u0,
        violation=jnp.asarray(jnp.inf, dtype),
        step_size=jnp.asarray(learning_rate, dtype),
        steps=jnp.asarray(0),
        outer=jnp.asarray(0),
        done=jnp.asarray(False),
    )
    return jax.lax.while_loop(cond, body, init)


def _objective_and_constraint(problem, u):
    damage, deflection = responses(problem, to_design(problem, u))
    return jnp.mean(damage), jnp.max(deflection) - problem.deflection_limit


def _polish(problem: SizingProblem, x):
    """`polish`, also returning the objective and constraint of the result."""
    u = jnp.clip(to_unit(problem, x), 0.0, 1.0)
    stiff_q, stiff_all, soft_q = u.at[2].set(1.0), jnp.ones_like(u), u.at[2].set(0.0)
    f, c = jax.vmap(lambda v: _objective_and_constraint(problem, v))(
        jnp.stack([u, stiff_q, stiff_all, soft_q])
    )
    infeasible = c[0] > 0.0
    # Infeasible: towards more backing strength (or the stiffest corner), onto the
    # boundary. Feasible with slack: towards less backing strength, onto the boundary.
    use_q = c[1] <= 0.0
    target = jnp.where(infeasible, jnp.where(use_q, stiff_q, stiff_all), soft_q)
    f_target = jnp.where(infeasible, jnp.where(use_q, f[1], f[2]), f[3])
    c_target = jnp.where(infeasible, jnp.where(use_q, c[1], c[2]), c[3])
    # Bisection on [feasible end a, infeasible end b], carrying f and c of a.
    a = jnp.where(infeasible, target, u)
    b = jnp.where(infeasible, u, target)
    fa = jnp.where(infeasible, f_target, f[0])
    ca = jnp.where(infeasible, c_target, c[0])

    def body(_, carry):
        a, b, fa, ca = carry
        mid = 0.5 * (a + b)
        f_mid, c_mid = _objective_and_constraint(problem, mid)
        ok = c_mid <= 0.0
        return (
            jnp.where(ok, mid, a),
            jnp.where(ok, b, mid),
            jnp.where(ok, f_mid, fa),
            jnp.where(ok, c_mid, ca),
        )

    a, _, fa, ca = jax.lax.fori_loop(0, 52, body, (a, b, fa, ca))
    # Feasible all the way down in q0: the constraint is not active along this line.
    slack_line = ~infeasible & (c[3] <= 0.0)
    a = jnp.where(slack_line, soft_q, a)
    fa = jnp.where(slack_line, f[3], fa)
    ca = jnp.where(slack_line, c[3], ca)
    take = (ca <= 0.0) & (infeasible | (fa < f[0]))
    return (
        to_design(problem, jnp.where(take, a, u)),
        jnp.where(take, fa, f[0]),
        jnp.where(take, ca, c[0]),
    )


def polish(problem: SizingProblem, x):
    """Make design x feasible, or better if feasible with slack, by moving along q0
    (or, if q0 alone cannot make it feasible, towards the stiffest corner of the box)
    onto the constraint boundary by bisection, and return the feasible end. If even
    the stiffest corner is infeasible, x is returned unchanged."""
    return _polish(problem, x)[0]


@eqx.filter_jit
def solve(
    problem: SizingProblem,
    starts=None,
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
    """Minimise the mean crush under the deflection limit from every start (points of
    the unit cube, default `default_starts()`), by the augmented Lagrangian with
    projected optax.adam described in the module docstring; polish each result onto the
    feasible side of the constraint and pick the best feasible one."""
    u0 = default_starts() if starts is None else jnp.asarray(starts)
    u0 = jnp.clip(u0.astype(problem.lower.dtype), 0.0, 1.0)
    run = lambda u, lr: _augmented_lagrangian(
        problem,
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
        u, x, f, c, outer, converged = carry
        lr = learning_rate * round_factor ** jnp.asarray(r, u.dtype)
        final = jax.vmap(run, in_axes=(0, None))(u, lr)
        x_new, f_new, c_new = jax.vmap(lambda v: _polish(problem, v))(to_design(problem, final.u))
        better = jnp.where(c <= 0.0, (c_new <= 0.0) & (f_new < f), c_new < c)
        keep = lambda new, old: jnp.where(
            better.reshape(better.shape + (1,) * (new.ndim - 1)), new, old
        )
        return (
            to_unit(problem, x_new),
            keep(x_new, x),
            keep(f_new, f),
            keep(c_new, c),
            outer + final.outer,
            keep(final.done, converged),
        )

    inf = jnp.full(u0.shape[:1], jnp.inf, u0.dtype)
    init = (
        u0,
        to_design(problem, u0),
        inf,
        inf,
        jnp.zeros(u0.shape[:1], int),
        jnp.zeros(u0.shape[:1], bool),
    )
    _, x, f, c, outer, converged = jax.lax.fori_loop(0, rounds, round_, init)
    feasible = c <= 0.0
    best = jnp.where(jnp.any(feasible), jnp.argmin(jnp.where(feasible, f, jnp.inf)), jnp.argmin(c))
    return Solution(
        x=x,
        objective=f,
        constraint=c,
        outer=outer,
        converged=converged,
        feasible=feasible,
        best=best,
    )


# --------------------------------------------------------------------------------------
# Brute force.


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


# --------------------------------------------------------------------------------------
# Report.


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

        def plain(value):
            if isinstance(value, tuple):
                return [plain(v) for v in value]
            if isinstance(value, float) and not math.isfinite(value):
                return None
            return value

        return {field.name: plain(getattr(self, field.name)) for field in dataclasses.fields(self)}

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


def _timed(fn):
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
    sol, time_solve = _timed(run_solve)
    grid, time_grid = _timed(run_grid)
    # The same calls again, compiled: the run times without compilation.
    _, warm_solve = _timed(run_solve)
    _, warm_grid = _timed(run_grid)

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
    """`optimize(SizingProblem())`: the default problem (see the module docstring)."""
    return optimize(SizingProblem())
