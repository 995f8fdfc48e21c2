"""Size the default barrier for MASH TL-3 over real-world impacts, and look at why the
optimum is where it is.

    python examples/size_barrier_tl3.py [out.png]

`barrierjax.design.optimize_robust` (what `barrierjax optimize --level MASH-TL3` runs): the
rail's wall thickness and the backing's crush strength that give the least expected crush
over the Interstate impacts of NCHRP Report 665 with MASH tests 3-10 and 3-11 passing. Then
two plots: the expected crush over the design box with the boundary where test 3-11
deflects the barrier by the limit (the feasible side shaded), the gradient optimum, the
brute force's best and the default scene's barrier; and the crush of every real-world
impact (equally probable slices of severity and mass) against the optimum and against the
default scene's barrier, as distributions. About 2 minutes on 2 cores.
"""

import sys

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from barrierjax.design import (
    RobustSizing,
    damages,
    optimize_robust,
    rail_barrier,
    robust_formulation,
)
from barrierjax.scene_file import default_scene


def main(out="size_barrier_tl3.png"):
    scene = default_scene()
    problem = RobustSizing("MASH TL-3", deflection_limit=0.6)
    report = optimize_robust(problem, scene.barrier, baseline_name="default scene", progress=print)
    print(report.summary())

    form = robust_formulation(problem)
    n = 61
    axis = jnp.linspace(0.0, 1.0, n)
    u = jnp.stack(jnp.meshgrid(axis, axis, indexing="ij"), axis=-1).reshape(-1, 2)
    crush, g = jax.jit(jax.vmap(lambda v: form.measure(form.problem, v)))(u)
    x = jax.vmap(lambda v: form.design(form.problem, v))(u)
    t_mm = np.asarray(x[:, 0]).reshape(n, n) * 1e3
    q0_kn = np.asarray(x[:, 1]).reshape(n, n) * 1e-3
    crush_mm = np.asarray(crush).reshape(n, n) * 1e3
    worst = np.asarray(jnp.max(g, axis=-1)).reshape(n, n)

    fig, (left, right) = plt.subplots(1, 2, figsize=(12.5, 5.0))
    levels = np.linspace(crush_mm.min(), crush_mm.max(), 25)
    filled = left.contourf(t_mm, q0_kn, crush_mm, levels=levels, cmap="viridis")
    fig.colorbar(filled, ax=left, label="expected crush over real-world impacts (mm)")
    left.contour(t_mm, q0_kn, worst, levels=[0.0], colors="white", linewidths=2)
    left.contourf(t_mm, q0_kn, worst, levels=[worst.min(), 0.0], colors="none", hatches=["//"])
    left.plot(1e3 * report.t, 1e-3 * report.q0, "r*", ms=16, label="gradient optimum")
    left.plot(1e3 * report.grid_t, 1e-3 * report.grid_q0, "o", mec="orange", mfc="none", ms=13, mew=2,
              label="brute force's best")  # fmt: skip
    tube_t = 6.35  # the default scene's HSS 203x152x6.4 (barrierjax/default_scene.toml)
    left.plot(tube_t, float(scene.barrier.backing_strength) * 1e-3, "ks", ms=9,
              label="default scene")  # fmt: skip
    left.set_yscale("log")
    left.set_xlabel("rail wall thickness t (mm)")
    left.set_ylabel("backing crush strength q0 (kN/m)")
    left.set_title("MASH TL-3 feasible (hatched): test 3-11 deflects at most 0.6 m")
    left.legend(loc="upper right", fontsize=8)

    weights = np.full(problem.impact_mass.shape[0], 1.0 / problem.impact_mass.shape[0])
    barriers = {
        f"optimum (E = {1e3 * report.optimum.expected_damage:.1f} mm)": rail_barrier(
            problem, jnp.array([report.t, report.q0])
        ),
        f"default scene (E = {1e3 * report.baseline.expected_damage:.1f} mm)": scene.barrier,
    }
    for label, barrier in barriers.items():
        values = np.asarray(damages(problem, barrier)[0]) * 1e3
        order = np.argsort(values)
        right.step(values[order], np.cumsum(weights[order]), where="post", label=label)
    right.set_xscale("log")
    right.set_xlabel("vehicle crush in a real-world impact (mm)")
    right.set_ylabel("share of Interstate impacts with at most this crush")
    right.set_title("Crush over NCHRP Report 665's Interstate impacts")
    right.grid(alpha=0.3)
    right.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
