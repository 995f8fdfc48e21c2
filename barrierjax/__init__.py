"""barrierjax: differentiable impact-dynamics models for highway barriers, in JAX.

Describe a `Scene` (a `Barrier`, a `Vehicle`, an `Impact`) in any consistent units, or
read one with `load_scene("scene.toml")`, and call `simulate(scene)` for its `Result`.
The report's models live in `barrierjax.materials` (chapter 2), `barrierjax.hinge`
(chapter 3) and `barrierjax.beam` (chapter 4); the sizing problem in `barrierjax.design`;
crash-test occupant risk (MASH, EN 1317) in `barrierjax.assess`.
"""

# `_xla_flags` first: it sets XLA_FLAGS before JAX's backend starts.
from . import _xla_flags, beam, hinge, materials  # noqa: F401
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
from .scene_file import load_scene
from .simulate import History, Result, simulate

from . import assess, design  # noqa: E402  (after simulate, which they build on)

__all__ = [
    "Barrier",
    "Dimensionless",
    "History",
    "Impact",
    "Result",
    "Scales",
    "Scene",
    "Vehicle",
    "assess",
    "beam",
    "broadcast_scene",
    "design",
    "dimensionless",
    "hinge",
    "load_scene",
    "materials",
    "simulate",
]
