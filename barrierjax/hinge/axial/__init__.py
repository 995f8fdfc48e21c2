"""Report 3.4's dynamic model: a vehicle striking a beam held against axial motion.

- `stages`: the beam stage (3.4.23)-(3.4.40) in the speed-free variables of 3.2, and the
  hand-over to the plastic string (3.4.46) where N reaches N0 (the string itself is
  `barrierjax.hinge.string`);
- `api`: `axial_impact`, which returns the `NormalImpact` of report 3.2.

The static collapse of 3.4 is `barrierjax.hinge.static_collapse`.
"""

from .api import axial_impact

__all__ = ["axial_impact"]
