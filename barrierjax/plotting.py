"""Plots of a `Result`'s histories, in SI units, with matplotlib (no pyplot, no display).

Each function takes a `barrierjax.Result` from `simulate` (with its history) and returns
a `matplotlib.figure.Figure`; `save` writes one as PNG. Figures are built on
`matplotlib.figure.Figure` directly, so nothing here touches pyplot's global state or
needs a display: it works the same under the Agg backend, in a test, or in a notebook.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

__all__ = [
    "RUN_PLOTS",
    "deflected_shape_figure",
    "dense_times",
    "hermite",
    "histories_figure",
    "save",
    "shape_times",
    "write_run_plots",
]

_MS = 1e3  # s -> ms
_MM = 1e3  # m -> mm
_KN = 1e-3  # N -> kN


def _history(result):
    if result.history is None:
        raise ValueError("the result has no history: call simulate(scene, n_history>=2)")
    h = result.history
    return {f.name: np.asarray(getattr(h, f.name)) for f in dataclasses.fields(h)}


def hermite(t_new, t, y, dydt):
    """Cubic Hermite interpolation of samples `y(t)` with slopes `dydt`, at `t_new`.

    Used to draw a displacement between the history's samples with its exact slope (the
    velocity), so that an uneven sampling does not show as corners; repeated sample
    times (the phase switch, the state at rest) are dropped."""
    t, first = np.unique(np.asarray(t), return_index=True)
    y, dydt = np.asarray(y)[first], np.asarray(dydt)[first]
    t_new = np.asarray(t_new)
    i = np.clip(np.searchsorted(t, t_new, side="right") - 1, 0, t.size - 2)
    h = t[i + 1] - t[i]
    s = (t_new - t[i]) / h
    return (
        (2 * s**3 - 3 * s**2 + 1) * y[i]
        + (s**3 - 2 * s**2 + s) * h * dydt[i]
        + (-2 * s**3 + 3 * s**2) * y[i + 1]
        + (s**3 - s**2) * h * dydt[i + 1]
    )


def dense_times(t, count: int = 800) -> np.ndarray:
    """The sample times `t` together with `count` evenly spaced ones over their range."""
    t = np.asarray(t)
    return np.union1d(t, np.linspace(t[0], t[-1], count))


def _label_line(ax, x, text, **style):
    """A small grey label just right of the vertical line at data coordinate x."""
    ax.annotate(
        text,
        xy=(x, 0.5),
        xycoords=("data", "axes fraction"),
        xytext=(4, 0),
        textcoords="offset points",
        fontsize=8,
        color="0.4",
        **style,
    )


def histories_figure(result, title: str | None = None) -> Figure:
    """Four panels against time (ms): vehicle and barrier velocity (m/s), contact force
    (kN), hinge position (m) and the barrier's displacement under the vehicle (mm). The end
    of the accelerative phase (report 3.2, T*) is marked in each."""
    h = _history(result)
    t = h["time"] * _MS
    t_star = float(result.model.t_star) * float(result.groups.scales.time) * _MS
    fig = Figure(figsize=(10, 7), layout="constrained")
    axes = fig.subplots(2, 2, sharex=True)
    ax = axes[0, 0]
    ax.plot(t, h["vehicle_velocity"], label="vehicle")
    ax.plot(t, h["barrier_velocity"], label="barrier at impact point")
    ax.set_ylabel("velocity (m/s)")
    ax.legend(loc="upper right")
    ax = axes[0, 1]
    ax.plot(t, h["contact_force"] * _KN, color="C3")
    ax.set_ylabel("contact force (kN)")
    ax.set_ylim(bottom=0.0)
    ax = axes[1, 0]
    ax.plot(t, h["hinge_position"], color="C2")
    ax.set_ylabel("hinge position from impact point (m)")
    ax.set_ylim(bottom=0.0)
    ax = axes[1, 1]
    fine = dense_times(h["time"])
    w = hermite(fine, h["time"], h["displacement"], h["barrier_velocity"])
    ax.plot(fine * _MS, w * _MM, color="C4")
    ax.set_ylabel("displacement under vehicle (mm)")
    for ax in axes.flat:
        ax.axvline(t_star, color="0.6", linestyle=":", linewidth=1)
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time (ms)")
    _label_line(axes[0, 0], t_star, "end of accelerative phase", rotation=90, va="center")
    if title:
        fig.suptitle(title)
    return fig


def shape_times(result, count: int = 6) -> np.ndarray:
    """Indices into the history of `count` distinct instants spread over the impact, from
    the end of the accelerative phase (T*) to rest: for each of `count` evenly spaced
    target times, the nearest sample not already taken."""
    t = np.asarray(result.history.time)
    start = float(result.model.t_star) * float(result.groups.scales.time)
    targets = np.linspace(start, t[-1], count)
    _, candidates = np.unique(t, return_index=True)  # one index per distinct time
    chosen: list[int] = []
    for target in targets:
        free = [k for k in candidates if k not in chosen]
        if not free:
            break
        chosen.append(min(free, key=lambda k: abs(t[k] - target)))
    return np.array(sorted(chosen, key=lambda k: t[k]), dtype=int)


def deflected_shape_figure(result, count: int = 6, title: str | None = None) -> Figure:
    """The barrier's deflected shape (mm) along its axis (m) at `count` instants; the
    shape is symmetric about the impact point, so x is mirrored to show both sides. The
    final hinge positions are marked."""
    h = _history(result)
    x = h["x"]
    mirrored = np.concatenate([-x[::-1], x[1:]])
    fig = Figure(figsize=(10, 4.8), layout="constrained")
    ax = fig.subplots()
    colors = [f"C{k}" for k in range(10)]
    for n, k in enumerate(shape_times(result, count)):
        w = h["deflected_shape"][k]
        ax.plot(
            mirrored,
            np.concatenate([w[::-1], w[1:]]) * _MM,
            color=colors[n % 10],
            label=f"t = {h['time'][k] * _MS:.1f} ms",
        )
    extent = float(result.hinge_extent)
    for side in (-extent, extent):
        ax.axvline(side, color="0.5", linestyle=":", linewidth=1)
    _label_line(ax, extent, "final hinge")
    ax.invert_yaxis()  # the barrier is pushed away from the traffic, drawn downwards
    ax.set_xlabel("distance along the barrier from the impact point (m)")
    ax.set_ylabel("deflection (mm)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower right", fontsize=9)
    if title:
        fig.suptitle(title)
    return fig


def save(fig: Figure, path, dpi: int = 120) -> Path:
    """Write `fig` to `path` as PNG (creating folders) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


# File name -> figure function, for `barrierjax run`.
RUN_PLOTS = {
    "histories.png": histories_figure,
    "deflected_shape.png": deflected_shape_figure,
}


def write_run_plots(result, out_dir, title: str | None = None, progress=None) -> list[Path]:
    """Write the plots of `RUN_PLOTS` for `result` into `out_dir`; `progress(path)` is
    called before each file is written. Returns the paths."""
    paths = []
    for name, make in RUN_PLOTS.items():
        path = Path(out_dir) / name
        if progress is not None:
            progress(path)
        paths.append(save(make(result, title=title), path))
    return paths
