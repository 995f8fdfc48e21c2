"""The report's figures, recomputed (the scanned report keeps only their captions).

`FIGURES` maps a figure number ("3.2.2") to its caption and a function returning a
`matplotlib.figure.Figure`; `write_figures` writes them as `fig_3_2_2.png`, ... and is
what `barrierjax figures` runs. A later model adds its figures with

    @figure("3.3.2", "Caption as printed in the report")
    def _figure_3_3_2() -> Figure: ...

Section 3.2, normal impact (`barrierjax.hinge.normal_impact`):

- 3.2.2: hinge distance S, barrier velocity V/V0 and displacement W/V0^2 against T/V0, for
  phi = 2 and several mass ratios. With V0 = 1 the model's speed-free variables are the
  plotted ones (the report's remark after (3.2.20)). T/V0 runs to about mu, so the time
  axis is logarithmic to show every mass ratio.
- 3.2.3: the default scene (`barrierjax/default_scene.toml`) in SI units.
- 3.2.4: vehicle damage D/V0^2 = T*/(2 V0) against mu, for several force ratios, with its
  bound as mu -> infinity, S*/(2 (phi - S*)), S* = (phi^2 + 3)^(1/2) - phi (3.2.11).
  The report's printed closed form lacks the factor 1/2 (ERRATA.md); so does its bound.

Section 3.3, oblique impact (`barrierjax.hinge.oblique_impact`, `moving_load`). The scan
keeps the caption of 3.3.6 only; those of 3.3.3-3.3.5 are composed from the text that
cites them (registered with `printed=False`, and said so under the figure's title). The
text sets mu = 5 and phi = 2 "in all cases" of its examples (3.3.4-3.3.6); time is T and
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
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from . import plotting
from .hinge.elastic import (
    delayed_yield_limit_speed,
    elastic_impact,
    elastic_limit_speed,
    string_impact,
)
from .hinge.normal import normal_impact
from .hinge.oblique import moving_load, oblique_impact
from .hinge.static_collapse import static_load_deflection
from .materials.delayed_yield import grain_diameter, upper_yield_stress
from .materials.hereditary import HereditaryLaw
from .materials.overstress import (
    CowperSymonds,
    GilmanJohnston,
    LinearOverstress,
    LogOverstress,
    SinhOverstress,
    StrainDependentOverstress,
)
from .materials.plasticity import RateIndependentPlasticity
from .materials.response import uniaxial_response

__all__ = ["FIGURES", "FigureEntry", "damage_bound", "figure", "filename", "write_figures"]


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


def _title(fig: Figure, number: str, subtitle: str = "") -> None:
    entry = FIGURES[number]
    lines = [f"Figure {number}  {entry.caption}"]
    if entry.added:
        lines.append("(not a figure of the report: added to show its section " + number + ")")
    elif not entry.printed:
        lines.append("(caption lost from the scan; composed from the report's text)")
    if subtitle:
        lines.append(subtitle)
    fig.suptitle("\n".join(lines), fontsize=12)


# --------------------------------------------------------------------------------------
# Chapter 2, constitutive laws, and sections 3.1 and 3.5, elastic impact: the report has
# no figures here; these show what its text describes. Mild steel in the report's units
# (psi, s): E = 30e6 psi and a static (lower) yield stress of 30,000 psi (the report gives
# none).

STEEL_E = 30e6  # psi
STEEL_G = 11.5e6  # psi
STEEL_YIELD = 30_000.0  # psi, static lower yield stress (assumed)
STRAIN_RATES_2_2 = (1e-3, 1e-1, 1e1, 1e2)  # 1/s: the report's range for structures
DELAY_2_3 = {"A": 1.2e-6, "beta": 9.0, "grains": (2030.0, 346.0)}  # mm^3 s, -, per mm^2
LOG_LAW_2_3 = {"sigma_c": 26_000.0, "tau": 0.1}  # as printed after (2.2.8)


def _rate_laws():
    """Each rate law of 2.2 with mild-steel parameters that raise the flow stress by about
    half at 100/s, where the report gives none: (name, law)."""
    E, sigma0 = STEEL_E, STEEL_YIELD
    return [
        ("linear (2.2.2), tau = 5 us", LinearOverstress(E, sigma0, 5e-6)),
        (
            "strain-dependent (2.2.5), tau = 5 us, eps0 = -0.01",
            StrainDependentOverstress(E, sigma0, 5e-6, -0.01),
        ),
        (
            "logarithmic (2.2.6), sigma_c = 2.6 ksi, tau = 0.1 s",
            LogOverstress(E, sigma0, 2600.0, 0.1),
        ),
        ("sinh, sigma_c = 2.6 ksi, tau = 0.1 s", SinhOverstress(E, sigma0, 2600.0, 0.1)),
        ("Cowper-Symonds (4.3.1), D = 40/s, q = 5", CowperSymonds(E, sigma0, 40.0, 5.0)),
        (
            "Gilman-Johnston, rate0 = 1e8/s, D = 760 ksi",
            GilmanJohnston(E, 1e8, 760_000.0),
        ),
        (
            "hereditary (2.2.15), psi: 0.5 e^(-t/1 us) + 0.5 e^(-t/10 us)",
            HereditaryLaw(E, sigma0, jnp.array([0.5, 0.5]), jnp.array([1e-6, 1e-5])),
        ),
        (
            "rate-independent, kinematic hardening H = E/100",
            RateIndependentPlasticity(E, sigma0, kinematic=E / 100),
        ),
    ]


def _constant_rate(law, rate, strain=0.02, n=200):
    """Stress against strain at a constant strain rate, loaded to `strain`."""
    strains = np.linspace(0.0, strain, n)
    return strains, np.asarray(uniaxial_response(law, strains / rate, strains).stress)


@figure("2.2", "Stress-Strain Curves of the Rate Laws at Several Strain Rates", added=True)
def _figure_2_2() -> Figure:
    laws = _rate_laws()
    fig = Figure(figsize=(11, 12), layout="constrained")
    axes = fig.subplots(4, 2, sharex=True).ravel()
    for ax, (name, law) in zip(axes, laws):
        for k, rate in enumerate(STRAIN_RATES_2_2):
            strain, stress = _constant_rate(law, rate)
            ax.plot(100 * strain, stress / 1e3, color=f"C{k}", label=f"{rate:g}/s")
        ax.axhline(STEEL_YIELD / 1e3, color="0.5", ls="--", lw=0.9)
        ax.set_title(name, fontsize=9)
        ax.set_ylabel("stress, ksi")
        ax.grid(True, alpha=0.3)
    axes[0].legend(fontsize=8, title="strain rate")
    for ax in axes[-2:]:
        ax.set_xlabel("strain, %")
    _title(
        fig,
        "2.2",
        f"E = {STEEL_E / 1e6:g}e6 psi, static yield {STEEL_YIELD / 1e3:g} ksi (dashed); "
        "backward-Euler updates (`uniaxial_response`)",
    )
    return fig


def _lower_yield(sigma_c, tau, rates):
    """The logarithmic law's flow stress at 2 % strain at each constant rate (2.2.8)."""
    law = LogOverstress(STEEL_E, STEEL_YIELD, sigma_c, tau)
    return np.array([_constant_rate(law, rate)[1][-1] for rate in rates])


@figure("2.3", "Upper and Lower Yield Points of Mild Steel against Strain Rate", added=True)
def _figure_2_3() -> Figure:
    rates = np.logspace(-3, 3, 7)
    fig = Figure(figsize=(10, 7), layout="constrained")
    ax = fig.subplots()
    sigma0 = 2.0 * STEEL_G / 45.0
    for k, grains in enumerate(DELAY_2_3["grains"]):
        upper = upper_yield_stress(
            rates,
            E=STEEL_E,
            sigma0=sigma0,
            A=DELAY_2_3["A"],
            d=grain_diameter(grains),
            beta=DELAY_2_3["beta"],
        )
        ax.loglog(
            rates,
            np.asarray(upper) / 1e3,
            color=f"C{k}",
            label=f"upper (2.3.5), {grains:g} grains/mm$^2$",
        )
        printed = 77_000.0 if grains == 2030.0 else 60_000.0
        ax.loglog(
            rates,
            printed * rates**0.1 / 1e3,
            color=f"C{k}",
            ls="--",
            label=f"as printed: {printed:,.0f} $\\alpha^{{1/10}}$ psi",
        )
    for k, (sigma_c, tau, note) in enumerate(
        ((LOG_LAW_2_3["sigma_c"], LOG_LAW_2_3["tau"], "as printed"), (2600.0, 0.1, "sigma_c / 10"))
    ):
        lower = _lower_yield(sigma_c, tau, rates)
        ax.loglog(
            rates,
            lower / 1e3,
            color=f"C{k + 2}",
            marker="o",
            ms=3,
            label=f"lower, log law: $\\sigma_c$ = {sigma_c:,.0f} psi, $\\tau$ = {tau:g} s ({note})",
        )
    ax.set_xlabel("strain rate $\\alpha$, 1/s")
    ax.set_ylabel("yield stress, ksi")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    _title(
        fig,
        "2.3",
        "upper (2.3.5): sigma0 = 2G/45, A = 1.2e-6 mm$^3$ s, beta = 9, d = (grains/mm$^2$)$^{-1/2}$"
        " mm,\nabout 10 x the printed coefficients; lower: the log law's flow stress at 2 % strain"
        " over a static 30 ksi,\nwhich with the printed sigma_c and tau rises faster than the"
        " upper, against the text",
    )
    return fig


# A rectangular steel bar 1 in wide and 4 in deep, in lb, in, s.
BAR_3_1 = {"E": STEEL_E, "b": 1.0, "h": 4.0, "rho": 7.33e-4}  # rho in lb s^2/in^4


def _bar_section():
    b, h = BAR_3_1["b"], BAR_3_1["h"]
    return {"E": BAR_3_1["E"], "I": b * h**3 / 12.0, "A": b * h, "rho": BAR_3_1["rho"]}


@figure(
    "3.1", "Mass Striking an Infinite Elastic Beam: Motion and Moment under the Mass", added=True
)
def _figure_3_1() -> Figure:
    section = _bar_section()
    fig = Figure(figsize=(11, 7.5), layout="constrained")
    (ax_v, ax_a), (ax_w, ax_m) = fig.subplots(2, 2)
    masses = (1.0, 10.0, 100.0)  # lb s^2/in
    t = np.logspace(-6, -1, 300)
    for k, mass in enumerate(masses):
        r = elastic_impact(mass, 1.0, t, **section)
        s = string_impact(mass, 1.0, t, tension=1e5, rho=section["rho"] * section["A"])
        label = f"M = {mass:g} lb s$^2$/in"
        ax_v.semilogx(t * 1e3, np.asarray(r.velocity), color=f"C{k}", label=label)
        ax_v.semilogx(t * 1e3, np.asarray(s.velocity), color=f"C{k}", ls=":")
        ax_a.loglog(t * 1e3, -np.asarray(r.acceleration), color=f"C{k}")
        ax_a.loglog(t * 1e3, -np.asarray(s.acceleration), color=f"C{k}", ls=":")
        ax_w.loglog(t * 1e3, np.asarray(r.displacement), color=f"C{k}")
        ax_m.semilogx(t * 1e3, np.asarray(r.moment) / 1e3, color=f"C{k}")
    ax_v.set_ylabel("velocity under the mass / $V_0$")
    ax_a.set_ylabel("deceleration / $V_0$, 1/s")
    ax_w.set_ylabel("displacement / $V_0$, s")
    ax_m.set_ylabel("moment under the mass / $V_0$, kip s")
    ax_v.legend(fontsize=8, title="solid: beam (3.1.3); dotted: string (3.1.5), T = 100 kip")
    for ax in (ax_v, ax_a, ax_w, ax_m):
        ax.set_xlabel("time after impact, ms")
        ax.grid(True, which="both", alpha=0.3)
    _title(
        fig,
        "3.1",
        "steel bar 1 x 4 in, E = 30e6 psi; the beam's deceleration is infinite at impact, the"
        " string's finite;\nthe moment starts at 2 EI K$^2$ V$_0$ whatever the mass",
    )
    return fig


@figure("3.5", "Limiting Speed of an Elastic Impact with Delayed Yield against Mass", added=True)
def _figure_3_5() -> Figure:
    section = _bar_section()
    y = BAR_3_1["h"] / 2.0
    masses = np.logspace(-3, 3, 61)  # lb s^2/in
    fig = Figure(figsize=(10.5, 6), layout="constrained")
    ax = fig.subplots()
    elastic = elastic_limit_speed(**section, y=y, yield_stress=STEEL_YIELD)
    # sigma0 as printed (2G/45), and the values that reproduce 2.3's printed coefficients
    # (`barrierjax.materials.delayed_yield`), 10 times lower.
    implied = {2030.0: 39_280.0, 346.0: 39_980.0}
    for k, grains in enumerate(DELAY_2_3["grains"]):
        for sigma0, style, note in (
            (2.0 * STEEL_G / 45.0, ":", "2G/45"),
            (implied[grains], "-", ""),
        ):
            delayed = delayed_yield_limit_speed(
                masses,
                **section,
                y=y,
                sigma0=sigma0,
                delay_constant=DELAY_2_3["A"],
                d=grain_diameter(grains),
                beta=DELAY_2_3["beta"],
            )
            label = f"{grains:g} grains/mm$^2$, $\\sigma_0$ = {sigma0 / 1e3:.1f} ksi {note}"
            ax.loglog(masses, np.asarray(delayed / elastic), color=f"C{k}", ls=style, label=label)
    ax.axhline(1.0, color="0.5", ls="--", lw=0.9)
    ax.set_xlabel("striking mass M, lb s$^2$/in")
    ax.set_ylabel("limiting speed with delayed yield / without (30 ksi)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=9)
    _title(
        fig,
        "3.5",
        "steel bar 1 x 4 in, elastic limit at 30 ksi; delay constants of 2.3 (A = 1.2e-6 mm$^3$"
        " s, beta = 9)\nwith sigma0 as printed (dotted) and as implied by the printed"
        " coefficients of 2.3 (solid); the gain falls as M$^{-2/9}$",
    )
    return fig


# --------------------------------------------------------------------------------------
# Section 3.2, normal impact.

MASS_RATIOS_3_2_2 = (0.5, 1.0, 2.0, 5.0, 10.0, 20.0)
FORCE_RATIO_3_2_2 = 2.0
FORCE_RATIOS_3_2_4 = (1.25, 1.5, 2.0, 3.0, 5.0, 10.0)


def _normal_histories(mass_ratios, force_ratio, n_history=200):
    """`normal_impact` at unit speed for each mass ratio (vmapped), with histories."""
    solve = lambda mu: normal_impact(mu, force_ratio, 1.0, n_history=n_history)
    return jax.vmap(solve)(jnp.asarray(mass_ratios, dtype=float))


@figure("3.2.2", "Hinge Distance S and Barrier Velocity and Displacement Against T/V0")
def _figure_3_2_2() -> Figure:
    mus, phi = MASS_RATIOS_3_2_2, FORCE_RATIO_3_2_2
    result = _normal_histories(mus, phi)
    h = jax.tree.map(np.asarray, result.history)
    fig = Figure(figsize=(8.5, 10), layout="constrained")
    ax_s, ax_v, ax_w = fig.subplots(3, 1, sharex=True)
    t_min = 1e-2
    for k, mu in enumerate(mus):
        color, label = f"C{k}", rf"$\mu$ = {mu:g}"
        t = h.time[k]
        # On the log time axis, draw the samples' interpolant in T (linear for S and V,
        # Hermite with slope V for W), not straight chords in log T.
        fine = np.union1d(t[t >= t_min], np.geomspace(t_min, t[-1], 600))
        ax_s.plot(fine, np.interp(fine, *_unique(t, h.hinge[k])), color=color, label=label)
        ax_v.plot(fine, np.interp(fine, *_unique(t, h.barrier_velocity[k])), color=color)
        n = t.shape[0] // 2  # first half: accelerative phase, the vehicle faster
        ax_v.plot(t[1:n], h.vehicle_velocity[k][1:n], color=color, linestyle=":", lw=1)
        w = plotting.hermite(fine, t, h.displacement[k], h.barrier_velocity[k])
        ax_w.plot(fine, w, color=color)
    s_star = float(result.s_star[0])
    ax_s.axhline(s_star, color="0.5", linestyle="--", lw=0.8)
    ax_s.annotate(
        rf"$S^*$ = {s_star:.3f} (accelerative phase)",
        xy=(0.012, s_star),
        xytext=(0, 4),
        textcoords="offset points",
        fontsize=8,
        color="0.3",
    )
    ax_s.axhline(1.0, color="0.5", linestyle="-.", lw=0.8)
    ax_s.annotate(
        r"final $S = \alpha \to 1$ as $\mu \to \infty$",
        xy=(0.012, 1.0),
        xytext=(0, 4),
        textcoords="offset points",
        fontsize=8,
        color="0.3",
    )
    ax_s.set_ylabel("hinge distance $S$")
    ax_s.set_ylim(0.0, 1.6)
    ax_s.legend(title=rf"$\phi$ = {phi:g}", ncol=3, fontsize=9, loc="lower right")
    ax_v.set_ylabel("barrier velocity $V/V_0$")
    ax_v.set_ylim(0.0, 1.02)
    ax_v.annotate(
        "dotted: vehicle velocity\nduring the accelerative phase",
        xy=(0.02, 0.55),
        xycoords="axes fraction",
        fontsize=8,
        color="0.3",
        va="top",
    )
    ax_w.set_ylabel("displacement $W/V_0^2$")
    ax_w.set_yscale("log")
    ax_w.set_ylim(1e-5, 20.0)
    ax_w.set_xscale("log")
    ax_w.set_xlim(t_min, 30.0)
    ax_w.set_xlabel("$T/V_0$ (log scale)")
    for ax in (ax_s, ax_v, ax_w):
        ax.grid(True, which="both", alpha=0.3)
    _title(fig, "3.2.2")
    return fig


def _unique(t, y):
    """Samples at distinct times (the history repeats the switch and the rest state)."""
    t, first = np.unique(t, return_index=True)
    return t, y[first]


@figure("3.2.3", "Solution for a Typical Impact in Terms of Real Variables")
def _figure_3_2_3() -> Figure:
    from .scene_file import default_scene
    from .simulate import simulate

    scene = default_scene()
    result = simulate(scene)
    fig = plotting.histories_figure(result)
    g = result.groups
    fig.suptitle(
        "Figure 3.2.3  " + FIGURES["3.2.3"].caption + "\n"
        f"default scene: {float(scene.vehicle.mass):.0f} kg, P0 = "
        f"{float(scene.vehicle.crush_force) / 1e3:.0f} kN at "
        f"{float(scene.impact.speed) * 3.6:.0f} km/h on M0 = "
        f"{float(scene.barrier.plastic_moment) / 1e3:.1f} kN*m, m = "
        f"{float(scene.barrier.mass_per_length):.1f} kg/m, q0 = "
        f"{float(scene.barrier.backing_strength) / 1e3:.0f} kN/m "
        rf"($\mu$ = {float(g.mass_ratio):.3g}, $\phi$ = {float(g.force_ratio):.3g})",
        fontsize=11,
    )
    return fig


def damage_bound(force_ratio):
    """lim D/V0^2 as mu -> infinity: S*/(2 (phi - S*)), S* = (phi^2 + 3)^(1/2) - phi."""
    phi = jnp.asarray(force_ratio, dtype=float)
    s_star = 3.0 / (jnp.sqrt(phi**2 + 3.0) + phi)  # = sqrt(phi^2 + 3) - phi, no cancellation
    return s_star / (2.0 * (phi - s_star))


@figure("3.2.4", "Vehicle Damage as a Function of Mass Ratio for Various Force Ratios")
def _figure_3_2_4() -> Figure:
    mus = jnp.logspace(-2.0, 3.0, 201)
    phis = jnp.asarray(FORCE_RATIOS_3_2_4)
    damage = jax.vmap(lambda phi: normal_impact(mus, phi, 1.0).damage)(phis)
    bounds = damage_bound(phis)
    fig = Figure(figsize=(8.5, 6.5), layout="constrained")
    ax = fig.subplots()
    for k, phi in enumerate(FORCE_RATIOS_3_2_4):
        color = f"C{k}"
        ax.loglog(np.asarray(mus), np.asarray(damage[k]), color=color, label=rf"$\phi$ = {phi:g}")
        ax.axhline(float(bounds[k]), color=color, linestyle="--", lw=0.9)
    ax.plot(
        [],
        [],
        color="0.4",
        linestyle="--",
        lw=0.9,
        label=r"$\mu \to \infty$: $S^*/(2(\phi - S^*))$",
    )
    ax.set_xlim(1e-2, 1e3)
    ax.set_xlabel(r"mass ratio $\mu = M/(mL)$")
    ax.set_ylabel("vehicle damage $D/V_0^2$")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(loc="upper left", fontsize=9)
    ax.annotate(
        r"$D/V_0^2 = T^*/(2V_0) = \mu S^* / (2[\phi S^* + \mu(\phi - S^*)])$,  "
        r"$S^* = (\phi^2 + 3)^{1/2} - \phi$",
        xy=(0.98, 0.02),
        xycoords="axes fraction",
        ha="right",
        va="bottom",
        fontsize=8,
        color="0.3",
    )
    _title(fig, "3.2.4")
    return fig


# --------------------------------------------------------------------------------------
# Section 3.3, oblique impact.

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


def _cut(history, n):
    """A history's per-step arrays cut to its `n` recorded steps (the grid `x` kept)."""
    return {
        k: np.asarray(v)[:n] if np.ndim(v) and k != "x" else np.asarray(v)
        for k, v in history.items()
    }


@functools.cache
def _oblique_examples():
    """The impacts of 3.3.4 (three angles) and 3.3.5-3.3.6, in one vmapped call: a list of
    (result scalars, history cut to its recorded steps, vehicle path (along, normal))."""
    from .simulate import vehicle_path

    angles = np.radians(ANGLES_3_3_4)
    vn = np.append(SPEED_3_3_4 * np.sin(angles), NORMAL_SPEED_3_3_5)
    vh = np.append(SPEED_3_3_4 * np.cos(angles), TANGENTIAL_SPEED_3_3_5)
    ones = jnp.ones(vn.shape)
    result = oblique_impact(
        MASS_RATIO_3_3 * ones,
        FORCE_RATIO_3_3 * ones,
        jnp.asarray(vn),
        jnp.asarray(vh),
        history=True,
        max_steps=_MAX_STEPS_3_3,
    )
    along, normal = jax.vmap(vehicle_path)(result.history)
    fields = {
        k: np.asarray(getattr(result.history, k)) for k in result.history.__dataclass_fields__
    }
    scalars = {
        k: np.asarray(getattr(result, k)) for k in result.__dataclass_fields__ if k != "history"
    }
    examples = []
    for i in range(vn.size):
        n = int(fields["n_saved"][i])
        history = {k: v[i] for k, v in fields.items()}
        path = (np.asarray(along[i])[:n], np.asarray(normal[i])[:n])
        examples.append(({k: float(v[i]) for k, v in scalars.items()}, _cut(history, n), path))
    return examples


_first_free = plotting._first_free  # the sample where the vehicle leaves the barrier


def _draw_oblique(axes, result, h, color, label):
    """S1, S2 / V0, V_N / P/P_b against T on three axes; T* marked on V0 and P."""
    ax_s, ax_v, ax_p = axes
    t = h["time"]
    ax_s.plot(t, h["s1"], color=color)
    ax_s.plot(t, h["s2"], color=color, linestyle="--")
    ax_v.plot(t, h["v0"], color=color)
    ax_v.plot(t, h["vehicle_normal_velocity"], color=color, linestyle=":")
    contact = slice(0, max(_first_free(h), 1))
    ax_p.plot(t[contact], h["contact_force"][contact], color=color, label=label)
    t_star = result["t_star"]
    k = np.searchsorted(t, t_star)
    ax_v.plot(t_star, np.interp(t_star, t, h["v0"]), "o", color=color, markersize=5)
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
    h = result.history
    h = _cut({k: getattr(h, k) for k in h.__dataclass_fields__}, int(h.n_saved))
    s1_inf, s2_inf, v0_inf = steady_state(phi, vh)
    fig = Figure(figsize=(8.5, 8), layout="constrained")
    ax_s, ax_v = fig.subplots(2, 1, sharex=True)
    t = h["time"]
    ax_s.plot(t, h["s1"], color="C0", label="$S_1$ (ahead of the load)")
    ax_s.plot(t, h["s2"], color="C1", label="$S_2$ (behind it)")
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
    ax_v.plot(t, h["v0"], color="C2", label="$V_0$: barrier under the load")
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
        h["v0"] + h["slope"] * vh,
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
    _title(
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
    _title(
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
    _title(
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
    leave = _first_free(h)
    marks = plotting.nearest_samples(t, np.linspace(0.0, t[-1], 7)[1:])
    how = "separates" if result["separated"] > 0.5 else "leaves as the barrier stops"
    fig = Figure(figsize=(10, 4.6), layout="constrained")
    ax = fig.subplots()
    plotting.draw_plan(
        ax,
        h["x"],
        h["displacement"][marks],
        [f"barrier at T = {t[k]:.2f}" for k in marks],
        path,
        (h["contact_position"], h["contact_displacement"]),
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
    ax.set_xlabel("position along the barrier $X$ (from the impact point)")
    ax.set_ylabel("displacement $W$ (towards the barrier)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    _title(
        fig,
        "3.3.6",
        rf"$\mu$ = {MASS_RATIO_3_3:g}, $\phi$ = {FORCE_RATIO_3_3:g}: the impact of figure "
        "3.3.5, drawn to scale",
    )
    return fig


# --------------------------------------------------------------------------------------
# Section 3.4, axial force: static collapse.

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
    ax.set_xlabel("$N/N_0$")
    ax.set_ylabel("$M/M_0$")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="center", fontsize=8)
    _title(fig, "3.4.2", "A: incipient collapse, B: on the way, C: the plastic string (3.4.8)")
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
    _title(
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
    ax.set_xlabel("$N/N_0$")
    ax.set_ylabel("$M/M_0$")
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, title=r"$|M/M_0| + (N/N_0)^\alpha = 1$")
    _title(fig, "3.4.4", "(3.4.17): 1 the ideal I section, 2 the rectangle")
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
    _title(
        fig,
        "3.4.5",
        "pinned ends: $1 + (\\alpha - 1)(\\delta/\\alpha)^{\\alpha/(\\alpha-1)}$ "
        "up to $\\delta = \\alpha$, then $\\delta$",
    )
    return fig


# --------------------------------------------------------------------------------------
# Section 3.4, axial force: the dynamic beam stage.

EXAMPLE_3_4_9 = {"mass_ratio": 0.5, "force_ratio": 2.0, "speed": 1.0}
AXIAL_RATIOS_3_4_9 = (0.0, 2.0, 2.5, 5.0, 10.0)  # 10: the string stage is reached


@figure("3.4.9", "Resulting Curves of the Example in Section 3.4 (ii)")
def _figure_3_4_9() -> Figure:
    etas = jnp.asarray(AXIAL_RATIOS_3_4_9)
    ones = jnp.ones_like(etas)
    result = normal_impact(
        EXAMPLE_3_4_9["mass_ratio"] * ones,
        EXAMPLE_3_4_9["force_ratio"] * ones,
        EXAMPLE_3_4_9["speed"] * ones,
        method="ode",
        rtol=1e-10,
        axial_ratio=etas,
        n_history=150,
    )
    h = jax.tree.map(np.asarray, result.history)
    fig = Figure(figsize=(9, 10), layout="constrained")
    ax_s, ax_v, ax_w, ax_n = fig.subplots(4, 1, sharex=True)
    w_plain = float(result.w_final[0])
    for k, eta in enumerate(AXIAL_RATIOS_3_4_9):
        t = h.time[k]
        reduction = 100.0 * (1.0 - float(result.w_final[k]) / w_plain)
        label = rf"$\eta_0$ = {eta:g}" + (f": $W_f$ {-reduction:+.1f} %" if eta else "")
        if np.isfinite(result.t_string[k]):
            label += f", string from T = {float(result.t_string[k]):.3f}"
        ax_s.plot(t, h.hinge[k], color=f"C{k}", label=label)
        ax_v.plot(t, h.barrier_velocity[k], color=f"C{k}")
        ax_w.plot(t, h.displacement[k], color=f"C{k}")
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
    _title(
        fig,
        "3.4.9",
        rf"$\mu$ = {EXAMPLE_3_4_9['mass_ratio']:g}, $\phi$ = {EXAMPLE_3_4_9['force_ratio']:g}, "
        f"speed {EXAMPLE_3_4_9['speed']:g}\nthe report quotes -2.5 % ($\\eta_0$ = 2) and "
        "-12.5 % ($\\eta_0$ = 5) from its coarse scheme (benchmarks/axial_force.py)",
    )
    return fig


# Chapter 4's figures register themselves on import (they draw from `barrierjax.beam`).
from . import figures_beam  # noqa: F401
