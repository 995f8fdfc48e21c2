"""Figures of report sections 3.1 and 3.5, elastic impact: the report has no figures here;
these show what its text describes (registered with `added=True`), for a mass striking a
rectangular steel bar (mild steel of `chapter2`, in psi and s).

- 3.1: velocity, deceleration and displacement under the mass and the moment there against
  time, for an infinite elastic beam (3.1.3) and a string (3.1.5).
- 3.5: the limiting speed of an elastic impact with delayed yield (2.3) against the mass.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..hinge.elastic import (
    delayed_yield_limit_speed,
    elastic_impact,
    elastic_limit_speed,
    string_impact,
)
from ..plotting import label_axes
from .chapter2 import DELAY_2_3, STEEL_E, STEEL_G, STEEL_YIELD, delay_constants_2_3
from .registry import figure, title

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
    title(
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
        delay_constant, d, beta = delay_constants_2_3(grains)
        for sigma0, style, note in (
            (2.0 * STEEL_G / 45.0, ":", "2G/45"),
            (implied[grains], "-", ""),
        ):
            delayed = delayed_yield_limit_speed(
                masses, **section, y=y, sigma0=sigma0, delay_constant=delay_constant, d=d, beta=beta
            )
            label = f"{grains:g} grains/mm$^2$, $\\sigma_0$ = {sigma0 / 1e3:.1f} ksi {note}"
            ax.loglog(masses, np.asarray(delayed / elastic), color=f"C{k}", ls=style, label=label)
    ax.axhline(1.0, color="0.5", ls="--", lw=0.9)
    label_axes(
        ax,
        "striking mass M, lb s$^2$/in",
        "limiting speed with delayed yield / without (30 ksi)",
        which="both",
        fontsize=9,
    )
    title(
        fig,
        "3.5",
        "steel bar 1 x 4 in, elastic limit at 30 ksi; delay constants of 2.3 (A = 1.2e-6 mm$^3$"
        " s, beta = 9)\nwith sigma0 as printed (dotted) and as implied by the printed"
        " coefficients of 2.3 (solid); the gain falls as M$^{-2/9}$",
    )
    return fig
