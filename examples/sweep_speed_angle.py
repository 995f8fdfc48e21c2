"""Damage and occupant risk of the default barrier over impact speed and angle: the oblique
impact of report 3.3 on a grid of scenarios, solved as one batch, assessed as one batch.

    python examples/sweep_speed_angle.py [out.png]

The default scene's barrier and vehicle (barrierjax/default_scene.toml: a 2270 kg pickup
against a steel tube on foam) at 30-110 km/h and 10-80 degrees: the vehicle's crush, the
barrier's largest deflection, and the occupant impact velocity and ridedown acceleration
(`barrierjax.assess`, MASH's flail space) of each, drawn as maps with MASH's OIV limit.
"""

import sys

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from barrierjax import Impact, Scene, simulate
from barrierjax.assess import assess
from barrierjax.scene_file import default_scene


def main(out="sweep_speed_angle.png"):
    s = default_scene()
    speeds_kmh = np.linspace(30.0, 110.0, 9)
    angles = np.linspace(10.0, 80.0, 8)
    speed, angle = (a.ravel() for a in np.meshgrid(speeds_kmh / 3.6, angles, indexing="ij"))
    scene = Scene(s.barrier, s.vehicle, Impact(jnp.asarray(speed), jnp.asarray(angle)))
    result = simulate(scene, n_history=400, oblique=True)
    risk = assess(result)
    shape = (len(speeds_kmh), len(angles))
    maps = {
        "vehicle crush (m)": result.damage,
        "largest deflection (m)": result.max_deflection,
        "OIV, resultant (m/s)": jnp.hypot(risk.oiv_x, risk.oiv_y),
        "ORA, larger component (g)": jnp.maximum(jnp.abs(risk.ora_x), jnp.abs(risk.ora_y))
        / 9.80665,
    }
    fig, axes = plt.subplots(2, 2, figsize=(10, 7), sharex=True, sharey=True)
    for ax, (title, values) in zip(axes.ravel(), maps.items(), strict=True):
        grid = np.asarray(values).reshape(shape).T
        image = ax.contourf(speeds_kmh, angles, grid, levels=12, cmap="viridis")
        fig.colorbar(image, ax=ax)
        if title.startswith("OIV"):
            ax.contour(speeds_kmh, angles, grid, levels=[12.2], colors="w", linewidths=2)
        ax.set_title(title)
    for ax in axes[1]:
        ax.set_xlabel("impact speed (km/h)")
    for ax in axes[:, 0]:
        ax.set_ylabel("impact angle (deg)")
    fig.suptitle("Default barrier, 2270 kg pickup (report 3.3; white: MASH's OIV limit 12.2 m/s)")
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    worst = int(np.argmax(np.asarray(maps["OIV, resultant (m/s)"])))
    print(
        f"{len(speed)} scenarios; the largest OIV {float(maps['OIV, resultant (m/s)'][worst]):.2f} "
        f"m/s at {speed[worst] * 3.6:.0f} km/h and {angle[worst]:.0f} deg; wrote {out}"
    )


if __name__ == "__main__":
    main(*sys.argv[1:])
