"""Figures of report chapter 4: viscoplastic beam sections (4.1, `barrierjax.beam.section`)
and the cantilever examples (4.3, `barrierjax.beam.report_example`).

- 4.1.2: M/M0 against kappa/kappa_e at constant curvature rates, for the section's own
  linear law (4.1.2) in the report's dimensionless variables (4.1.4), with the static
  elastic-perfectly plastic curve; and, for the Example-1 section of 4.3 (steel, E = 30e6 psi,
  sigma0 = 29,000 psi, H = 0.177 in, B = 0.644 in) under the law (4.3.1) (Cowper-Symonds,
  D = 40/s, q = 5), the moment in lb in at physical curvature rates.
- 4.1.3: the approximations (4.1.14)-(4.1.17) against the exact curve (4.1.12), kappa_' = 1.
- 4.1.7: the dynamic yield surfaces (4.1.45)-(4.1.46) at several rates D, with the static
  surface |M_| + N_^2 = 1 and the high-rate ellipse 4 N_^2 + 3 M_^2 = D^2.
- 4.3.2-4.3.7: Examples 1, 2 and 3 of 4.3 at the report's data and steps (sub-stepped, scheme
  "damped-newmark"): the final configuration, at the tip's rest (its largest deflection,
  `barrierjax.beam.tip_rest`), and the tip's
  displacements, each with the law (4.3.1) and, dashed, its rate-independent limit. The
  report prints no numbers for these; its text says the tip mass makes the beam rotate nearly
  rigidly about a hinge at the root, and that without one the curvature spreads to the tip.
"""

from functools import cache

import jax.numpy as jnp
import numpy as np
from matplotlib.figure import Figure

from ..beam import report_example
from ..beam.plots import shape_figure, tip_figure
from ..beam.section import (
    moment_curvature,
    moment_curvature_bar,
    moment_elastic_plastic,
    moment_exponential,
    moment_limit,
    moment_rigid_plastic,
    static_moment,
    yield_surface,
)
from ..plotting import label_axes
from .registry import figure, title

EXAMPLE_1 = {"E": 30e6, "sigma0": 29_000.0, "depth": 0.177, "width": 0.644, "D": 40.0, "q": 5.0}
KAPPA_RATES_4_1 = (0.1, 0.5, 1.0, 2.0)  # dimensionless curvature rates E kappa' tau* h/sigma0
CURVATURE_RATES_EXAMPLE_1 = (0.1, 1.0, 10.0, 100.0)  # 1/(in s)
YIELD_RATES_4_1_7 = (0.0, 0.5, 1.0, 2.0)


@figure("4.1.2", "Moment Curvature Relation for Visco Plastic Material")
def _figure_4_1_2() -> Figure:
    fig = Figure(figsize=(11, 5), layout="constrained")
    left, right = fig.subplots(1, 2)
    kappa = jnp.linspace(0.01, 8.0, 400)
    left.plot(kappa, static_moment(kappa), color="k", label="static")
    for k, rate in enumerate(KAPPA_RATES_4_1):
        left.plot(kappa, moment_curvature_bar(kappa, rate), color=f"C{k}", label=f"{rate:g}")
        left.axhline(float(moment_limit(rate)), color=f"C{k}", ls=":", lw=0.8)
    left.set_title("linear law (4.1.2); dotted: the limits (4.1.13)", fontsize=9)
    label_axes(
        left,
        "curvature  E kappa h / sigma0",
        "M / M0",
        fontsize=8,
        title="E kappa' tau* h / sigma0",
    )

    example = EXAMPLE_1
    yield_curvature = 2 * example["sigma0"] / (example["E"] * example["depth"])
    full = example["sigma0"] * example["width"] * example["depth"] ** 2 / 4
    curvature = yield_curvature * kappa
    right.plot(curvature, full * static_moment(kappa), color="k", label="static")
    for k, rate in enumerate(CURVATURE_RATES_EXAMPLE_1):
        right.plot(
            curvature,
            moment_curvature(curvature, rate, **example),
            color=f"C{k}",
            label=f"{rate:g}",
        )
    right.set_title("Example-1 section, law (4.3.1): D = 40/s, q = 5", fontsize=9)
    label_axes(right, "curvature, 1/in", "M, lb in", fontsize=8, title="kappa', 1/(in s)")
    title(fig, "4.1.2", "constant curvature rate from rest (4.1.9)-(4.1.12)")
    return fig


@figure("4.1.3", "Different Approximation for the Moment Curvature Relation")
def _figure_4_1_3() -> Figure:
    fig = Figure(figsize=(9, 5.5), layout="constrained")
    ax = fig.subplots()
    rate = 1.0
    kappa = jnp.linspace(0.0, 8.0, 400)
    exact = moment_curvature_bar(jnp.maximum(kappa, 1e-6), rate)
    ax.plot(kappa, exact, color="k", lw=2, label="viscoplastic (4.1.12)")
    ax.plot(kappa, moment_rigid_plastic(kappa, rate), label="rigid, (4.1.14)")
    ax.plot(kappa, moment_elastic_plastic(kappa, rate), label="elastic, (4.1.15)")
    ax.plot(kappa, moment_exponential(kappa, rate), label="exponential, (4.1.16)")
    ax.plot(kappa, moment_exponential(kappa, rate, 0.65), label="(4.1.17), alpha = 0.65")
    label_axes(ax, "curvature  E kappa h / sigma0", "M / M0", fontsize=8)
    title(fig, "4.1.3", "E kappa' tau* h / sigma0 = 1 (alpha = 0.65 minimises the largest error)")
    return fig


@figure("4.1.7", "Dynamic Yield Surface for Bending and Extension")
def _figure_4_1_7() -> Figure:
    fig = Figure(figsize=(10, 7), layout="constrained")
    ax = fig.subplots()
    ratio = jnp.concatenate([jnp.linspace(0.0, 2.0, 200), 2.0 + jnp.geomspace(1e-3, 1e4, 300)])
    for k, rate in enumerate(YIELD_RATES_4_1_7):
        normal, moment = yield_surface(rate, ratio)
        ax.plot(normal, moment, color=f"C{k}", label=f"D = {rate:g}")
        if rate > 0:
            angle = np.linspace(0.0, np.pi / 2, 100)
            ax.plot(
                rate / 2 * np.cos(angle),
                rate / np.sqrt(3) * np.sin(angle),
                color=f"C{k}",
                ls=":",
                lw=0.8,
            )
    ax.set_xlim(0, None)
    ax.set_ylim(0, None)
    label_axes(ax, "N / N0", "M / M0", fontsize=8)
    title(
        fig,
        "4.1.7",
        "(4.1.45)-(4.1.46), D = (lambda_'^2 + (4/3) kappa_'^2)^1/2; dotted: 4N^2 + 3M^2 = D^2",
    )
    return fig


# --------------------------------------------------------------------------------------
# 4.3: the cantilever examples.


@cache
def example_runs(n: int) -> dict:
    """Example `n` with the law (4.3.1) and with its rate-independent limit, labelled."""
    return {
        "Cowper-Symonds (4.3.1)": report_example(n),
        "rate-independent": report_example(n, rate_dependent=False),
    }


def _configuration(number: str, n: int) -> Figure:
    fig = shape_figure(example_runs(n))
    title(fig, number, "thin: the law (4.3.1) at earlier times")
    return fig


def _tip(number: str, n: int) -> Figure:
    fig = tip_figure(example_runs(n))
    title(fig, number, "solid: the law (4.3.1); dashed: rate-independent; grey: the tip at rest")
    return fig


@figure("4.3.2", "Final Configuration of Example (1)")
def _figure_4_3_2() -> Figure:
    return _configuration("4.3.2", 1)


@figure("4.3.3", "Displacement of the Tip, Example (1)")
def _figure_4_3_3() -> Figure:
    return _tip("4.3.3", 1)


@figure("4.3.4", "Final Configuration of Example (2)")
def _figure_4_3_4() -> Figure:
    return _configuration("4.3.4", 2)


@figure("4.3.5", "Displacements of the Tip Mass, Example (2)", printed=False)
def _figure_4_3_5() -> Figure:
    return _tip("4.3.5", 2)


@figure("4.3.6", "Final Configuration of Example (3)", printed=False)
def _figure_4_3_6() -> Figure:
    return _configuration("4.3.6", 3)


@figure("4.3.7", "Displacements of the Free End, Example (3)", printed=False)
def _figure_4_3_7() -> Figure:
    return _tip("4.3.7", 3)
