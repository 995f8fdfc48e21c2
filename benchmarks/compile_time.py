"""The cost of a first answer: every public model's first call in a fresh process.

For each model, forward and gradient, on one scenario and on a batch: the wall time of the
first call in a fresh Python process with no persistent compilation cache (tracing,
compilation and one run), the steady-state time of the same call afterwards in that
process (the best of a few), and the process's peak resident memory. A user who calls a
model once pays the first column; a sweep pays the second.

    python benchmarks/compile_time.py [--quick] [--before PATH] [--only WORD ...] [--jobs N]

The last rows time a batch of another size after a first batch (run in the setup, not
timed): what a second sweep of a script waits for.

`--before PATH`: also run every case with the `barrierjax` package of another checkout
(a folder holding `barrierjax/`, e.g. `git worktree add /tmp/before <commit>`), side by
side in the table. `--only`: the cases whose label contains one of the words. `--jobs N`:
run N cases at a time, each in its own process (for a machine with many cores, such as a
lent GPU's 16: the processes share the cores and the accelerator, so the times are an upper
bound of those run one at a time).
"""

from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from harness import argument_parser, first_call, table, write_json

_MASH_3_11 = Path(__file__).resolve().parent.parent / "examples" / "mash_3_11.toml"

_NORMAL = """
    import jax, jax.numpy as jnp
    from barrierjax.hinge import normal_impact
    mus = jnp.geomspace(0.1, 50.0, {batch})
    one = lambda mu: normal_impact(mu, 3.0, 0.5, {options}).damage
    many = lambda mus: normal_impact(mus, 3.0, 0.5, {options}).damage
"""
_AXIAL = """
    import jax, jax.numpy as jnp
    from barrierjax.hinge import axial_impact
    mus = jnp.geomspace(0.2, 2.0, {batch})
    one = lambda mu: axial_impact(mu, 2.0, 1.0, axial_ratio=5.0).barrier_displacement
    many = lambda mus: axial_impact(mus, 2.0, 1.0, axial_ratio=5.0).barrier_displacement
"""
_OBLIQUE = """
    import jax, jax.numpy as jnp
    from barrierjax.hinge import oblique_impact
    mus = jnp.geomspace(0.5, 8.0, {batch})
    one = lambda mu: oblique_impact(mu, 2.0, 0.3, 0.5, friction=0.1).exit_angle_deg
    many = lambda mus: oblique_impact(mus, 2.0, 0.3, 0.5, friction=0.1).exit_angle_deg
"""
_BEAM = """
    import math, jax, jax.numpy as jnp
    from barrierjax.beam.examples import EXAMPLES, example_model
    from barrierjax.beam.integrate import integrate
    data = EXAMPLES[1]
    dts = jnp.full({steps}, data["dt"] / math.ceil(data["dt"] / data["max_substep"]))
    tip = lambda s0: integrate(example_model(1, sigma0=s0), dts, scheme="damped-newmark").displacement[-1, -2]
    s0s = float(data["sigma0"]) * jnp.linspace(0.8, 1.2, {batch})
    one, many = tip, jax.vmap(tip)
"""
# The barrier system on MASH 3-11 (0.6 s of impact, the scene's step): the peak dynamic
# deflection against the impact speed. Its batch is 4 variants: a run costs about half a
# second after compilation.
_SYSTEM = """
    import jax, jax.numpy as jnp
    from barrierjax.system import system_impact
    from barrierjax.system.scene import load_system_scene
    s = load_system_scene({scene!r})
    def deflection(speed):
        return system_impact(s.vehicle, s.barrier, speed=speed, angle_deg=s.angle_deg,
                             impact_point=s.impact_point, duration=0.6,
                             friction=s.friction).dynamic_deflection
    speeds = s.speed * jnp.linspace(0.9, 1.1, {batch})
    one, many = deflection, jax.vmap(deflection)
"""
# Occupant risk of a record of 1 s at 10 kHz (a half-sine pulse of 100 ms on ax, and 0.3 of
# it on ay): the OIV against the pulse's amplitude in g; a batch is records side by side.
_OCCUPANT = """
    import jax, jax.numpy as jnp
    from barrierjax.assess import occupant_risk
    t = jnp.arange(10_001) * 1e-4
    pulse = 9.80665 * jnp.where(t < 0.1, jnp.sin(jnp.pi * t / 0.1), 0.0)
    risk = lambda g: occupant_risk(t, -g[..., None] * pulse, 0.3 * g[..., None] * pulse)
    one = many = lambda g: risk(jnp.asarray(g)).oiv_x
    gs = jnp.linspace(5.0, 25.0, {batch})
"""
_MATERIAL = """
    import jax, jax.numpy as jnp
    from barrierjax import materials
    strain = jnp.linspace(0.0, 0.02, 257)
    def stress(sigma0):
        law = materials.CowperSymonds(E=200e9, sigma0=sigma0, D=40.0, q=5.0)
        return materials.uniaxial_response(law, strain / 100.0, strain, method="implicit").stress[-1]
    s0s = jnp.linspace(200e6, 300e6, {batch})
    one, many = stress, jax.vmap(stress)
"""


def cases(quick: bool) -> dict:
    """{label: (setup, call)}: forward and gradient, one scenario and a batch, per model."""
    batch = 10 if quick else 100
    models = {
        "normal, closed form": (_NORMAL.format(batch=batch, options='method="closed_form"'), "2.0", "mus"),
        "normal, ODE": (_NORMAL.format(batch=batch, options='method="ode"'), "2.0", "mus"),
        "axial (3.4)": (_AXIAL.format(batch=batch), "0.5", "mus"),
        "oblique (3.3)": (_OBLIQUE.format(batch=batch), "5.0", "mus"),
        "beam, Example 1": (_BEAM.format(batch=4 if quick else 16, steps=20 if quick else 200), "s0s[0]", "s0s"),
        "uniaxial, Cowper-Symonds": (_MATERIAL.format(batch=batch), "250e6", "s0s"),
        "barrier system, MASH 3-11": (
            _SYSTEM.format(batch=2 if quick else 4, scene=str(_MASH_3_11)), "s.speed", "speeds"
        ),
        "occupant risk": (_OCCUPANT.format(batch=batch), "15.0", "gs"),
    }
    out = {}
    for name, (setup, scalar, array) in models.items():
        out[f"{name}: forward, one"] = (setup, f"one({scalar})")
        out[f"{name}: forward, batch"] = (setup, f"many({array})")
        out[f"{name}: gradient, one"] = (setup, f"jax.grad(one)({scalar})")
        out[f"{name}: gradient, batch"] = (setup, f"jax.grad(lambda x: many(x).sum())({array})")
    # The gradient a sizing script writes first: a vmap of the scalar gradient.
    out["oblique (3.3): vmap of the gradient, 10"] = (_OBLIQUE.format(batch=10), "jax.vmap(jax.grad(one))(mus)")
    # A sweep of another size after a first one (the first in the setup): batches are solved
    # at padded sizes, so that this one need not compile again.
    for name in ("normal, ODE", "axial (3.4)", "oblique (3.3)"):
        setup, _, array = models[name]
        warmed = setup + f"    jax.block_until_ready(many({array})); {array} = {array}[:-{batch // 10}]\n"
        out[f"{name}: forward, a second batch size ({batch - batch // 10} after {batch})"] = (
            warmed, f"many({array})"
        )
    return out


def run(selected: dict, package=None, reps=3, jobs=1) -> list:
    def one(label: str) -> dict:
        setup, call = selected[label]
        result = first_call(setup, call, timeout=900.0, rss_limit_gb=12.0, steady_reps=reps, package=package)
        print(f"  {label}: " + (f"{result['first_call_s']:.1f} s first, {result['peak_rss_mb']:.0f} MB"
                                 if result["ok"] else f"FAILED: {result['failure']}"), flush=True)
        return dict(case=label, **result)

    with ThreadPoolExecutor(max_workers=jobs) as pool:
        return list(pool.map(one, selected))


def main(argv=None):
    parser = argument_parser(__doc__)
    parser.add_argument("--before", type=Path, help="a folder holding another checkout's barrierjax/")
    parser.add_argument("--only", nargs="*", default=(), help="cases whose label holds one of these words")
    parser.add_argument("--jobs", type=int, default=1, help="cases run at a time, each in its own process")
    args = parser.parse_args(argv)
    selected = {k: v for k, v in cases(args.quick).items() if not args.only or any(w in k for w in args.only)}
    print("after (this checkout):")
    after = run(selected, reps=1 if args.quick else 3, jobs=args.jobs)
    data = {"first_call": after}
    columns = [("case", "case", "s"), ("first call s", "first_call_s", ".1f"),
               ("steady s", "steady_s", ".2e"), ("peak RSS MB", "peak_rss_mb", ".0f")]
    if args.before:
        print(f"before ({args.before}):")
        before = run(selected, package=args.before.resolve(), reps=1 if args.quick else 3, jobs=args.jobs)
        data["before"] = before
        for row, old in zip(after, before):
            row.update(before_first_call_s=old.get("first_call_s"), before_steady_s=old.get("steady_s"),
                       before_peak_rss_mb=old.get("peak_rss_mb"))
            if not old["ok"]:
                row["before_first_call_s"] = "FAILED"
        columns = [columns[0], ("first call s: before", "before_first_call_s", ".1f"), columns[1],
                   ("steady s: before", "before_steady_s", ".2e"), columns[2],
                   ("peak MB: before", "before_peak_rss_mb", ".0f"), columns[3]]
    table("First call in a fresh process (imports apart; no persistent cache), steady state, peak memory",
          after, columns)
    slowest = max((r for r in after if r["ok"]), key=lambda r: r["first_call_s"])
    print(f"\nSUMMARY: slowest first call {slowest['first_call_s']:.1f} s ({slowest['case']}); "
          f"largest peak {max(r['peak_rss_mb'] for r in after if r['ok']):.0f} MB")
    write_json(args, "compile_time", data)


if __name__ == "__main__":
    main()
