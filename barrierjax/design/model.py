r"""The model of the sizing problem: the vehicle's crush and the barrier's deflection of a
design x = (t, d, q0) in SI units in every impact case, by the closed form of report 3.2
(`barrierjax.simulate`), and the objective and constraint built on them. `to_design` and
`to_unit` map the unit cube onto the box and back, uniformly in log coordinates.

Physics of the trade-off: a vehicle crushes least against a soft, light barrier that it
can set moving and yield (force ratio phi = P0 / (4 (M0 q0)^(1/2)) > 1 and mass ratio
mu = M/(m L) large); a barrier that the vehicle cannot yield (phi <= 1) acts as a rigid
wall and the vehicle alone absorbs its kinetic energy, D = M v^2 / (2 P0), whatever the
barrier. The same softness lets the heavier vehicle push the barrier further, so the
deflection limit is active at the optimum. The objective is continuous across phi = 1 but
has a kink there and is flat on the rigid side (no gradient), and it falls steeply just
above phi = 1; the landscape can have a second basin where the light vehicle sees a rigid
barrier. Hence the deterministic multi-start of `barrierjax.design.solve`.
"""

import jax
import jax.numpy as jnp

from ..scene import Barrier, Impact, Scene, Vehicle
from ..simulate import simulate
from .formulation import Formulation
from .problem import SizingProblem, Vector


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


def _measure(problem: SizingProblem, u):
    """Mean crush, and each case's deflection over the limit minus one, at u."""
    damage, deflection = responses(problem, to_design(problem, u))
    return jnp.mean(damage), deflection / problem.deflection_limit - 1.0


def sizing_formulation(problem: SizingProblem) -> Formulation:
    """The sizing problem on the unit cube: mean crush over the rigid-wall crush, one
    deflection constraint per case; q0 (the third coordinate) stiffens."""
    return Formulation(
        problem, rigid_wall_crush(problem), measure=_measure, design=to_design, stiffening=2
    )
