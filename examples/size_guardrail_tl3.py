"""Size a W-beam guardrail on posts for MASH TL-3: the least steel per metre of barrier
that keeps the 2270P's working width (test 3-11) within a site's limit, with both tests
of the level (3-10, the 1100C; 3-11, the 2270P; 100 km/h, 25 degrees) contained and
within MASH's occupant-risk limits. The barrier-system model (`barrierjax.system`): the
MGS preset, its post spacing and its rail's wall thickness changed by
`system.design.redesign`, every design of the grid and both tests in one `jax.vmap` each.

    python examples/size_guardrail_tl3.py [--limit 1.0] [out.png]

The steel per metre is the rail's (its section area times the thickness ratio, 7850
kg/m^3) plus a post per spacing: a W6x8.5 (8.5 lb/ft by its designation) 6 ft long,
23.1 kg (the MGS's standard post; the blockout and hardware left out). A brute-force grid
is the answer here, not the gradient optimiser of `barrierjax.design`: the script checks
the working width's gradient against finite differences at the chosen design and prints
how far apart they are (over a whole impact, with posts failing and the vehicle sliding
along the rail, the crash numbers are rough in the spacing: the README says how much).
MASH's exit box is not judged (see `barrierjax.system.assessment`).
"""

import argparse
import time
from pathlib import Path
from types import SimpleNamespace

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from barrierjax.assess.verdict import judge
from barrierjax.system.barrier import stable_step
from barrierjax.system.design import crash_numbers, redesign
from barrierjax.system.scene import load_system_scene
from barrierjax.system.vehicle import contact_stiffness_bound

HERE = Path(__file__).resolve().parent
TESTS = {"MASH 3-10": HERE / "mash_3_10.toml", "MASH 3-11": HERE / "mash_3_11.toml"}
STEEL = 7850.0  # kg/m^3
POST_KG = 8.5 * 0.45359237 / 0.3048 * 6 * 0.3048  # W6x8.5, 6 ft: 23.1 kg
# Half to twice the MGS's 1.905 m (75 in); 0.75 to 1.6 times 12 gauge's 2.67 mm wall
# (10 gauge, 3.42 mm, is 1.28).
SPACINGS = np.linspace(0.9525, 3.81, 7)
THICKNESS = np.array([0.75, 1.0, 1.28, 1.6])


def numbers_of(scene, dt):
    """The crash-test numbers of `scene`'s test as a function of (spacing, thickness)."""

    def one(spacing, thickness):
        vehicle, barrier = redesign(scene.vehicle, scene.barrier, post_spacing=spacing,
                                    rail_thickness_ratio=thickness)  # fmt: skip
        return crash_numbers(vehicle, barrier, speed=scene.speed, angle_deg=scene.angle_deg,
                             impact_point=scene.impact_point, duration=scene.duration,
                             dt=dt, friction=scene.friction)  # fmt: skip

    return one


def steel_per_metre(scene, spacing, thickness):
    rail = float(jnp.asarray(scene.barrier.rail.section.area).ravel()[0]) * STEEL
    return rail * thickness + POST_KG / spacing


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", nargs="?", default="size_guardrail_tl3.png")
    parser.add_argument("--limit", type=float, default=1.0, help="working width limit, m")
    args = parser.parse_args(argv)
    scenes = {name: load_system_scene(path) for name, path in TESTS.items()}
    s, t = (a.ravel() for a in np.meshgrid(SPACINGS, THICKNESS, indexing="ij"))
    # One step for every design: the stable step of the shortest spacing, stiffest contact.
    _, stiffest = redesign(scenes["MASH 3-11"].vehicle, scenes["MASH 3-11"].barrier,
                           post_spacing=float(SPACINGS[0]))  # fmt: skip
    dt = min(stable_step(stiffest, contact_stiffness_bound(c.vehicle)) for c in scenes.values())
    grid = {}
    for name, scene in scenes.items():
        start = time.perf_counter()
        run = jax.jit(jax.vmap(numbers_of(scene, dt)))
        grid[name] = {k: np.asarray(v) for k, v in run(jnp.asarray(s), jnp.asarray(t)).items()}
        print(f"{name}: {s.size} designs in {time.perf_counter() - start:.1f} s "
              f"(compilation included; dt {dt:.2e} s)")  # fmt: skip
    ww = grid["MASH 3-11"]["working_width"]
    # Contained, and MASH's OIV and ORA maxima (criteria H, I) met, in both tests.
    meets_mash = lambda n, i: (
        bool(n["contained"][i])
        and all(c.passed for c in judge(SimpleNamespace(**{k: v[i] for k, v in n.items()})))
    )
    feasible = (ww <= args.limit) & np.array(
        [all(meets_mash(n, i) for n in grid.values()) for i in range(s.size)]
    )
    mass = steel_per_metre(scenes["MASH 3-11"], s, t)
    print("\nspacing m  thickness  steel kg/m  3-11 WW m  3-10 WW m  OIV max m/s  ORA max g  ok")
    for i in range(s.size):
        oiv = max(max(abs(g["oiv_x"][i]), abs(g["oiv_y"][i])) for g in grid.values())
        ora = max(max(g["ora_x"][i], g["ora_y"][i]) for g in grid.values()) / 9.80665
        print(f"{s[i]:9.3f}  {t[i]:9.2f}  {mass[i]:10.1f}  {ww[i]:9.3f}  "
              f"{grid['MASH 3-10']['working_width'][i]:9.3f}  {oiv:11.2f}  {ora:9.1f}  "
              f"{'yes' if feasible[i] else 'no'}")  # fmt: skip
    mgs = np.argmin(np.abs(s - 1.905) + np.abs(t - 1.0))
    print(
        f"\nthe MGS as built (1.905 m, 12 gauge): {mass[mgs]:.1f} kg/m, 3-11 working width "
        f"{ww[mgs]:.3f} m ({'meets' if feasible[mgs] else 'fails'} the {args.limit:g} m limit)"
    )
    if not feasible.any():
        print(f"no design of the grid meets a {args.limit:g} m working width")
        return 1
    best = int(np.argmin(np.where(feasible, mass, np.inf)))
    print(
        f"least steel meeting every criterion: spacing {s[best]:.3f} m, thickness "
        f"{t[best]:.2f} x 12 gauge, {mass[best]:.1f} kg/m, working width {ww[best]:.3f} m"
    )
    check_gradient(numbers_of(scenes["MASH 3-11"], dt), s[best], t[best])
    plot(s, t, ww, mass, feasible, best, mgs, args)
    return 0


def check_gradient(numbers, spacing, thickness, rel_steps=(1e-3, 1e-2)):
    """The 3-11 working width's gradient (forward mode) against central differences of
    two step sizes (which disagree with each other where the function is rough)."""
    width = lambda x: numbers(x[0], x[1])["working_width"]
    x = jnp.array([spacing, thickness])
    gradient = np.asarray(jax.jit(jax.jacfwd(width))(x))
    at = jax.jit(width)
    for k, name in enumerate(("spacing", "thickness")):
        differences = []
        for rel in rel_steps:
            step = jnp.zeros(2).at[k].set(rel * float(x[k]))
            fd = (float(at(x + step)) - float(at(x - step))) / (2 * rel * float(x[k]))
            differences.append(f"{fd:+.4f} (step {rel:g} x)")
        print(
            f"d(working width)/d({name}): gradient {gradient[k]:+.4f}; central differences "
            + ", ".join(differences)
        )


def plot(s, t, ww, mass, feasible, best, mgs, args):
    shape = (SPACINGS.size, THICKNESS.size)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    pad = lambda v: (v[0] - 0.04 * np.ptp(v), v[-1] + 0.04 * np.ptp(v))  # edge points whole
    for ax, values, label in ((axes[0], ww, "MASH 3-11 working width (m)"),
                              (axes[1], mass, "steel per metre (kg/m)")):  # fmt: skip
        filled = ax.contourf(SPACINGS, THICKNESS, values.reshape(shape).T, levels=12)
        fig.colorbar(filled, ax=ax, label=label)
        ax.contour(SPACINGS, THICKNESS, ww.reshape(shape).T, levels=[args.limit], colors="w",
                   linewidths=2)  # fmt: skip
        ax.plot(s[feasible], t[feasible], "wo", ms=5, label="meets every criterion")
        ax.plot(s[~feasible], t[~feasible], "kx", ms=5, label="fails one")
        ax.plot(s[mgs], t[mgs], "s", mfc="none", mec="r", ms=11, label="the MGS as built")
        ax.plot(s[best], t[best], "*", color="gold", mec="k", ms=16, label="least steel")
        ax.set_xlabel("post spacing (m)")
        ax.set_xlim(*pad(SPACINGS))
        ax.set_ylim(*pad(THICKNESS))
    axes[0].set_ylabel("wall thickness / 12 gauge (2.67 mm)")
    axes[0].set_title(f"white line: the {args.limit:g} m limit", fontsize=9)
    axes[1].legend(fontsize=8, loc="upper right")
    fig.suptitle("Sizing a W-beam guardrail for MASH TL-3 (barrier-system model)")
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    raise SystemExit(main())
