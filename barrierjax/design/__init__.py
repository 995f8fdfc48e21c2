"""Barrier design: size a tube rail and its backing for least vehicle damage under a
deflection limit, by gradients (augmented Lagrangian with optax), checked by brute force.

`optimize_default()` solves the default problem and returns a `DesignReport`
(`summary()`, `as_dict()`); `SizingProblem` states a problem, `SteelTube` the section.
"""

from .formulation import Formulation
from .grid import GridResult, grid_minimise, grid_search
from .model import (
    barrier,
    constraint,
    objective,
    responses,
    rigid_wall_crush,
    sizing_formulation,
    to_design,
    to_unit,
)
from .optimizer import Solution, default_starts, minimise, polish, solve
from .problem import ImpactCases, SizingProblem, default_cases
from .report import DesignReport, optimize, optimize_default
from .section import SteelTube, area, plastic_modulus

__all__ = [
    "DesignReport",
    "Formulation",
    "GridResult",
    "ImpactCases",
    "SizingProblem",
    "Solution",
    "SteelTube",
    "area",
    "barrier",
    "constraint",
    "default_cases",
    "default_starts",
    "grid_minimise",
    "grid_search",
    "minimise",
    "objective",
    "optimize",
    "optimize_default",
    "plastic_modulus",
    "polish",
    "responses",
    "rigid_wall_crush",
    "sizing_formulation",
    "solve",
    "to_design",
    "to_unit",
]
