"""Figures of report section 3.4, axial force: the static collapse of a beam held against
axial motion (3.4.2-3.4.5, `barrierjax.hinge.static_collapse`) and the dynamic beam stage
of the example in 3.4 (ii) (3.4.9, `barrierjax.hinge.axial_impact`).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from ..hinge.axial import axial_impact
from ..hinge.static_collapse import static_load_deflection
from ..plotting import label_axes
from .registry import figure, title

# --------------------------------------------------------------------------------------
# Static collapse.

EXPONENTS_3_4_4 = (1.0, 1.5, 2.0, 3.0, 5.0, np.inf)
_DEFLECTIONS_3_4 = np.linspace(0.0, 8.0, 401)  # delta over M0/N0 (h/4 for a rectangle)


def _yield_curve(a, n):
    """|m| + n^a = 1 in the first quadrant: m against n."""
    return np.ones_like(n) if np.isinf(a) else 1.0 - n**a


def _exponent_label(a):
    return r"$\alpha = \infty$" if np.isinf(a) else rf"$\alpha$ = {a:g}"


@figure("3.4.2", "M/M0 - N/N0 Interaction Curve for a Rectangular Beam")
def _figure_3_4_2() -> Figure:
    n = np.linspace(-1.0, 1.0, 401)
    path = static_load_deflection(_DEFLECTIONS_3_4[_DEFLECTIONS_3_4 <= 2.0], "pinned", 2.0)
    fig = Figure(figsize=(6.5, 6.0), layout="constrained")
    ax = fig.subplots()
    ax.plot(n, 1.0 - n**2, color="C0", label=r"$|M/M_0| + (N/N_0)^2 = 1$")
    ax.plot(n, -(1.0 - n**2), color="C0")
    ax.plot(
        path.axial_force,
        path.moment,
        color="C3",
        lw=2.5,
        alpha=0.6,
        label=r"central hinge, pinned beam: $N/N_0 = \delta N_0/(2M_0)$",
    )
    for label, (x, y) in {"A": (0.0, 1.0), "B": (0.6, 0.64), "C": (1.0, 0.0)}.items():
        ax.plot(x, y, "ko", ms=4)
        ax.annotate(label, (x, y), xytext=(6, 4), textcoords="offset points")
    # The flow rule at B: the plastic strain rate is normal to the curve.
    ax.annotate(
        "",
        xy=(0.6 + 0.25 * 1.2, 0.64 + 0.25),
        xytext=(0.6, 0.64),
        arrowprops={"arrowstyle": "->", "color": "0.3"},
    )
    ax.text(
        0.93,
        0.9,
        r"$(\dot\epsilon N_0,\ \dot\kappa M_0)$" "\n" r"$\propto (2N/N_0,\ 1)$",
        fontsize=8,
        color="0.3",
    )
    ax.axhline(0.0, color="0.6", lw=0.7)
    ax.axvline(0.0, color="0.6", lw=0.7)
    ax.set_aspect("equal")
    label_axes(ax, "$N/N_0$", "$M/M_0$", loc="center", fontsize=8)
    title(fig, "3.4.2", "A: incipient collapse, B: on the way, C: the plastic string (3.4.8)")
    return fig


def _load_deflection_axes(ax, support_rotations):
    ax.set_xlabel(r"central deflection $\delta N_0/M_0$  (rectangle: $\delta/(h/4)$)")
    ax.set_ylabel(f"$P\\ell/({4 * support_rotations}M_0)$: load over the collapse load without N")
    ax.grid(True, alpha=0.3)


@figure("3.4.3", "P - delta Curve for a Pin-Pin Beam in Figure 3.4.1")
def _figure_3_4_3() -> Figure:
    d = _DEFLECTIONS_3_4
    fig = Figure(figsize=(10, 4.8), layout="constrained")
    axes = fig.subplots(1, 2)
    for ax, support, k in zip(axes, ("pinned", "clamped"), (1, 2)):
        result = static_load_deflection(d, support, 2.0)
        beam = ~np.asarray(result.string)
        ax.plot(d[beam], result.load[beam], color="C0", label="beam: $1 + (\\delta/(2k))^2$")
        ax.plot(d[~beam], result.load[~beam], color="C3", label=r"plastic string: $\delta/k$")
        ax.plot(d, result.axial_force, color="0.5", ls="--", label="$N/N_0$")
        ax.axvline(2.0 * k, color="0.6", lw=0.8, ls=":")
        ax.set_title(
            f"{support} ends (k = {k}); $N = N_0$ at $\\delta = {2 * k}M_0/N_0$", fontsize=10
        )
        _load_deflection_axes(ax, k)
        ax.legend(fontsize=8)
    title(
        fig,
        "3.4.3",
        "rectangular section, ends held against axial motion; the clamped "
        "beam's 1 + (delta/4)^2 corrects the printed (3.4.22)",
    )
    return fig


@figure("3.4.4", "Yielding Curves for General Sections")
def _figure_3_4_4() -> Figure:
    n = np.linspace(0.0, 1.0, 201)
    fig = Figure(figsize=(6.0, 5.5), layout="constrained")
    ax = fig.subplots()
    for i, a in enumerate(EXPONENTS_3_4_4):
        m = _yield_curve(a, n)
        if np.isinf(a):
            n, m = np.array([0.0, 1.0, 1.0]), np.array([1.0, 1.0, 0.0])
        ax.plot(n, m, color=f"C{i}", label=_exponent_label(a))
    ax.set_aspect("equal")
    label_axes(ax, "$N/N_0$", "$M/M_0$", fontsize=8, title=r"$|M/M_0| + (N/N_0)^\alpha = 1$")
    title(fig, "3.4.4", "(3.4.17): 1 the ideal I section, 2 the rectangle")
    return fig


@figure(
    "3.4.5",
    "P - delta Curves for the Pin-Pin Beam in Figure 3.4.1 using the Yielding Conditions in "
    "Figure 3.4.4",
)
def _figure_3_4_5() -> Figure:
    d = _DEFLECTIONS_3_4
    fig = Figure(figsize=(10.5, 6.0), layout="constrained")
    ax = fig.subplots()
    for i, a in enumerate(EXPONENTS_3_4_4):
        result = static_load_deflection(d, "pinned", a)
        ax.plot(d, result.load, color=f"C{i}", label=_exponent_label(a))
        if np.isfinite(a) and a <= d[-1]:
            ax.plot(a, a, "o", color=f"C{i}", ms=4)
    ax.plot([], [], "ko", ms=4, label="N reaches $N_0$: the plastic string")
    ax.set_ylim(0.0, 9.0)
    _load_deflection_axes(ax, 1)
    ax.legend(fontsize=8)
    title(
        fig,
        "3.4.5",
        "pinned ends: $1 + (\\alpha - 1)(\\delta/\\alpha)^{\\alpha/(\\alpha-1)}$ "
        "up to $\\delta = \\alpha$, then $\\delta$",
    )
    return fig


# --------------------------------------------------------------------------------------
# The dynamic beam stage.

EXAMPLE_3_4_9 = {"mass_ratio": 0.5, "force_ratio": 2.0, "speed": 1.0}
AXIAL_RATIOS_3_4_9 = (0.0, 2.0, 2.5, 5.0, 10.0)  # 10: the string stage is reached


@figure("3.4.9", "Resulting Curves of the Example in Section 3.4 (ii)")
def _figure_3_4_9() -> Figure:
    etas = jnp.asarray(AXIAL_RATIOS_3_4_9)
    ones = jnp.ones_like(etas)
    result = axial_impact(
        EXAMPLE_3_4_9["mass_ratio"] * ones,
        EXAMPLE_3_4_9["force_ratio"] * ones,
        EXAMPLE_3_4_9["speed"] * ones,
        rtol=1e-10,
        axial_ratio=etas,
        n_history=150,
    )
    h = jax.tree.map(np.asarray, result.history)
    fig = Figure(figsize=(9, 10), layout="constrained")
    ax_s, ax_v, ax_w, ax_n = fig.subplots(4, 1, sharex=True)
    w_plain = float(result.barrier_displacement[0])
    for k, eta in enumerate(AXIAL_RATIOS_3_4_9):
        t = h.time[k]
        reduction = 100.0 * (1.0 - float(result.barrier_displacement[k]) / w_plain)
        label = rf"$\eta_0$ = {eta:g}" + (f": $W_f$ {-reduction:+.1f} %" if eta else "")
        if np.isfinite(result.t_string[k]):
            label += f", string from T = {float(result.t_string[k]):.3f}"
        ax_s.plot(t, h.hinge_position[k], color=f"C{k}", label=label)
        ax_v.plot(t, h.barrier_velocity[k], color=f"C{k}")
        ax_w.plot(t, h.barrier_displacement[k], color=f"C{k}")
        ax_n.plot(t, h.axial_force[k], color=f"C{k}")
    ax_s.set_ylabel("hinge distance $S$")
    ax_s.legend(fontsize=9, title="final displacement against $\\eta_0$ = 0")
    ax_v.set_ylabel("barrier velocity $V_0$")
    ax_w.set_ylabel("displacement $W_0$")
    ax_n.set_ylabel("axial force $N/N_0 = 2\\eta_0 W_0$")
    ax_n.axhline(1.0, color="0.5", ls=":", lw=0.9)
    ax_n.annotate(
        "plastic string",
        xy=(0.01, 1.0),
        xytext=(0, -12),
        textcoords="offset points",
        fontsize=8,
        color="0.3",
        xycoords=("axes fraction", "data"),
    )
    ax_n.set_xlabel("time $T$")
    for ax in (ax_s, ax_v, ax_w, ax_n):
        ax.grid(True, alpha=0.3)
    title(
        fig,
        "3.4.9",
        rf"$\mu$ = {EXAMPLE_3_4_9['mass_ratio']:g}, $\phi$ = {EXAMPLE_3_4_9['force_ratio']:g}, "
        f"speed {EXAMPLE_3_4_9['speed']:g}\nthe report quotes -2.5 % ($\\eta_0$ = 2) and "
        "-12.5 % ($\\eta_0$ = 5) from its coarse scheme (benchmarks/axial_force.py)",
    )
    return fig
