"""Figures of report section 3.3, oblique impact (`barrierjax.hinge.oblique_impact`,
`moving_load`). The scan keeps the caption of 3.3.6 only; those of 3.3.3-3.3.5 are
composed from the text that cites them (registered with `printed=False`, and said so under
the figure's title). The text sets mu = 5 and phi = 2 "in all cases" of its examples (3.3.4-3.3.6); time is T and
speeds are over L/t0, as in 3.2.

- 3.3.3: hinge distances S1 (ahead of the load), S2 (behind it) and the barrier's velocity
  V0 under the load against T, for a constant force moving along the barrier (phi = 2,
  V_H = 1; the accelerative-phase equations (3.3.16) alone, by `moving_load`), with the
  steady state (3.3.18)-(3.3.19) dashed. The text's V_N = 1 does not enter a moving load:
  it is the vehicle's normal speed, and the vehicle crushes (the load stays P0) as long as
  its normal velocity V_N - 2T/mu exceeds that of the load point, V0 + theta V_H (drawn
  dotted), which stays below 0.5 here: the transition drawn, to T = 25, is that of a
  vehicle heavier than about mu = 50 (the mass ratio is not given; mu -> infinity is the
  moving load).
- 3.3.4: S1, S2, V0, the vehicle's normal velocity V_N and the contact force P/P_b against
  T, for mu = 5, phi = 2 and a vehicle speed of 0.6 at 15, 30 and 45 degrees to the
  barrier (V_N = 0.6 sin a, V_H = 0.6 cos a), one vmapped call. The grey line is the
  final hinge distance with R = 0, the positive root of the text's cubic
  s^3 + (3 - 2R) mu s^2 - 3s - 3mu = 0 (also the normal impact's): the 15 degree impact
  ends on it, its load still short of the initial hinge S*, where the deposited
  curvature Psi' is zero. At 30 and 45 degrees the load passes the point where the right
  hinge stood at T* (T = 1.3 and 1.6), where Psi' jumps (`barrierjax.hinge.oblique`):
  the force dips, S1, S2 and V0 kink, and the hinges end above the R = 0 root. The text
  mentions neither.
- 3.3.5: the same for V_H = 0.23, V_N = 0.4 (speed 0.46 at 60 degrees; like 15 degrees,
  it ends on the R = 0 root).
- 3.3.6: that impact in plan and to scale: the barrier's displacement W(X) at several
  times with the contact point on each, and the vehicle's path (its body: the barrier
  under it plus its crush, `simulate.vehicle_path`), its approach and departure (dashed),
  and where it leaves.

Checked against the text: V0 overshoots its steady value and comes back from above
(3.3.3), S1 settles sooner than S2 in absolute terms (though it undershoots its steady
value by 6 %, which the text does not mention); V0 is concave downward in the
decelerative phase, S1 = S2 at rest, and the vehicle leaves with a negative normal
velocity (3.3.4-3.3.6).

The three impacts of 3.3.4 and the one of 3.3.5-3.3.6 are one vmapped call (one compile),
computed once per process.
"""

from __future__ import annotations

import functools

import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from .. import plotting
from ..hinge.oblique import moving_load, oblique_impact
from .registry import figure, title

FORCE_RATIO_3_3 = 2.0
MASS_RATIO_3_3 = 5.0
TANGENTIAL_SPEED_3_3_3 = 1.0
T_END_3_3_3 = 25.0
SPEED_3_3_4 = 0.6
ANGLES_3_3_4 = (15.0, 30.0, 45.0)
NORMAL_SPEED_3_3_5, TANGENTIAL_SPEED_3_3_5 = 0.4, 0.23
# Step budget per phase (the default): the examples take about 160 steps in all at rtol
# 1e-8, and a smaller budget barely shortens the compile.
_MAX_STEPS_3_3 = 1024


def steady_state(force_ratio, tangential_speed):
    """(S1, S2, V0) of a constant load moving steadily along the barrier, (3.3.18)-(3.3.19):
    S1 = phi - (phi^2 - 1)^(1/2), S2 = phi + (phi^2 - 1)^(1/2), V0 = (phi^2 - 1)^(1/2)/V_H."""
    root = np.sqrt(force_ratio**2 - 1.0)
    return 1.0 / (force_ratio + root), force_ratio + root, root / tangential_speed


def final_hinge(mass_ratio, r=0.0):
    """The final hinge distance S1 = S2 of the text after (3.3.25): the positive root of
    s^3 + (3 - 2R) mu s^2 - 3s - 3mu = 0 (R = 0: the load on a straight part of the beam,
    as in normal impact)."""
    roots = np.roots([1.0, (3.0 - 2.0 * r) * mass_ratio, -3.0, -3.0 * mass_ratio])
    real = roots[np.abs(roots.imag) < 1e-12].real
    return float(real[real > 0.0].max())


@functools.cache
def _oblique_examples():
    """The impacts of 3.3.4 (three angles) and 3.3.5-3.3.6, in one vmapped call: a list of
    (result scalars, history, vehicle path (along, normal))."""
    angles = np.radians(ANGLES_3_3_4)
    vn = np.append(SPEED_3_3_4 * np.sin(angles), NORMAL_SPEED_3_3_5)
    vh = np.append(SPEED_3_3_4 * np.cos(angles), TANGENTIAL_SPEED_3_3_5)
    ones = jnp.ones(vn.shape)
    result = oblique_impact(
        MASS_RATIO_3_3 * ones,
        FORCE_RATIO_3_3 * ones,
        jnp.asarray(vn),
        jnp.asarray(vh),
        n_history=_N_HISTORY,
        max_steps=_MAX_STEPS_3_3,
    )
    fields = {
        k: np.asarray(getattr(result.history, k)) for k in result.history.__dataclass_fields__
    }
    scalars = {
        k: np.asarray(getattr(result, k)) for k in result.__dataclass_fields__ if k != "history"
    }
    examples = []
    for i in range(vn.size):
        history = {k: v[i] for k, v in fields.items()}
        path = (history["vehicle_position"], history["vehicle_displacement"])
        examples.append(({k: float(v[i]) for k, v in scalars.items()}, history, path))
    return examples


# Samples of each history drawn (equally spaced in time).
_N_HISTORY = 400


def _draw_oblique(axes, result, h, color, label):
    """S1, S2 / V0, V_N / P/P_b against T on three axes; T* marked on V0 and P."""
    ax_s, ax_v, ax_p = axes
    t = h["time"]
    ax_s.plot(t, h["hinge_position"], color=color)
    ax_s.plot(t, h["rear_hinge_position"], color=color, linestyle="--")
    ax_v.plot(t, h["barrier_velocity"], color=color)
    ax_v.plot(t, h["vehicle_velocity"], color=color, linestyle=":")
    contact = slice(0, max(plotting.first_free(h), 1))
    ax_p.plot(t[contact], h["contact_force"][contact], color=color, label=label)
    t_star = result["t_star"]
    k = np.searchsorted(t, t_star)
    ax_v.plot(t_star, np.interp(t_star, t, h["barrier_velocity"]), "o", color=color, markersize=5)
    ax_p.plot(t[k], h["contact_force"][k], "o", color=color, markersize=5)


def _finish_oblique(fig, axes, s_final):
    ax_s, ax_v, ax_p = axes
    ax_s.axhline(
        s_final,
        color="0.5",
        linestyle="-.",
        lw=0.8,
        label=rf"final $S_1 = S_2$ if $R$ = 0 at rest: {s_final:.3f}",
    )
    ax_s.plot([], [], color="0.3", label="$S_1$ (ahead of the vehicle)")
    ax_s.plot([], [], color="0.3", linestyle="--", label="$S_2$ (behind it)")
    ax_s.set_ylabel("hinge distance $S$")
    ax_s.set_ylim(0.5, 1.3)
    ax_s.legend(fontsize=8, loc="lower right")
    ax_v.axhline(0.0, color="0.5", lw=0.8)
    ax_v.plot([], [], color="0.3", label="$V_0$: barrier under the vehicle")
    ax_v.plot([], [], color="0.3", linestyle=":", label="$V_N$: vehicle, normal to the barrier")
    ax_v.plot([], [], "o", color="0.3", markersize=5, label="$T^*$: end of crushing")
    ax_v.set_ylabel("velocity $V$")
    ax_v.legend(fontsize=8, loc="upper right")
    ax_p.set_ylabel(r"contact force $P/P_b$")
    ax_p.set_ylim(0.0, 2.2)
    ax_p.set_xlabel("time $T$")
    ax_p.set_xlim(left=0.0)
    for ax in axes:
        ax.grid(True, alpha=0.3)


@figure(
    "3.3.3",
    "Transition of the Hinges to the Steady State under a Moving Constant Load",
    printed=False,
)
def _figure_3_3_3() -> Figure:
    phi, vh = FORCE_RATIO_3_3, TANGENTIAL_SPEED_3_3_3
    result = moving_load(phi, vh, T_END_3_3_3, max_steps=512)
    h = {k: np.asarray(getattr(result.history, k)) for k in result.history.__dataclass_fields__}
    s1_inf, s2_inf, v0_inf = steady_state(phi, vh)
    fig = Figure(figsize=(8.5, 8), layout="constrained")
    ax_s, ax_v = fig.subplots(2, 1, sharex=True)
    t = h["time"]
    ax_s.plot(t, h["hinge_position"], color="C0", label="$S_1$ (ahead of the load)")
    ax_s.plot(t, h["rear_hinge_position"], color="C1", label="$S_2$ (behind it)")
    for value, color, name in ((s1_inf, "C0", "S_1"), (s2_inf, "C1", "S_2")):
        ax_s.axhline(value, color=color, linestyle="--", lw=0.9)
        ax_s.annotate(
            rf"steady ${name}$ = {value:.3f}",
            xy=(T_END_3_3_3, value),
            xytext=(-4, 4),
            textcoords="offset points",
            ha="right",
            fontsize=8,
            color="0.3",
        )
    ax_s.set_ylabel("hinge distance $S$")
    ax_s.set_ylim(0.0, 4.2)
    ax_s.legend(loc="center right", fontsize=9)
    ax_v.plot(t, h["barrier_velocity"], color="C2", label="$V_0$: barrier under the load")
    ax_v.axhline(v0_inf, color="C2", linestyle="--", lw=0.9)
    ax_v.annotate(
        rf"steady $V_0 = (\phi^2 - 1)^{{1/2}}/V_H$ = {v0_inf:.3f}",
        xy=(T_END_3_3_3, v0_inf),
        xytext=(-4, -12),
        textcoords="offset points",
        ha="right",
        fontsize=8,
        color="0.3",
    )
    ax_v.plot(
        t,
        h["barrier_velocity"] + h["slope"] * vh,
        color="C3",
        linestyle=":",
        label=r"$V_0 + \theta V_H$: the load point's normal velocity",
    )
    ax_v.axhline(0.0, color="0.5", lw=0.8)
    ax_v.set_ylabel("velocity $V$")
    ax_v.set_xlabel("time $T$")
    ax_v.set_xlim(0.0, T_END_3_3_3)
    ax_v.legend(loc="center right", fontsize=9)
    for ax in (ax_s, ax_v):
        ax.grid(True, alpha=0.3)
    title(
        fig,
        "3.3.3",
        rf"$\phi$ = {phi:g}, $V_H$ = {vh:g}: a vehicle at $V_N$ = 1 would keep crushing "
        rf"to T = {T_END_3_3_3:g} if $\mu$ > {phi * T_END_3_3_3:g}",
    )
    return fig


@figure(
    "3.3.4",
    "Hinge Distances and Barrier Velocity for Impacts at 15, 30 and 45 Degrees",
    printed=False,
)
def _figure_3_3_4() -> Figure:
    examples = _oblique_examples()
    fig = Figure(figsize=(8.5, 10), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    for k, angle in enumerate(ANGLES_3_3_4):
        result, h, _ = examples[k]
        label = rf"$\alpha$ = {angle:g}$\degree$: {result['exit_angle_deg']:.1f}$\degree$"
        _draw_oblique(axes, result, h, f"C{k}", label)
    _finish_oblique(fig, axes, final_hinge(MASS_RATIO_3_3))
    axes[2].legend(fontsize=9, loc="upper right", title="vehicle at angle, exit angle")
    title(
        fig,
        "3.3.4",
        rf"$\mu$ = {MASS_RATIO_3_3:g}, $\phi$ = {FORCE_RATIO_3_3:g}, vehicle speed "
        rf"$V_V$ = {SPEED_3_3_4:g} at angle $\alpha$ to the barrier",
    )
    return fig


@figure(
    "3.3.5",
    "Hinge Distances and Barrier Velocity for V_H = 0.23, V_N = 0.4",
    printed=False,
)
def _figure_3_3_5() -> Figure:
    result, h, _ = _oblique_examples()[-1]
    fig = Figure(figsize=(8.5, 10), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    _draw_oblique(
        axes,
        result,
        h,
        "C0",
        rf"the vehicle leaves at {result['exit_angle_deg']:.1f}$\degree$ "
        rf"($V_N$ = {result['exit_normal_speed']:.3f}, $V_H$ = "
        rf"{result['exit_tangential_speed']:.2f})",
    )
    _finish_oblique(fig, axes, final_hinge(MASS_RATIO_3_3))
    axes[2].legend(fontsize=9, loc="upper right")
    title(
        fig,
        "3.3.5",
        rf"$\mu$ = {MASS_RATIO_3_3:g}, $\phi$ = {FORCE_RATIO_3_3:g}, "
        rf"$V_H$ = {TANGENTIAL_SPEED_3_3_5:g}, $V_N$ = {NORMAL_SPEED_3_3_5:g} "
        rf"($V_V$ = {np.hypot(TANGENTIAL_SPEED_3_3_5, NORMAL_SPEED_3_3_5):.2f} at "
        rf"{np.degrees(np.arctan2(NORMAL_SPEED_3_3_5, TANGENTIAL_SPEED_3_3_5)):.0f}$\degree$)",
    )
    return fig


@figure("3.3.6", "Barrier Displacement Pattern")
def _figure_3_3_6() -> Figure:
    result, h, path = _oblique_examples()[-1]
    t = h["time"]
    leave = plotting.first_free(h)
    marks = plotting.nearest_samples(t, np.linspace(0.0, t[-1], 7)[1:])
    how = "separates" if result["separated"] > 0.5 else "leaves as the barrier stops"
    fig = Figure(figsize=(10, 4.6), layout="constrained")
    ax = fig.subplots()
    plotting.draw_plan(
        ax,
        h["x"],
        h["deflected_shape"][marks],
        [f"barrier at T = {t[k]:.2f}" for k in marks],
        path,
        (h["contact_position"], h["barrier_displacement"]),
        marks,
        leave,
        (TANGENTIAL_SPEED_3_3_5, NORMAL_SPEED_3_3_5),
        (result["exit_tangential_speed"], result["exit_normal_speed"]),
        0.3 * t[leave],
    )
    ax.set_title(
        rf"impact: $V_H$ = {TANGENTIAL_SPEED_3_3_5:g}, $V_N$ = {NORMAL_SPEED_3_3_5:g}; "
        f"vehicle crush D = {result['damage']:.4f}; the vehicle's line is its body, the "
        "crush beyond the contact point\n"
        f"the vehicle {how}, at T = {t[leave]:.2f}: "
        rf"$V_N$ = {result['exit_normal_speed']:.3f}, $V_H$ = "
        rf"{result['exit_tangential_speed']:.3f}, {result['exit_angle_deg']:.1f}$\degree$ "
        "away from the barrier",
        loc="left",
        fontsize=9,
    )
    ax.set_aspect("equal")
    plotting.label_axes(
        ax,
        "position along the barrier $X$ (from the impact point)",
        "displacement $W$ (towards the barrier)",
        loc="upper right",
        fontsize=8,
    )
    title(
        fig,
        "3.3.6",
        rf"$\mu$ = {MASS_RATIO_3_3:g}, $\phi$ = {FORCE_RATIO_3_3:g}: the impact of figure "
        "3.3.5, drawn to scale",
    )
    return fig
