"""What a tolerance costs and what it gives: the oblique model on the field's vehicles.

    python benchmarks/tolerance.py [--quick] [--out DIR] [--seed N]

`barrierjax sweep --rtol R` and `barrierjax run --rtol R` set the impact models' relative
tolerance (default 1e-8). Scenarios of `examples/oblique_scene.toml`'s barrier (the default
tube rail on its foam backing) as its sweep in the README draws them: mass 1,000-40,000 kg
(cars to articulated trucks), crush force 250-700 kN (either side of the barrier's
P_b = 318 kN), 5-40 degrees, 100 km/h; uniform, `--seed`. For each rtol:

- the errors, against the same scenarios solved at rtol 1e-12 (64 of them; 16 with
  `--quick`): the relative error of the exit angle, the exit speed, the duration, the
  damage (the barrier's final displacement) and the largest deflection, median and largest
  over the scenarios, and the accepted steps a scenario;
- the cost of a batch of 4,096 (256 with `--quick`) through `simulate`, as a sweep's chunk
  runs: the first call and the peak memory of a fresh process, and the steady time a
  scenario (best of 2 calls after the first). A scenario that no step budget solves
  (phi - 1 ~ 1e-5) raises after the batch is solved, as in a sweep: its cost is counted.

The tolerance is traced: every rtol runs the same compiled programs. Writes
`tolerance.json`.
"""

import numpy as np
from harness import HERE, argument_parser, first_call, table, write_json

TOLERANCES = (1e-8, 1e-7, 1e-6, 1e-5, 1e-4)
REFERENCE = 1e-12
FIELDS = ("exit_angle_deg", "exit_speed", "duration", "damage", "max_deflection")
SCENE = HERE.parent / "examples" / "oblique_scene.toml"

_RANGES = ((1000.0, 40000.0), (250e3, 700e3), (5.0, 40.0))  # mass kg, crush force N, deg

# The child's snippet: the same scenes, and a chunk's solve as a sweep runs it.
_SETUP = """
    import jax.numpy as jnp
    from barrierjax import simulate
    from barrierjax.hinge import SolveError
    from tolerance import scenes
    scene = scenes({n}, {seed})

    def solve(rtol):
        # (A scenario that no budget solves, phi - 1 ~ 1e-5, raises after the batch is
        # solved, as a sweep's chunk does; `--skip-failures` then keeps the others.)
        try:
            return simulate(scene, n_history=0, rtol=rtol).exit_angle_deg
        except SolveError:
            return jnp.zeros(())
"""


def scenes(n: int, seed: int):
    """`n` vehicles drawn uniformly within `_RANGES` on `SCENE`'s barrier, as one batch."""
    import jax.numpy as jnp

    from barrierjax import Impact, Scene, Vehicle, load_scene

    base = load_scene(SCENE)
    rng = np.random.default_rng(seed)
    mass, crush, angle = (jnp.asarray(rng.uniform(lo, hi, n)) for lo, hi in _RANGES)
    vehicle = Vehicle(mass, crush)
    return Scene(base.barrier, vehicle, Impact(base.impact.speed, angle, base.impact.friction))


def errors(n: int, seed: int) -> list:
    from barrierjax import simulate

    scene = scenes(n, seed)
    solve = lambda rtol: simulate(scene, n_history=0, rtol=rtol)
    reference = solve(REFERENCE)
    rows = []
    for rtol in TOLERANCES:
        result = solve(rtol)
        row = dict(rtol=rtol, steps=float(np.mean(result.model.steps)))
        for name in FIELDS:
            exact = np.asarray(getattr(reference, name))
            difference = np.abs(np.asarray(getattr(result, name)) - exact)
            # (A vehicle that leaves parallel to the barrier has an exit angle of 0 in both.)
            error = np.divide(difference, np.abs(exact), out=np.zeros_like(exact),
                              where=difference > 0.0)  # fmt: skip
            row[f"{name}_median"], row[f"{name}_max"] = float(np.median(error)), float(error.max())
        rows.append(row)
        print(f"  rtol {rtol:g}: {row['steps']:.0f} steps a scenario, exit angle within "
              f"{row['exit_angle_deg_max']:.1e}", flush=True)  # fmt: skip
    return rows


def costs(n: int, seed: int) -> list:
    rows = []
    for rtol in TOLERANCES:
        call = f"solve({rtol!r})"
        result = first_call(_SETUP.format(n=n, seed=seed), call, timeout=900.0, steady_reps=2)
        row = dict(rtol=rtol, n=n, **result)
        if result["ok"]:
            row["us"] = result["steady_s"] / n * 1e6
            print(f"  rtol {rtol:g}: {result['first_call_s']:.1f} s first, {row['us']:.1f} us "
                  f"a scenario, {result['peak_rss_mb']:.0f} MB", flush=True)  # fmt: skip
        else:
            print(f"  rtol {rtol:g}: FAILED {result['failure']}", flush=True)
        rows.append(row)
    return rows


def main():
    args = argument_parser(__doc__).parse_args()
    import jax

    jax.config.update("jax_enable_x64", True)
    n_errors, n_costs = (16, 256) if args.quick else (64, 4096)
    print(f"errors of {n_errors} scenarios against rtol {REFERENCE:g}:")
    accuracy = errors(n_errors, args.seed)
    print(f"cost of {n_costs} scenarios, fresh processes:")
    cost = costs(n_costs, args.seed)
    rows = [a | {k: c.get(k) for k in ("first_call_s", "us", "peak_rss_mb")}
            for a, c in zip(accuracy, cost)]  # fmt: skip
    default = rows[0]
    for row in rows:
        row["speed_up"] = default["us"] / row["us"] if row.get("us") and default.get("us") else None
    table(
        f"The oblique model on the field's vehicles (mass 1,000-40,000 kg, 250-700 kN, 5-40 deg, "
        f"100 km/h): relative errors against rtol {REFERENCE:g} ({n_errors} scenarios, median / "
        f"largest), cost of {n_costs} in a fresh process",
        rows,
        [("rtol", "rtol", "g"), ("steps", "steps", ".0f")]
        + [(f"{name} {stat}", f"{name}_{stat}", ".1e") for name in FIELDS[:3] + FIELDS[4:]
           for stat in ("median", "max")]  # fmt: skip
        + [("damage max", "damage_max", ".1e"), ("first call s", "first_call_s", ".1f"),
           ("us a scenario", "us", ".0f"), ("speed-up", "speed_up", ".2f"),
           ("peak MB", "peak_rss_mb", ".0f")],  # fmt: skip
    )
    for row in rows:
        if row.get("speed_up"):
            print(f"SUMMARY: rtol {row['rtol']:g}: {row['speed_up']:.2f} times the default's "
                  f"speed, exit angle within {row['exit_angle_deg_max']:.1e} relative")  # fmt: skip
    write_json(args, "tolerance", {"rows": rows, "n_errors": n_errors, "n_costs": n_costs})


if __name__ == "__main__":
    main()
