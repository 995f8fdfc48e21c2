"""Where chapter 3's rigid-plastic model and the elastic-plastic system model part.

    python benchmarks/chapter3_validity.py [--quick] [--out DIR]

The default scene's barrier and vehicle (barrierjax/default_scene.toml: M0 = 105.5 kN m,
m = 34.2 kg/m, q0 = 60 kN/m, M = 2270 kg, P0 = 450 kN) in both models: the report's
oblique impact (`barrierjax.hinge.oblique_impact`, rigid-plastic beam, backing and vehicle,
a point load) and `barrierjax.system.system_impact` on the same barrier built of the chapter
4 element on a continuous elastic-plastic backing, struck by a narrow vehicle
(`barrierjax.system.report_limit`). (1) The barrier's largest deflection over a grid of
normal impact speed (as the energy ratio, the vehicle's normal kinetic energy over the
barrier's elastic energy at collapse) and impact angle, as the system's difference from
the report's; (2) at the highest speed of the grid, head on, the system model's mesh
convergence. Writes `chapter3_validity.json` and `chapter3_validity.png` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import time

import jax.numpy as jnp
import numpy as np
from harness import argument_parser, pyplot, save_figure, table, write_json

from barrierjax.hinge.oblique import oblique_impact
from barrierjax.scene import Impact, Scene, dimensionless
from barrierjax.scene_file import default_scene
from barrierjax.system import stable_step, system_impact
from barrierjax.system.report_limit import backed_rail, energy_ratio, point_vehicle
from barrierjax.system.vehicle import contact_stiffness_bound

RAIL_LENGTH, IMPACT_POINT = 40.0, 12.0  # m: the hinges and the slide stay well inside


def report_deflection(scene, speeds, angles):
    """The report's largest deflection (m) and duration (s) for each (speed, angle)."""
    groups = dimensionless(Scene(scene.barrier, scene.vehicle, Impact(speeds, angles)))
    r = oblique_impact(groups.mass_ratio, groups.force_ratio, groups.normal_speed,
                       groups.tangential_speed)  # fmt: skip
    s = groups.scales
    return np.asarray(r.max_deflection * s.length), np.asarray(r.duration * s.time)


def system_deflection(scene, speeds, angles, element_length, duration):
    """The system model's largest deflection (m) and energy audit for each (speed, angle),
    one vmap."""
    rail = backed_rail(scene.barrier, length=RAIL_LENGTH, element_length=element_length)
    car = point_vehicle(scene.vehicle)
    dt = stable_step(rail, contact_stiffness_bound(car))

    @jax.jit
    def run(speed, angle):
        r = system_impact(car, rail, speed=speed, angle_deg=angle, impact_point=IMPACT_POINT,
                          duration=duration, dt=dt, save_every=50, friction=0.0)  # fmt: skip
        return r.dynamic_deflection, jnp.max(jnp.abs(r.history.energy_error))

    start = time.perf_counter()
    deflection, error = jax.block_until_ready(
        jax.vmap(run)(jnp.asarray(speeds), jnp.asarray(angles))
    )
    return np.asarray(deflection), np.asarray(error), time.perf_counter() - start, dt


def main():
    args = argument_parser(__doc__).parse_args()
    scene = default_scene()
    normal_speeds = np.array([2.0, 6.0, 16.0]) if args.quick else np.array(
        [1.5, 2.5, 4.0, 6.5, 10.0, 16.0])  # fmt: skip
    angles = np.array([90.0, 40.0]) if args.quick else np.array([90.0, 60.0, 40.0, 25.0])
    vn, angle = (a.ravel() for a in np.meshgrid(normal_speeds, angles, indexing="ij"))
    speed = vn / np.sin(np.radians(angle))
    ratio = np.array([
        float(energy_ratio(Scene(scene.barrier, scene.vehicle, Impact(s, a))))
        for s, a in zip(speed, angle)
    ])  # fmt: skip
    reference, duration = report_deflection(scene, speed, angle)
    element = 0.5 if args.quick else 0.25
    deflection, error, seconds, dt = system_deflection(
        scene, speed, angle, element, 1.2 * float(np.max(duration))
    )
    difference = deflection / reference - 1.0
    keys = ("vn", "angle", "speed", "ratio", "report", "system", "diff", "err")
    columns = (vn, angle, 3.6 * speed, ratio, reference, deflection, 100 * difference, error)
    rows = [dict(zip(keys, values, strict=True)) for values in zip(*columns, strict=True)]
    table(
        f"Largest deflection, report (rigid-plastic) and system (elastic-plastic, elements of "
        f"{element} m, dt {dt:.3g} s; {len(rows)} runs in one vmap, {seconds:.1f} s)",
        rows,
        [("normal speed m/s", "vn", ".1f"), ("angle deg", "angle", ".0f"),
         ("speed km/h", "speed", ".0f"), ("energy ratio", "ratio", ".3g"),
         ("report m", "report", ".4f"), ("system m", "system", ".4f"),
         ("difference %", "diff", "+.1f"), ("energy audit", "err", ".1e")],
    )  # fmt: skip

    # Mesh convergence, head on, at the highest speed.
    fastest = float(normal_speeds[-1])
    head_on_reference, head_on_duration = report_deflection(scene, fastest, 90.0)
    convergence = []
    for size in (0.5, 0.25) if args.quick else (0.5, 0.25, 0.125):
        d, e, s, step = system_deflection(
            scene, [fastest], [90.0], size, 1.2 * float(head_on_duration)
        )
        row = {"element": size, "dt": step, "system": float(d[0]), "error": float(e[0]), "s": s}
        convergence.append(row | {"diff": 100 * (row["system"] / float(head_on_reference) - 1)})
    table(
        f"Mesh convergence, head on at {fastest} m/s (report: {float(head_on_reference):.4f} m)",
        convergence,
        [("element m", "element", "g"), ("dt s", "dt", ".3g"), ("system m", "system", ".4f"),
         ("difference %", "diff", "+.2f"), ("energy audit", "error", ".1e"),
         ("wall s", "s", ".1f")],
    )  # fmt: skip
    write_json(args, "chapter3_validity", {"grid": rows, "mesh_convergence": convergence})
    if not args.no_plots:
        plt = pyplot()
        fig, ax = plt.subplots(figsize=(7, 4))
        shape = (len(normal_speeds), len(angles))
        image = ax.pcolormesh(np.arange(shape[0] + 1), np.arange(shape[1] + 1),
                              100 * difference.reshape(shape).T, cmap="RdBu_r", vmin=-50, vmax=50)  # fmt: skip
        for i in range(shape[0]):
            for j in range(shape[1]):
                ax.text(i + 0.5, j + 0.5, f"{100 * difference.reshape(shape)[i, j]:+.0f}",
                        ha="center", va="center", fontsize=8)  # fmt: skip
        ax.set_xticks(np.arange(shape[0]) + 0.5,
                      [f"{r:.2g}" for r in ratio.reshape(shape)[:, 0]])  # fmt: skip
        ax.set_yticks(np.arange(shape[1]) + 0.5, [f"{a:.0f}" for a in angles])
        ax.set_xlabel("energy ratio: normal kinetic energy / elastic energy at collapse")
        ax.set_ylabel("impact angle (deg)")
        ax.set_title("system model's largest deflection against chapter 3's (%)")
        fig.colorbar(image, ax=ax, label="%")
        print(f"wrote {save_figure(fig, args, 'chapter3_validity')}")


if __name__ == "__main__":
    main()
