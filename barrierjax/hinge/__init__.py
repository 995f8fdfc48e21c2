"""Rigid-plastic hinge mechanisms of a vehicle striking a beam on a backing (report ch. 3).

A solve that fails (a spent step budget, say) raises a `SolveError` (a `RuntimeError`)
naming the model, the phase and, in a batch, the first scenario that failed
(`SolveError.scenario`; every one, with its reason: `SolveError.failures`)."""

from .._solve.phases import SolveError
from .axial import axial_impact
from .elastic import (
    ElasticImpact,
    StringImpact,
    delay_integral,
    delayed_yield_limit_speed,
    elastic_impact,
    elastic_limit_speed,
    impact_rate,
    string_impact,
    timoshenko_initial_deceleration,
)
from .normal import NormalImpact, NormalImpactHistory, normal_impact
from .oblique import MovingLoad, ObliqueImpact, ObliqueImpactHistory, moving_load, oblique_impact
from .static_collapse import StaticLoadDeflection, static_load_deflection

__all__ = [
    "axial_impact",
    "ElasticImpact",
    "MovingLoad",
    "NormalImpact",
    "NormalImpactHistory",
    "ObliqueImpact",
    "ObliqueImpactHistory",
    "SolveError",
    "StaticLoadDeflection",
    "StringImpact",
    "delay_integral",
    "delayed_yield_limit_speed",
    "elastic_impact",
    "elastic_limit_speed",
    "impact_rate",
    "moving_load",
    "normal_impact",
    "oblique_impact",
    "static_load_deflection",
    "string_impact",
    "timoshenko_initial_deceleration",
]
