"""barrierjax: differentiable impact-dynamics models for highway barriers, in JAX."""

from . import hinge

__all__ = ["hinge"]
