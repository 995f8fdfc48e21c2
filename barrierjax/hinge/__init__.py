"""Rigid-plastic hinge mechanisms of a vehicle striking a beam on a backing (report ch. 3)."""

from .normal import NormalImpact, NormalImpactHistory, normal_impact
from .oblique import MovingLoad, ObliqueImpact, ObliqueImpactHistory, moving_load, oblique_impact

__all__ = [
    "MovingLoad",
    "NormalImpact",
    "NormalImpactHistory",
    "ObliqueImpact",
    "ObliqueImpactHistory",
    "moving_load",
    "normal_impact",
    "oblique_impact",
]
