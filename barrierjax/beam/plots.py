"""Plots of cantilever runs (`CantileverResult`, report 4.3), in the report's inch-pound units.

Each function takes `results`, a dict from a label to a `CantileverResult` (one run, or several
to compare, e.g. the rate-dependent law and its rate-independent limit), and returns a
`matplotlib.figure.Figure`; the first result is drawn solid, the others dashed. They draw the
figures 4.3.2-4.3.7 of `barrierjax figures` and the plots of `barrierjax run cantilever-N`
(`write_cantilever_plots`).
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ..plotting import save
from .examples import tip_rest

__all__ = [
    "deformed_shape",
    "root_figure",
    "shape_figure",
    "tip_figure",
    "write_cantilever_plots",
]

_MS = 1e3  # s -> ms
_STYLES = ("-", "--", ":", "-.")


def deformed_shape(result, k: int, points_per_element: int = 12) -> np.ndarray:
    """The beam's axis at saved time `k` as (n, 2) points (in): each element drawn as the
    cubic Hermite curve between its nodes with the nodes' rotations as end slopes (the
    element's own transverse interpolation, 4.2.28), for a beam laid along +X."""
    nodes = np.asarray(result.node_coordinates[k])
    rotation = np.asarray(result.history.displacement[k])[2::3]
    tangent = np.stack([np.cos(rotation), np.sin(rotation)], axis=-1)
    s = np.linspace(0.0, 1.0, points_per_element)[:, None]
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    pieces = []
    for i in range(len(nodes) - 1):
        chord = np.linalg.norm(nodes[i + 1] - nodes[i])
        piece = (
            h00 * nodes[i]
            + h10 * chord * tangent[i]
            + h01 * nodes[i + 1]
            + h11 * chord * tangent[i + 1]
        )
        pieces.append(piece if i == 0 else piece[1:])
    return np.concatenate(pieces)


def _rest_index(result) -> int:
    """The saved time nearest the tip's rest (the last one if it does not come to rest)."""
    rest = tip_rest(result)
    if rest.index < 0:
        return len(result.times) - 1
    times = np.asarray(result.times)
    before, after = rest.index - 1, rest.index
    return before if rest.time - times[before] < times[after] - rest.time else after


def shape_figure(results: dict, count: int = 6, title: str | None = None) -> Figure:
    """The deformed beam: the first result at `count` times from the start to the tip's
    rest (thin), and each result's configuration at its tip's rest (thick), at the largest
    deflection: the report's "final configuration corresponding to zero velocity of the
    tip". Drawn to scale where the tip deflects by more than a fifth of the length, else with
    the deflection magnified."""
    fig = Figure(figsize=(7.5, 6.5), layout="constrained")
    ax = fig.subplots()
    first = next(iter(results.values()))
    times = np.asarray(first.times)
    last = _rest_index(first)
    targets = np.linspace(0.0, times[last], count + 1)[:-1]
    for k in np.unique(np.abs(times[:, None] - targets).argmin(axis=0)):
        shape = deformed_shape(first, k)
        ax.plot(*shape.T, color="0.6", lw=0.8)
        ax.annotate(
            f"{float(first.times[k]) * _MS:.3g} ms",
            shape[-1],
            fontsize=7,
            color="0.4",
            xytext=(3, 0),
            textcoords="offset points",
        )
    for n, (label, result) in enumerate(results.items()):
        k = _rest_index(result)
        shape = deformed_shape(result, k)
        rest = tip_rest(result)
        when = (
            f"tip at rest at {rest.time * _MS:.1f} ms, {rest.tip_displacement[1]:.3g} in"
            if rest.index >= 0
            else f"end of run, {float(result.times[k]) * _MS:.1f} ms (tip still moving)"
        )
        ax.plot(*shape.T, color=f"C{n}", lw=2.2, ls=_STYLES[n % 4], label=f"{label}: {when}")
        ax.plot(*np.asarray(result.node_coordinates[k]).T, "o", color=f"C{n}", ms=3)
    length = float(np.asarray(first.node_coordinates[0, -1, 0]))
    low, high = ax.get_ylim()
    to_scale = high > 0.2 * length
    ax.plot([0, 0], [-0.04 * (high - low), 0.04 * (high - low)], color="k", lw=4)
    if to_scale:
        ax.set_aspect("equal")
    ax.set_xlabel("x (in), along the undeformed beam from the clamped root")
    ax.set_ylabel("y (in), the direction of the impulse" + ("" if to_scale else " (magnified)"))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    if title:
        fig.suptitle(title)
    return fig


def _mark_rest(ax, result, style):
    rest = tip_rest(result)
    if rest.index >= 0:
        ax.axvline(rest.time * _MS, color="0.5", lw=0.8, ls=style)


def tip_figure(results: dict, title: str | None = None) -> Figure:
    """The tip's axial and transverse displacements (in) and velocities (in/s) against time
    (ms); grey lines mark the tip's rest at its largest deflection."""
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    displacement, velocity = fig.subplots(1, 2)
    for n, (label, result) in enumerate(results.items()):
        t = np.asarray(result.times) * _MS
        style = _STYLES[n % 4]
        for j, (component, color) in enumerate((("axial", "C0"), ("transverse", "C3"))):
            name = f"{component}, {label}"
            displacement.plot(
                t, np.asarray(result.tip_displacement[:, j]), color, ls=style, label=name
            )
            velocity.plot(t, np.asarray(result.tip_velocity[:, j]), color, ls=style, label=name)
        for ax in (displacement, velocity):
            _mark_rest(ax, result, style)
    displacement.set_ylabel("tip displacement (in)")
    velocity.set_ylabel("tip velocity (in/s)")
    for ax in (displacement, velocity):
        ax.set_xlabel("time (ms)")
        ax.axhline(0.0, color="k", lw=0.6)
        ax.grid(True, alpha=0.3)
    displacement.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    return fig


def root_figure(results: dict, plastic_moment: float, title: str | None = None) -> Figure:
    """At the clamped root: the moment over the static plastic moment `plastic_moment`
    (lb in), and the rotation of the first element's chord (rad), against time (ms)."""
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    moment, rotation = fig.subplots(1, 2)
    for n, (label, result) in enumerate(results.items()):
        t = np.asarray(result.times) * _MS
        style = _STYLES[n % 4]
        moment.plot(
            t, np.asarray(result.root_moment) / plastic_moment, f"C{n}", ls=style, label=label
        )
        rotation.plot(t, np.asarray(result.root_rotation), f"C{n}", ls=style, label=label)
        for ax in (moment, rotation):
            _mark_rest(ax, result, style)
    moment.axhline(1.0, color="k", lw=0.6, ls=":")
    moment.set_ylabel("root moment / static plastic moment M0")
    rotation.set_ylabel("root rotation (rad), first element's chord")
    for ax in (moment, rotation):
        ax.set_xlabel("time (ms)")
        ax.grid(True, alpha=0.3)
    moment.legend(fontsize=8)
    if title:
        fig.suptitle(title)
    return fig


def write_cantilever_plots(
    results: dict, plastic_moment: float, out_dir, title: str | None = None, progress=None
) -> list[Path]:
    """Write deformed_shape.png, tip_histories.png and root_histories.png for `results` into
    `out_dir`; `progress(path)` is called before each file is written. Returns the paths."""
    plots = {
        "deformed_shape.png": partial(shape_figure, results, title=title),
        "tip_histories.png": partial(tip_figure, results, title=title),
        "root_histories.png": partial(root_figure, results, plastic_moment, title=title),
    }
    paths = []
    for name, make in plots.items():
        path = Path(out_dir) / name
        if progress is not None:
            progress(path)
        paths.append(save(make(), path))
    return paths
