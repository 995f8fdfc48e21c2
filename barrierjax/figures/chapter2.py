"""Figures of report chapter 2, constitutive laws: the report has no figures here; these
show what its text describes (registered with `added=True`). Mild steel in the report's
units (psi, s): E = 30e6 psi and a static (lower) yield stress of 30,000 psi (the report
gives none). The constants are shared with sections 3.1 and 3.5 (`chapter3_elastic`).

- 2.2: stress against strain at constant strain rates for each rate law of 2.2.
- 2.3: the upper (2.3.5) and lower yield points of mild steel against strain rate.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from ..materials.delayed_yield import grain_diameter, upper_yield_stress
from ..materials.hereditary import HereditaryLaw
from ..materials.overstress import (
    CowperSymonds,
    GilmanJohnston,
    LinearOverstress,
    LogOverstress,
    SinhOverstress,
    StrainDependentOverstress,
)
from ..materials.plasticity import RateIndependentPlasticity
from ..materials.response import uniaxial_response
from ..plotting import label_axes
from .registry import figure, title

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
    title(
        fig,
        "2.2",
        f"E = {STEEL_E / 1e6:g}e6 psi, static yield {STEEL_YIELD / 1e3:g} ksi (dashed); "
        "backward-Euler updates (`uniaxial_response`)",
    )
    return fig


def delay_constants_2_3(grains):
    """The delay-time constants of (2.3.2) given in 2.3, for `grains` grains per mm^2:
    (A in mm^3 s, the grain diameter d in mm, beta). Public: the delayed yield of 3.5
    (`chapter3_elastic`) uses them too."""
    return DELAY_2_3["A"], grain_diameter(grains), DELAY_2_3["beta"]


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
        A, d, beta = delay_constants_2_3(grains)
        upper = upper_yield_stress(rates, E=STEEL_E, sigma0=sigma0, A=A, d=d, beta=beta)
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
    label_axes(ax, "strain rate $\\alpha$, 1/s", "yield stress, ksi", which="both", fontsize=8)
    title(
        fig,
        "2.3",
        "upper (2.3.5): sigma0 = 2G/45, A = 1.2e-6 mm$^3$ s, beta = 9, d = (grains/mm$^2$)$^{-1/2}$"
        " mm,\nabout 10 x the printed coefficients; lower: the log law's flow stress at 2 % strain"
        " over a static 30 ksi,\nwhich with the printed sigma_c and tau rises faster than the"
        " upper, against the text",
    )
    return fig
