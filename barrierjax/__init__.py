"""barrierjax: differentiable impact-dynamics models for highway barriers, in JAX.

Describe a `Scene` (a `Barrier`, a `Vehicle`, an `Impact`) in any consistent units and
call `simulate(scene)`; the report's models live in `barrierjax.hinge` (chapter 3) and
`barrierjax.materials` (chapter 2), the sizing problem in `barrierjax.design`.
"""

from . import hinge, materials
from .scene import (
    Barrier,
    Dimensionless,
    Impact,
    Scales,
    Scene,
    Vehicle,
    broadcast_scene,
    dimensionless,
)
from .simulate import History, Result, simulate

__all__ = [
    "Barrier",
    "Dimensionless",
    "History",
    "Impact",
    "Result",
    "Scales",
    "Scene",
    "Vehicle",
    "broadcast_scene",
    "dimensionless",
    "hinge",
    "materials",
    "simulate",
]
