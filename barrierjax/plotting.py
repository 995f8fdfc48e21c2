"""Plots of a `Result`'s histories, in SI units, with matplotlib (no pyplot, no display).

Each function takes a `barrierjax.Result` from `simulate` (with its history) and returns
a `matplotlib.figure.Figure`; `save` writes one as PNG. Figures are built on
`matplotlib.figure.Figure` directly, so nothing here touches pyplot's global state or
needs a display: it works the same under the Agg backend, in a test, or in a notebook.

A normal impact (report 3.2) is drawn as `histories_figure` and `deflected_shape_figure`
(`RUN_PLOTS`); an oblique one (report 3.3) as the same two, drawn for a load that moves
along the barrier, and `path_figure`, the vehicle's path in plan (`OBLIQUE_RUN_PLOTS`).
`run_plots(result)` picks the set, `write_run_plots` writes it.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

__all__ = [
    "OBLIQUE_RUN_PLOTS",
    "RUN_PLOTS",
    "deflected_shape_figure",
    "dense_times",
    "draw_plan",
    "first_free",
    "hermite",
    "histories_figure",
    "is_oblique",
    "label_axes",
    "nearest_samples",
    "oblique_deflected_shape_figure",
    "oblique_histories_figure",
    "path_figure",
    "run_plots",
    "save",
    "shape_times",
    "write_run_plots",
]

_MS = 1e3  # s -> ms
_MM = 1e3  # m -> mm
_KN = 1e-3  # N -> kN

# The run plots' margins (`Figure.subplots_adjust`, fractions of the figure), fixed: those
# constrained layout gave them on the example scenes, with room to spare for wider tick
# labels. Constrained layout measures every artist before the figure is drawn, a third of
# the time `barrierjax run` spends on its plots (0.25 of 0.75 s, 2 cores), and these
# figures hold the same labels and legends whatever the scene.
_FOUR_PANELS = {"left": 0.065, "right": 0.99, "bottom": 0.07, "top": 0.95, "wspace": 0.18,
                "hspace": 0.08}  # fmt: skip
_ONE_PANEL = {"left": 0.07, "right": 0.99, "bottom": 0.10, "top": 0.92}
_PLAN = {"left": 0.10, "right": 0.815, "bottom": 0.09, "top": 0.875}
_TITLE_HEIGHT = 0.2  # inches above the axes that a figure's title takes


def _lay_out(fig: Figure, title: str | None, margins: dict) -> None:
    """`fig`'s title, if any, and its fixed `margins`; without a title the axes reach up
    into its room."""
    top = margins["top"]
    if title:
        fig.suptitle(title)
    else:
        top += _TITLE_HEIGHT / fig.get_figheight()
    fig.subplots_adjust(**{**margins, "top": min(top, 0.98)})


def is_oblique(result) -> bool:
    """Whether `result` is an oblique impact's (report 3.3, `ObliqueImpact` model)."""
    from .hinge.oblique import ObliqueImpact

    return isinstance(result.model, ObliqueImpact)


def _history(result):
    """The history as numpy arrays."""
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


def _label_line(ax, x, text, height=0.5, offset=4, **style):
    """A small grey label `offset` points right of the vertical line at data coordinate x,
    at `height` (a fraction of the axes' height)."""
    ax.annotate(
        text,
        xy=(x, height),
        xycoords=("data", "axes fraction"),
        xytext=(offset, 0),
        textcoords="offset points",
        fontsize=8,
        color="0.4",
        **style,
    )


def label_axes(ax, xlabel, ylabel, which="major", **legend):
    """Label `ax`'s axes, draw the light grid of every figure here (at the `which` ticks:
    "both" on log axes) and its legend, with the options `legend` (loc, fontsize, ...).
    Public: the report's figures (`barrierjax.figures`) are finished the same way."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which=which, alpha=0.3)
    ax.legend(**legend)


def histories_figure(result, title: str | None = None) -> Figure:
    """Four panels against time (ms): vehicle and barrier velocity (m/s), contact force
    (kN), hinge position (m) and the barrier's displacement under the vehicle (mm). The end
    of the accelerative phase (report 3.2, T*) is marked in each. An oblique impact is
    drawn by `oblique_histories_figure`."""
    if is_oblique(result):
        return oblique_histories_figure(result, title=title)
    h = _history(result)
    t = h["time"] * _MS
    t_star = float(result.model.t_star) * float(result.groups.scales.time) * _MS
    fig = Figure(figsize=(10, 7))
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
    w = hermite(fine, h["time"], h["barrier_displacement"], h["barrier_velocity"])
    ax.plot(fine * _MS, w * _MM, color="C4")
    ax.set_ylabel("displacement under vehicle (mm)")
    for ax in axes.flat:
        ax.axvline(t_star, color="0.6", linestyle=":", linewidth=1)
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time (ms)")
    _label_line(axes[0, 0], t_star, "end of accelerative phase", rotation=90, va="center")
    _lay_out(fig, title, _FOUR_PANELS)
    return fig


def nearest_samples(t, targets) -> np.ndarray:
    """Indices into the sample times `t` of distinct instants near `targets`: for each
    target in turn, the nearest sample not already taken, sorted in time (repeated
    sample times count once)."""
    t = np.asarray(t)
    _, candidates = np.unique(t, return_index=True)  # one index per distinct time
    chosen: list[int] = []
    for target in targets:
        free = [k for k in candidates if k not in chosen]
        if not free:
            break
        chosen.append(min(free, key=lambda k: abs(t[k] - target)))
    return np.array(sorted(chosen, key=lambda k: t[k]), dtype=int)


def shape_times(result, count: int = 6) -> np.ndarray:
    """Indices into the history of `count` distinct instants spread over the impact, from
    the end of the accelerative phase (T*) to rest: for each of `count` evenly spaced
    target times, the nearest sample not already taken."""
    t = np.asarray(result.history.time)
    start = float(result.model.t_star) * float(result.groups.scales.time)
    return nearest_samples(t, np.linspace(start, t[-1], count))


def _label_deflection(ax, xlabel, legend_loc):
    """Finish the axes of a deflected shape: the deflection (mm) against `xlabel`, drawn
    downwards (the barrier is pushed away from the traffic), with the legend at
    `legend_loc`."""
    ax.invert_yaxis()
    label_axes(ax, xlabel, "deflection (mm)", loc=legend_loc, fontsize=9)


def deflected_shape_figure(result, count: int = 6, title: str | None = None) -> Figure:
    """The barrier's deflected shape (mm) along its axis (m) at `count` instants; the
    shape is symmetric about the impact point, so x is mirrored to show both sides. The
    final hinge positions are marked. An oblique impact is drawn by
    `oblique_deflected_shape_figure`."""
    if is_oblique(result):
        return oblique_deflected_shape_figure(result, count=count, title=title)
    h = _history(result)
    x = h["x"]
    mirrored = np.concatenate([-x[::-1], x[1:]])
    fig = Figure(figsize=(10, 4.8))
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
    extent = float(result.hinge_position)
    for side in (-extent, extent):
        ax.axvline(side, color="0.5", linestyle=":", linewidth=1)
    _label_line(ax, extent, "final hinge")
    _label_deflection(ax, "distance along the barrier from the impact point (m)", "lower right")
    _lay_out(fig, title, _ONE_PANEL)
    return fig


# --------------------------------------------------------------------------------------
# Oblique impact (report 3.3): the load moves along the barrier, and the vehicle leaves.


def first_free(h) -> int:
    """Index of the first sample after contact (zero contact force) in a history `h` (a
    dict of arrays with "time" and "contact_force"): where the vehicle leaves, after a
    separation or with the barrier at rest; the last sample if none. Public: the oblique
    figures of `barrierjax.figures` mark the same sample."""
    free = np.flatnonzero(h["contact_force"] == 0.0)
    return int(free[0]) if free.size else h["time"].shape[0] - 1


def _oblique_marks(result, h):
    """(end of the crushing phase, separation time or None), in seconds."""
    t_star = float(result.model.t_star) * float(result.groups.scales.time)
    separated = bool(np.asarray(result.model.separated) > 0.5)
    return t_star, h["time"][first_free(h)] if separated else None


def _mark_phases(axes, t_star, t_sep):
    """Vertical lines at the end of crushing and at the separation, labelled at the top
    of the first axes."""
    marks = [(t_star, ":", "end of crushing")]
    if t_sep is not None:
        marks.append((t_sep, "--", "vehicle leaves"))
    for time, style, text in marks:
        for ax in axes:
            ax.axvline(time * _MS, color="0.6", linestyle=style, linewidth=1)
        _label_line(axes[0], time * _MS, text, height=0.97, offset=3, rotation=90, va="top")


def oblique_histories_figure(result, title: str | None = None) -> Figure:
    """Four panels against time (ms) for an oblique impact: the vehicle's velocity normal
    to the barrier and along it, and the barrier's under the vehicle (m/s); the contact
    force (kN); the distances from the contact point to the hinges ahead of and behind
    the vehicle (m); the barrier's displacement under the contact point and the vehicle's
    normal displacement, which exceeds it by the crush (mm). The end of the crushing
    phase (T*) is marked, and the separation where the vehicle leaves before the barrier
    stops."""
    h = _history(result)
    t = h["time"] * _MS
    t_star, t_sep = _oblique_marks(result, h)
    fig = Figure(figsize=(10, 7))
    axes = fig.subplots(2, 2, sharex=True)
    ax = axes[0, 0]
    ax.plot(t, h["vehicle_tangential_velocity"], label="vehicle, along the barrier")
    ax.plot(t, h["vehicle_velocity"], label="vehicle, towards the barrier")
    ax.plot(t, h["barrier_velocity"], label="barrier under the vehicle")
    ax.axhline(0.0, color="0.5", linewidth=0.8)
    ax.set_ylabel("velocity (m/s)")
    ax.legend(loc="center right", fontsize=8)
    ax = axes[0, 1]
    ax.plot(t, h["contact_force"] * _KN, color="C3")
    ax.set_ylabel("contact force (kN)")
    ax.set_ylim(bottom=0.0)
    ax = axes[1, 0]
    ax.plot(t, h["hinge_position"], color="C2", label="hinge ahead of the vehicle")
    ax.plot(t, h["rear_hinge_position"], color="C2", linestyle="--", label="hinge behind it")
    ax.set_ylabel("hinge distance from contact point (m)")
    ax.set_ylim(bottom=0.0)
    ax.legend(loc="lower right", fontsize=8)
    ax = axes[1, 1]
    ax.plot(t, h["barrier_displacement"] * _MM, color="C4", label="barrier under the contact point")
    ax.plot(
        t,
        h["vehicle_displacement"] * _MM,
        color="C4",
        linestyle="--",
        label="vehicle (barrier + crush)",
    )
    ax.set_ylabel("displacement towards the barrier (mm)")
    ax.legend(loc="lower right", fontsize=8)
    for ax in axes.flat:
        ax.grid(True, alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time (ms)")
    _mark_phases(list(axes.flat), t_star, t_sep)
    _lay_out(fig, title, _FOUR_PANELS)
    return fig


def oblique_deflected_shape_figure(result, count: int = 6, title: str | None = None) -> Figure:
    """The barrier's deflected shape (mm) along its axis (m, from the impact point, in
    the vehicle's direction of travel) at `count` instants from the end of the crushing
    phase to rest; a dot marks the contact point while the vehicle is on the barrier."""
    h = _history(result)
    x = h["x"]
    leave = first_free(h)
    fig = Figure(figsize=(10, 4.8))
    ax = fig.subplots()
    for n, k in enumerate(shape_times(result, count)):
        color = f"C{n % 10}"
        ax.plot(
            x,
            h["deflected_shape"][k] * _MM,
            color=color,
            label=f"t = {h['time'][k] * _MS:.1f} ms",
        )
        if k <= leave:
            ax.plot(h["vehicle_position"][k], h["barrier_displacement"][k] * _MM, "o", color=color)
    ax.plot([], [], "o", color="0.4", label="contact point")
    ax.axvline(0.0, color="0.3", linewidth=0.8)
    _label_line(ax, 0.0, "impact point", height=0.03, rotation=90, va="bottom")
    ax.annotate(
        "vehicle travels this way \u2192",
        xy=(0.98, 0.04),
        xycoords="axes fraction",
        ha="right",
        fontsize=8,
        color="0.4",
    )
    ax.set_ylim(bottom=0.0)
    _label_deflection(ax, "position along the barrier from the impact point (m)", "lower left")
    _lay_out(fig, title, _ONE_PANEL)
    return fig


def draw_plan(ax, x, shapes, labels, path, contact, marks, leave, approach, departure, span):
    """Draw a vehicle's path in plan on `ax`, in any one set of units; the normal axis
    points towards the barrier and is drawn downwards.

    - the barrier before impact (normal = 0), and deflected, `shapes[i]` on the grid `x`,
      labelled `labels[i]` and coloured C0, C1, ...;
    - `path = (along, normal)`: the vehicle's body, solid up to sample `leave` (where it
      leaves the barrier), then straight on at the velocity `departure`, and before
      impact at `approach` (both (along, normal) pairs, dashed, over the time `span`);
      a cross marks where it leaves;
    - `contact = (along, normal)`: the contact point (the vehicle's front, on the
      barrier) up to `leave`, with a dot at each sample of `marks` in the colour of the
      matching shape, on that shape.
    """
    along, normal = path
    ax.axhline(0.0, color="0.35", linewidth=2.5, alpha=0.35, label="barrier before impact")
    for n, (shape, label) in enumerate(zip(shapes, labels, strict=True)):
        ax.plot(x, shape, color=f"C{n % 10}", linewidth=1, label=label)
    dashed = {"color": "k", "linestyle": "--", "linewidth": 1}
    ax.plot([-approach[0] * span, 0.0], [-approach[1] * span, 0.0], **dashed)
    ax.plot(along[: leave + 1], normal[: leave + 1], color="k", linewidth=1.8, label="vehicle")
    end = (along[leave], normal[leave])
    ax.plot(
        [end[0], end[0] + departure[0] * span], [end[1], end[1] + departure[1] * span], **dashed
    )
    ax.plot(
        contact[0][: leave + 1],
        contact[1][: leave + 1],
        color="0.45",
        linewidth=1,
        label="contact point",
    )
    for n, k in enumerate(marks):
        if k <= leave:
            point = (contact[0][k], contact[1][k])
            ax.plot(*point, "o", color=f"C{n % 10}", markeredgecolor="k", markersize=6)
    ax.plot(*end, "X", color="C3", markersize=10, markeredgecolor="k", label="vehicle leaves")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()


def path_figure(result, count: int = 6, title: str | None = None) -> Figure:
    """The vehicle's path in plan: its lateral position (mm, towards the barrier, drawn
    downwards) against its position along the barrier from the impact point (m), with the
    barrier before impact, the deflected barrier at the `count` instants of
    `deflected_shape_figure` (a dot marks the contact point then), the approach and the
    departure (dashed), and the point where the vehicle leaves: at separation, or where
    the barrier stops. The vehicle's line is its body, which moves the crush further than
    the contact point (grey). The lateral scale is exaggerated, so the impact and exit
    speeds and angles are written out: the lines' slopes are not the angles."""
    h = _history(result)
    leave = first_free(h)
    marks = shape_times(result, count)
    t = h["time"]
    approach = (float(h["vehicle_tangential_velocity"][0]), float(h["vehicle_velocity"][0]))
    departure = (
        float(h["vehicle_tangential_velocity"][leave]),
        float(h["vehicle_velocity"][leave]),
    )
    fig = Figure(figsize=(10, 5.5))
    ax = fig.subplots()
    draw_plan(
        ax,
        h["x"],
        h["deflected_shape"][marks] * _MM,
        [f"barrier at t = {t[k] * _MS:.1f} ms" for k in marks],
        (h["vehicle_position"], h["vehicle_displacement"] * _MM),
        (h["vehicle_position"], h["barrier_displacement"] * _MM),
        marks,
        leave,
        (approach[0], approach[1] * _MM),
        (departure[0], departure[1] * _MM),
        0.3 * float(t[leave]),
    )
    separated = bool(np.asarray(result.model.separated) > 0.5)
    how = "separates from the moving barrier" if separated else "leaves as the barrier stops"
    speed_in, exit_speed = float(np.hypot(*approach)), float(result.exit_speed)
    ax.set_title(
        f"impact: {speed_in:.1f} m/s ({speed_in * 3.6:.0f} km/h) at "
        f"{float(np.degrees(np.arctan2(approach[1], approach[0]))):.1f}\u00b0 to the barrier; "
        f"vehicle crush {float(result.damage) * _MM:.0f} mm\n"
        f"the vehicle {how} at t = {t[leave] * _MS:.1f} ms: "
        f"{exit_speed:.1f} m/s ({exit_speed * 3.6:.0f} km/h) at "
        f"{float(result.exit_angle_deg):.1f}\u00b0 away from the barrier",
        loc="left",
        fontsize=9,
    )
    label_axes(
        ax,
        "position along the barrier from the impact point (m)",
        "lateral position, towards the barrier (mm)\n(scale exaggerated)",
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        fontsize=8,
    )
    _lay_out(fig, title, _PLAN)
    return fig


def save(fig: Figure, path, dpi: int = 120) -> Path:
    """Write `fig` to `path` as PNG (creating folders) and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    return path


# File name -> figure function, for `barrierjax run`: a normal impact, an oblique one.
RUN_PLOTS = {
    "histories.png": histories_figure,
    "deflected_shape.png": deflected_shape_figure,
}
OBLIQUE_RUN_PLOTS = {
    "path.png": path_figure,
    "deflected_shape.png": oblique_deflected_shape_figure,
    "histories.png": oblique_histories_figure,
}


def run_plots(result) -> dict:
    """`OBLIQUE_RUN_PLOTS` for an oblique impact's result, else `RUN_PLOTS`."""
    return OBLIQUE_RUN_PLOTS if is_oblique(result) else RUN_PLOTS


def write_run_plots(result, out_dir, title: str | None = None, progress=None) -> list[Path]:
    """Write the plots of `run_plots(result)` for `result` into `out_dir`;
    `progress(path)` is called before each file is written. Returns the paths."""
    paths = []
    for name, make in run_plots(result).items():
        path = Path(out_dir) / name
        if progress is not None:
            progress(path)
        paths.append(save(make(result, title=title), path))
    return paths
