"""`Formulation`: a sizing problem on the unit cube of its design box, as the gradient
optimiser (`barrierjax.design.minimise`) and the brute-force grid (`grid_search`) see it."""

from collections.abc import Callable

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array


class Formulation(eqx.Module):
    """A sizing problem as the optimiser and the grid see it, on the unit cube of its
    design box: `measure(problem, u)` returns (objective, g), g the constraints
    normalised by their limits (<= 0 feasible); `design(problem, u)` the design in SI
    units; `scale` the objective's reference value (the merit function divides by it);
    `stiffening` the coordinate along which designs become feasible (`polish`)."""

    problem: eqx.Module
    scale: Array
    measure: Callable = eqx.field(static=True)
    design: Callable = eqx.field(static=True)
    stiffening: int = eqx.field(static=True)

    def evaluate(self, u):
        """(objective, largest normalised constraint) at u."""
        f, g = self.measure(self.problem, u)
        return f, jnp.max(g)
