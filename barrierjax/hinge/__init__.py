"""Rigid-plastic hinge mechanisms of a vehicle striking a beam on a backing (report ch. 3)."""

from .normal import NormalImpact, NormalImpactHistory, normal_impact
from .oblique import MovingLoad, ObliqueImpact, ObliqueImpactHistory, moving_load, oblique_impact
from .static_collapse import StaticLoadDeflection, static_load_deflection

__all__ = [
    "MovingLoad",
    "NormalImpact",
    "NormalImpactHistory",
    "ObliqueImpact",
    "ObliqueImpactHistory",
    "StaticLoadDeflection",
    "moving_load",
    "normal_impact",
    "oblique_impact",
    "static_load_deflection",
]
