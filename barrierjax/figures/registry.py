"""The registry of the report's figures: `FIGURES` maps a figure number ("3.2.2") to its
caption and a function returning a `matplotlib.figure.Figure`; `write_figures` writes them
as `fig_3_2_2.png`, ... A chapter module adds its figures with

    @figure("3.3.2", "Caption as printed in the report")
    def _figure_3_3_2() -> Figure: ...

and titles each with `title(fig, "3.3.2", subtitle)`. The registry keeps the order in
which the figures were registered (the order in which `barrierjax.figures` imports the
chapter modules): `barrierjax figures` lists and writes them in that order.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from pathlib import Path
from typing import NamedTuple

from matplotlib.figure import Figure

from .. import plotting

__all__ = ["FIGURES", "FigureEntry", "figure", "filename", "title", "write_figures"]


class FigureEntry(NamedTuple):
    """A figure of the report: its `caption` and the function that draws it; `printed` is
    False where the scan lost the caption and it was composed from the report's text, and
    `added` True where the report has no figure: the key is then the section it shows."""

    caption: str
    make: Callable[[], Figure]
    printed: bool = True
    added: bool = False


FIGURES: dict[str, FigureEntry] = {}


def figure(number: str, caption: str, *, printed: bool = True, added: bool = False):
    """Register the decorated function as the report's figure `number` (with `added`, a
    figure of section `number` that the report does not have)."""

    def register(make):
        FIGURES[number] = FigureEntry(caption, make, printed and not added, added)
        return make

    return register


def filename(number: str) -> str:
    """ "3.2.2" -> "fig_3_2_2.png"."""
    return "fig_" + number.replace(".", "_") + ".png"


def write_figures(
    out_dir, numbers: Iterable[str] | None = None, progress=None, dpi: int = 120
) -> list[Path]:
    """Write the figures `numbers` (default: all of `FIGURES`) into `out_dir` as PNGs;
    `progress(path)` is called before each. Returns the paths written."""
    paths = []
    for number in FIGURES if numbers is None else numbers:
        path = Path(out_dir) / filename(number)
        if progress is not None:
            progress(path)
        paths.append(plotting.save(FIGURES[number].make(), path, dpi=dpi))
    return paths


def title(fig: Figure, number: str, subtitle: str = "") -> None:
    """Set `fig`'s suptitle to "Figure `number`  caption" from `FIGURES`, with a line saying
    when the figure is not the report's (`added`) or its caption was composed (not
    `printed`), and `subtitle` (if any) below. Every chapter module titles its figures with
    it."""
    entry = FIGURES[number]
    lines = [f"Figure {number}  {entry.caption}"]
    if entry.added:
        lines.append("(not a figure of the report: added to show its section " + number + ")")
    elif not entry.printed:
        lines.append("(caption lost from the scan; composed from the report's text)")
    if subtitle:
        lines.append(subtitle)
    fig.suptitle("\n".join(lines), fontsize=12)
