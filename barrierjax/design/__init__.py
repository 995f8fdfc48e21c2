"""Barrier design: size a tube rail and its backing for least vehicle damage under a
deflection limit, by gradients (augmented Lagrangian with optax), checked by brute force;
and robustly, for the least expected damage over real-world impacts (`impacts`) under
every crash test of a MASH level (`RobustSizing`, `optimize_robust`).

`optimize_default()` solves the default problem and returns a `DesignReport`
(`summary()`, `as_dict()`); `SizingProblem` states a problem, `SteelTube` the section.
"""

from .formulation import Formulation
from .grid import GridResult, grid_along_boundary, grid_minimise, grid_search
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
from .optimizer import Solution, default_starts, minimise, polish, solve, to_boundary
from .problem import ImpactCases, SizingProblem, default_cases
from .report import DesignReport, optimize, optimize_default
from .robust import (
    CRITERIA,
    RobustSizing,
    crash_test_responses,
    damages,
    expected_damage,
    limits,
    margins,
    rail_barrier,
    robust_formulation,
)
from .robust_report import Performance, RobustReport, optimize_robust, performance
from .section import SteelTube, area, plastic_modulus

__all__ = [
    "CRITERIA",
    "DesignReport",
    "Formulation",
    "GridResult",
    "ImpactCases",
    "Performance",
    "RobustReport",
    "RobustSizing",
    "SizingProblem",
    "Solution",
    "SteelTube",
    "area",
    "barrier",
    "constraint",
    "crash_test_responses",
    "damages",
    "default_cases",
    "default_starts",
    "expected_damage",
    "grid_along_boundary",
    "grid_minimise",
    "grid_search",
    "limits",
    "margins",
    "minimise",
    "objective",
    "optimize",
    "optimize_default",
    "optimize_robust",
    "performance",
    "plastic_modulus",
    "polish",
    "rail_barrier",
    "responses",
    "rigid_wall_crush",
    "robust_formulation",
    "sizing_formulation",
    "solve",
    "to_boundary",
    "to_design",
    "to_unit",
]
