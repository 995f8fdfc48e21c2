"""Viscoplastic beams (report chapter 4): sections, the dynamic yield surface, and the
incremental elastic-viscoplastic beam element.

- `section`: viscoplastic rectangular sections at constant rates (4.1): moment-curvature,
  combined bending and extension, the dynamic yield surface.
- `layered`, `element`, `model`, `integrate`: the layered section (4.2.14)-(4.2.19), the
  corotational Hermite beam element, assembly, and Newmark time integration (the report's
  linear-acceleration scheme and stable ones) in `lax.scan`.
- `report_example(n, ...)`: the cantilever Examples 1-3 of 4.3.
- `parkes_cantilever`: Parkes's rigid-plastic cantilever with a tip mass (a reference).
"""

from . import element, integrate, layered, model, section
from .examples import CantileverResult, TipRest, report_example, tip_rest
from .parkes import ParkesCantilever, parkes_cantilever

__all__ = [
    "CantileverResult",
    "ParkesCantilever",
    "TipRest",
    "element",
    "integrate",
    "layered",
    "model",
    "parkes_cantilever",
    "report_example",
    "section",
    "tip_rest",
]
