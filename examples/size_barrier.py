"""Size a tube rail and its backing for least vehicle crush under a deflection limit.

    python examples/size_barrier.py [out.png]

Runs `barrierjax.design.optimize_default()` (gradients, checked against a brute-force
grid), prints its summary, and plots the mean crush over (depth d, backing strength q0)
at the optimum's wall thickness t, with the deflection limit, the line where the car
starts to yield the barrier, and both optima. Saves the figure to `out.png`
(default size_barrier.png).
"""

import argparse

import jax
import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

jax.config.update("jax_enable_x64", True)

from barrierjax import Impact, Scene, Vehicle, dimensionless
from barrierjax.design import SizingProblem, barrier, optimize_default, responses


def _slice(problem, t, n=201):
    """Mean crush, max deflection and the car's force ratio on a (d, q0) grid at t."""
    d = np.linspace(*np.asarray(problem.depth_bounds), n)
    q0 = np.geomspace(*np.asarray(problem.backing_bounds), n)
    dd, qq = np.meshgrid(d, q0, indexing="xy")
    x = jnp.stack([jnp.full(dd.size, t), jnp.asarray(dd.ravel()), jnp.asarray(qq.ravel())], axis=-1)
    car = problem.cases

    def one(v):
        damage, deflection = responses(problem, v)
        groups = dimensionless(
            Scene(
                barrier(problem, v), Vehicle(car.mass[0], car.crush_force[0]), Impact(car.speed[0])
            )
        )
        return jnp.mean(damage), jnp.max(deflection), groups.force_ratio

    f, w, phi = jax.jit(jax.vmap(one))(x)
    shape = dd.shape
    return d, q0, *(np.asarray(a).reshape(shape) for a in (f, w, phi))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("png", nargs="?", default="size_barrier.png", help="output PNG path")
    args = parser.parse_args()

    report = optimize_default()
    print(report.summary())

    problem = SizingProblem()
    d, q0, f, w, phi = _slice(problem, report.t)
    limit = float(problem.deflection_limit)

    fig, ax = plt.subplots(figsize=(8.0, 6.0), constrained_layout=True)
    levels = np.arange(0.0, 10.0 * np.ceil(100.0 * f.max()) + 10.0, 10.0)  # mm
    filled = ax.contourf(1e3 * d, 1e-3 * q0, 1e3 * f, levels=levels, cmap="viridis")
    fig.colorbar(filled, ax=ax, label="mean vehicle crush (mm)")
    ax.contourf(1e3 * d, 1e-3 * q0, w, levels=[limit, np.inf], colors="none", hatches=["//"])
    boundary = ax.contour(1e3 * d, 1e-3 * q0, w, levels=[limit], colors="red", linewidths=2.0)
    ax.clabel(boundary, fmt={limit: f"max deflection = {limit:g} m"}, fontsize=9)
    yields = ax.contour(1e3 * d, 1e-3 * q0, phi, levels=[1.0], colors="white", linestyles="--")
    ax.clabel(yields, fmt={1.0: "car: phi = 1 (rigid above)"}, fontsize=9)
    ax.plot(
        1e3 * report.d,
        1e-3 * report.q0,
        marker="*",
        markersize=18,
        color="orange",
        markeredgecolor="black",
        linestyle="none",
        clip_on=False,
        zorder=5,
        label=f"gradient optimum: {1e3 * report.objective:.3f} mm",
    )
    ax.plot(
        1e3 * report.grid_d,
        1e-3 * report.grid_q0,
        marker="x",
        markersize=12,
        mew=2.5,
        color="magenta",
        linestyle="none",
        clip_on=False,
        zorder=6,
        label=f"grid best (t = {1e3 * report.grid_t:.3f} mm): {1e3 * report.grid_objective:.3f} mm",
    )
    ax.set_yscale("log")
    ax.set_xlabel("rail depth d (mm)")
    ax.set_ylabel("backing strength q0 (kN/m)")
    ax.set_title(
        f"Mean crush at t = {1e3 * report.t:.2f} mm (hatched: deflection over {limit:g} m)\n"
        f"relative difference gradient / grid - 1 = {100 * report.relative_difference:+.3f} %"
    )
    ax.annotate(
        "optimum: lightest rail in the box,\nbacking just strong enough",
        xy=(1e3 * report.d, 1e-3 * report.q0),
        xytext=(140.0, 1.8e-3 * report.q0),
        color="white",
        fontsize=9,
        arrowprops={"arrowstyle": "->", "color": "white"},
    )
    ax.legend(loc="lower right", framealpha=0.9)
    fig.savefig(args.png, dpi=120)
    print(f"saved {args.png}")


if __name__ == "__main__":
    main()
