"""Plots of a system impact: the plan view at several times (rail, posts, vehicle outline),
the histories, and the plan view animated (a GIF, as the overhead film of a crash test).
Rail nodes are drawn at their initial abscissa with their lateral displacement."""

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from .barrier import Guardrail
from .impact import SystemResult
from .vehicle import Vehicle, outline

G = 9.80665


def _rail_x(barrier):
    return np.asarray(barrier.rail.coords[:, 0]) if isinstance(barrier, Guardrail) else None


def _plan(result: SystemResult, vehicle: Vehicle, barrier):
    """The function k -> the plan view's lines at history sample `k`, (x, y) each: the rail
    and its posts (a guardrail's), then the vehicle's outline (its rectangle, closed). The
    history, the outline and the rail are read into numpy once, not at every frame."""
    h = result.history
    position, yaw = np.asarray(h.position), np.asarray(h.yaw)
    body = np.asarray(outline(vehicle))
    body = np.vstack([body, body[:1]])
    x = _rail_x(barrier)
    if x is not None:
        lateral = np.asarray(h.rail_deflection)
        posts = np.asarray(barrier.post_nodes)

    def lines(k) -> list:
        c, s = np.cos(yaw[k]), np.sin(yaw[k])
        moved = body @ np.array([[c, s], [-s, c]]) + position[k]
        rail = [] if x is None else [(x, lateral[k]), (x[posts], lateral[k][posts])]
        return rail + [(moved[:, 0], moved[:, 1])]

    return lines


def _draw_plan(ax, plan, k, *, faded=False) -> list:
    """The plan view at history sample `k` drawn on `ax`: its lines (`plan`'s, `_plan`)."""
    alpha = 0.35 if faded else 1.0
    *rail, body = plan(k)
    styles = [dict(color="tab:blue", lw=1.5), dict(marker="s", ls="", ms=3, color="0.3")]
    drawn = [ax.plot(*xy, alpha=alpha, **style)[0] for xy, style in zip(rail, styles)]
    return drawn + ax.plot(*body, color="tab:red", alpha=alpha, lw=1.2)


def plan_view_figure(result: SystemResult, vehicle: Vehicle, barrier, *, snapshots=6,
                     title=None) -> Figure:  # fmt: skip
    """The plan view at `snapshots` equally spaced times (the last one solid), the c.g.'s
    path, the rail at its largest deflection, and the failed posts."""
    h = result.history
    fig = Figure(figsize=(11, 4.5), layout="constrained")
    ax = fig.add_subplot()
    n = h.time.shape[0]
    picks = np.linspace(0, n - 1, snapshots).round().astype(int)
    plan = _plan(result, vehicle, barrier)
    for k in picks:
        _draw_plan(ax, plan, k, faded=k != picks[-1])
        t = float(h.time[k])
        ax.annotate(f"{t * 1e3:.0f} ms", np.asarray(h.position[k]), fontsize=7, color="tab:red")
    ax.plot(np.asarray(h.position[:, 0]), np.asarray(h.position[:, 1]), ":", color="tab:red",
            lw=0.8, label="c.g. path")  # fmt: skip
    x = _rail_x(barrier)
    if x is not None:
        peak = int(np.argmax(np.max(np.asarray(h.rail_deflection), axis=1)))
        ax.plot(x, np.asarray(h.rail_deflection[peak]), "--", color="tab:blue",
                label=f"rail at its largest deflection ({float(result.dynamic_deflection):.2f} m)")  # fmt: skip
        failed = np.asarray(barrier.post_nodes)[np.asarray(result.failed_posts)]
        if failed.size:
            ax.plot(x[failed], np.zeros(failed.size), "x", color="k", label="failed posts")
    else:
        ax.axhline(0.0, color="tab:blue", lw=2, label="rigid wall")
    ax.set_aspect("equal")
    ax.set_xlabel("along the barrier (m)")
    ax.set_ylabel("lateral, towards the field side (m)")
    ax.legend(loc="lower right", fontsize=8)
    if title:
        ax.set_title(title)
    return fig


def histories_figure(result: SystemResult, *, title=None) -> Figure:
    """The vehicle's accelerations (its axes), yaw rate and speed; the contact force and the
    rail's largest tension; the rail's largest deflection; the energy audit's remainder."""
    h = result.history
    t = np.asarray(h.time) * 1e3
    fig = Figure(figsize=(11, 7), layout="constrained")
    axes = fig.subplots(3, 2, sharex=True).ravel()
    acc = np.asarray(h.acceleration) / G
    axes[0].plot(t, acc[:, 0], label="longitudinal")
    axes[0].plot(t, acc[:, 1], label="lateral")
    axes[0].set_ylabel("c.g. acceleration (g)")
    axes[0].legend(fontsize=8)
    axes[1].plot(t, np.degrees(np.asarray(h.yaw_rate)))
    axes[1].set_ylabel("yaw rate (deg/s)")
    axes[2].plot(t, np.hypot(*np.asarray(h.velocity).T) * 3.6)
    axes[2].set_ylabel("speed (km/h)")
    axes[3].plot(t, np.asarray(h.contact_force) / 1e3, label="contact force")
    tension = np.asarray(h.rail_tension)
    if tension.shape[-1]:
        axes[3].plot(t, np.max(tension, axis=1) / 1e3, label="largest rail tension")
    axes[3].set_ylabel("force (kN)")
    axes[3].legend(fontsize=8)
    axes[4].plot(t, np.max(np.asarray(h.rail_deflection), axis=1) * 1e3)
    axes[4].set_ylabel("largest rail deflection (mm)")
    axes[5].plot(t, np.asarray(h.energy_error))
    axes[5].set_ylabel("energy audit remainder / KE0")
    for ax in axes[4:]:
        ax.set_xlabel("time (ms)")
    if title:
        fig.suptitle(title)
    return fig


def animate_plan_view(result: SystemResult, vehicle: Vehicle, barrier, path, *, frames=60,
                      fps=15, title=None) -> Path:  # fmt: skip
    """The plan view, animated, written as a GIF to `path` (Pillow's writer).

    The axes, their ticks and the layout are rendered once; each frame restores that
    image and draws the moving lines and the title on it (`draw_artist`): drawing every
    frame whole, its axes' text laid out anew each time, took most of the 3.1 s that 60
    frames took. Each frame's 256 colours by Pillow's maximum coverage (within 5 of 255
    of the rendered frame's, which holds 500-1,000 where its text is smoothed); its
    median cut, the GIF writer's default, took 0.9 s of the 60 frames."""
    h = result.history
    picks = np.linspace(0, h.time.shape[0] - 1, frames).round().astype(int)
    fig = Figure(figsize=(9, 3.6), layout="constrained")
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    positions = np.asarray(h.position)
    x = _rail_x(barrier)
    lateral = np.asarray(h.rail_deflection)
    low = min(positions[:, 1].min(), 0.0) - 3.0
    high = max(lateral.max() if x is not None else 0.0, 0.0) + 1.0
    left = positions[:, 0].min() - 4.0
    right = positions[:, 0].max() + 4.0

    ax.set_xlim(left, right)
    ax.set_ylim(low, high)
    ax.set_aspect("equal")
    plan = _plan(result, vehicle, barrier)
    lines = _draw_plan(ax, plan, picks[0])
    times = np.asarray(h.time)
    label = lambda k: (title + ": " if title else "") + f"{times[k] * 1e3:.0f} ms"
    ax.set_title(label(picks[-1]))  # the layout leaves room for a title
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    moving = [*lines, ax.title]
    for artist in moving:
        artist.set_animated(True)  # left out of the background
    canvas.draw()
    background = canvas.copy_from_bbox(fig.bbox)

    images = []
    for k in picks:
        for line, xy in zip(lines, plan(k)):
            line.set_data(*xy)
        ax.title.set_text(label(k))
        canvas.restore_region(background)
        for artist in moving:
            fig.draw_artist(artist)
        rgba = Image.frombuffer("RGBA", canvas.get_width_height(), canvas.buffer_rgba())
        images.append(rgba.convert("RGB").quantize(method=Image.Quantize.MAXCOVERAGE))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    images[0].save(path, save_all=True, append_images=images[1:],
                   duration=round(1000 / fps), loop=0)  # fmt: skip
    return path
