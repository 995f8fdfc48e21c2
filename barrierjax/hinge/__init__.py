"""Rigid-plastic hinge mechanisms of a vehicle striking a beam on a backing (report ch. 3)."""

from .normal import NormalImpact, NormalImpactHistory, normal_impact

__all__ = ["NormalImpact", "NormalImpactHistory", "normal_impact"]
