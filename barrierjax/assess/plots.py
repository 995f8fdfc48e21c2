"""Plots of a crash-test record's assessment (matplotlib `Figure`s, no pyplot): the
conditioned accelerations, the occupant's flail-space path with its impact point, and the
ASI history. `write_assessment_plots` writes the three as PNG files."""

from pathlib import Path

import jax
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from . import asi, flail
from .flail import FLAIL_X, FLAIL_Y
from .matrices import G

__all__ = ["accelerations_figure", "asi_figure", "flail_space_figure", "write_assessment_plots"]

_MS = 1e3

# The curves drawn, each one program (run operation by operation, they were some fifty
# small programs to compile in each new process).
_conditioned = jax.jit(asi.conditioned_accelerations, static_argnames=("dt", "edition"))
_occupant_motion = jax.jit(flail.occupant_motion, static_argnames="dt")
_asi_history = jax.jit(asi.asi_history, static_argnames=("dt", "edition"))


def accelerations_figure(record, risk, asi_edition: str = "2010") -> Figure:
    """The record's accelerations (in g) as assessed, and as the ASI reads them."""
    t = record.t * _MS
    channels = {"ax": record.ax, "ay": record.ay}
    if record.az is not None:
        channels["az"] = record.az
    stacked = np.stack(list(channels.values()))
    smoothed = np.asarray(_conditioned(stacked, dt=record.dt, edition=asi_edition))
    fig = Figure(figsize=(8, 4.5), layout="constrained")
    ax = fig.add_subplot()
    for (name, values), smooth, color in zip(channels.items(), smoothed, ("C0", "C1", "C2")):
        ax.plot(t, values / G, color=color, lw=0.8, alpha=0.5, label=f"{name}")
        ax.plot(t, smooth / G, color=color, lw=1.6, label=f"{name}, as the ASI reads it")
    for when, label in ((risk.t_impact, "occupant impact"), (risk.t_head, "head impact")):
        if np.isfinite(when):
            ax.axvline(
                float(when) * _MS,
                color="0.4",
                ls="--" if "occupant" in label else ":",
                lw=1,
                label=label,
            )
    ax.set(xlabel="time (ms)", ylabel="acceleration (g)", title="Vehicle accelerations")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    return fig


def flail_space_figure(record, risk) -> Figure:
    """The occupant's path relative to the vehicle in plan, inside the flail space."""
    position, _ = _occupant_motion(np.asarray(record.ax), np.asarray(record.ay), dt=record.dt)
    position = np.asarray(position)
    t_impact = float(risk.t_impact)
    before = record.t <= t_impact
    fig = Figure(figsize=(6, 6.5), layout="constrained")
    ax = fig.add_subplot()
    box = Rectangle((-FLAIL_Y, -FLAIL_X), 2 * FLAIL_Y, 2 * FLAIL_X, fill=False, ec="0.3", ls="--")
    box.set_label("flail space (0.6 m, 0.3 m)")
    ax.add_patch(box)
    ax.plot(
        -position[before, 1],
        position[before, 0],
        color="C0",
        label="occupant, relative to the vehicle",
    )
    if np.isfinite(t_impact):
        x, y = float(position[before, 0][-1]), float(position[before, 1][-1])
        ax.plot(
            -y,
            x,
            "o",
            color="C3",
            label=f"impact at {t_impact * _MS:.1f} ms: "
            f"OIV {abs(float(risk.oiv_x)):.2f} m/s x, {abs(float(risk.oiv_y)):.2f} m/s y",
        )
    ax.set(xlabel="to the right (m)", ylabel="forward (m)", aspect="equal", title="Flail space")
    ax.grid(alpha=0.3)
    fig.legend(fontsize=8, loc="outside lower center")
    return fig


def asi_figure(record, risk, asi_edition: str = "2010") -> Figure:
    """ASI(t), its maximum and the EN 1317-2 class bounds."""
    history = np.asarray(
        _asi_history(record.ax, record.ay, record.az, dt=record.dt, edition=asi_edition)
    )
    fig = Figure(figsize=(8, 4), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(record.t * _MS, history, color="C0", label=f"ASI(t), EN 1317-1:{asi_edition}")
    for bound, name in ((1.0, "A"), (1.4, "B"), (1.9, "C")):
        ax.axhline(bound, color="0.5", lw=0.8, ls=":")
        ax.text(record.t[-1] * _MS, bound, f" {name}", va="center", fontsize=8)
    ax.axhline(float(risk.asi), color="C3", lw=1, ls="--", label=f"ASI = {float(risk.asi):.2f}")
    ax.set(xlabel="time (ms)", ylabel="ASI", title="Acceleration severity index")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return fig


def write_assessment_plots(record, risk, out_dir, asi_edition: str = "2010") -> list[Path]:
    """Write accelerations.png, flail_space.png and asi.png into `out_dir`."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    figures = {
        "accelerations.png": accelerations_figure(record, risk, asi_edition),
        "flail_space.png": flail_space_figure(record, risk),
        "asi.png": asi_figure(record, risk, asi_edition),
    }
    paths = []
    for name, fig in figures.items():
        fig.savefig(out_dir / name, dpi=120)
        paths.append(out_dir / name)
    return paths
