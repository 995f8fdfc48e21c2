"""The report's figures, recomputed (the scanned report keeps only their captions).

`FIGURES` maps a figure number ("3.2.2") to its caption and a function returning a
`matplotlib.figure.Figure`; `write_figures` writes them as `fig_3_2_2.png`, ... and is
what `barrierjax figures` runs. The registry is `barrierjax.figures.registry`; each chapter
module registers its figures there on import, and this package imports them in the
report's order of the figures it lists:

- `chapter2`: 2.2, 2.3, constitutive laws (figures the report does not have);
- `chapter3_elastic`: 3.1, 3.5, elastic impact (likewise);
- `chapter3_normal`: 3.2.2-3.2.4, normal impact;
- `chapter3_oblique`: 3.3.3-3.3.6, oblique impact;
- `chapter3_axial`: 3.4.2-3.4.5 and 3.4.9, axial force;
- `chapter4`: 4.1.2, 4.1.3, 4.1.7, viscoplastic sections, and 4.3.2-4.3.7, the cantilever
  examples.

Each module's docstring says what its figures show and how they were checked.
"""

from __future__ import annotations

# The order of these imports is the order of `FIGURES` (`barrierjax figures` lists it):
# keep it, not the alphabetical one.
# isort: off
from . import chapter2  # noqa: F401  (imported to register its figures; likewise below)
from . import chapter3_elastic  # noqa: F401
from . import chapter3_normal  # noqa: F401
from . import chapter3_oblique  # noqa: F401
from . import chapter3_axial  # noqa: F401
from . import chapter4  # noqa: F401

# isort: on
from .chapter3_normal import damage_bound
from .chapter3_oblique import final_hinge, steady_state
from .chapter4 import example_runs
from .registry import FIGURES, FigureEntry, figure, filename, title, write_figures

__all__ = [
    "FIGURES",
    "FigureEntry",
    "damage_bound",
    "example_runs",
    "figure",
    "filename",
    "final_hinge",
    "steady_state",
    "title",
    "write_figures",
]
