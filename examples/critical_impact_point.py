"""The critical impact point of MASH test 3-11 on the MGS: the 2270P at 100 km/h and 25
degrees, its left front corner meeting the rail at points along it, every run in one vmap.

    python examples/critical_impact_point.py [out.png]

Prints each point's crash-test numbers (its place in the span: 0 at a post) and the worst
for the dynamic deflection, and plots the deflection, working width and OIV along the rail
(default critical_impact_point.png).
"""

import sys
from pathlib import Path

import jax

jax.config.update("jax_enable_x64", True)

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from barrierjax.system.critical import critical_impact_point
from barrierjax.system.scene import load_system_scene

SCENE = Path(__file__).resolve().parent / "mash_3_11.toml"


def main(out="critical_impact_point.png"):
    s = load_system_scene(SCENE)
    spacing = float(
        np.diff(np.asarray(s.barrier.rail.coords)[list(s.barrier.post_nodes[:2]), 0])[0]
    )
    points = np.arange(4.0, 37.0, 2.0)
    sweep = critical_impact_point(s.vehicle, s.barrier, points, speed=s.speed,
                                  angle_deg=s.angle_deg, duration=s.duration,
                                  friction=s.friction)  # fmt: skip
    n = {k: np.asarray(v) for k, v in sweep.numbers.items()}
    print("point m  in span  deflection m  working width m  exit deg  OIV x, y m/s   ORA x, y g")
    for i, p in enumerate(points):
        print(f"{p:7.1f}  {p % spacing / spacing:7.2f}  {n['dynamic_deflection'][i]:12.3f}  "
              f"{n['working_width'][i]:15.3f}  {n['exit_angle'][i]:8.1f}  "
              f"{n['oiv_x'][i]:5.2f} {n['oiv_y'][i]:5.2f}   "
              f"{n['ora_x'][i] / 9.80665:5.1f} {n['ora_y'][i] / 9.80665:5.1f}")  # fmt: skip
    print(
        f"critical impact point for the dynamic deflection: {float(sweep.critical):.1f} m "
        f"({float(np.max(sweep.values)):.3f} m; least {float(np.min(sweep.values)):.3f} m)"
    )
    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    axes[0].plot(points, n["dynamic_deflection"], "o-", label="dynamic deflection")
    axes[0].plot(points, n["working_width"], "s--", label="working width")
    axes[0].set_ylabel("m")
    axes[0].legend()
    axes[1].plot(points, n["oiv_x"], "o-", label="OIV x")
    axes[1].plot(points, n["oiv_y"], "s-", label="OIV y")
    axes[1].set_ylabel("m/s")
    axes[1].set_xlabel(f"impact point along the rail (m; posts every {spacing:.3f} m)")
    axes[1].legend()
    for ax in axes:
        for post in np.arange(0.0, points[-1] + spacing, spacing):
            ax.axvline(post, color="0.85", lw=0.8, zorder=0)
    fig.suptitle("MASH 3-11 on the MGS: the impact point")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print(f"wrote {out}")


if __name__ == "__main__":
    main(*sys.argv[1:])
