"""Benchmark of the barrier-system impact (`barrierjax.system`) on MASH test 3-11.

    python benchmarks/system_impact.py [--quick] [--out DIR]

The scene of `examples/mash_3_11.toml` (the 2270P at 100 km/h and 25 degrees into 53.3 m of
MGS) over 0.6 s of impact, at the rail's stable step: (1) one run after compilation (best of 3)
and its crash-test numbers; (2) variants of speed (90-110 km/h) and angle (20-30 degrees)
as one `jax.vmap`, per run, against one run; (3) the gradient of the dynamic deflection with
respect to the speed, the angle and the posts' strength, against the forward run; (4) the
first call in a fresh process (tracing, compilation, one run) and its peak memory, forward
and gradient. Writes `system_impact.json` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import dataclasses
import time
from pathlib import Path

import jax.numpy as jnp
import numpy as np
from harness import argument_parser, first_calls, steady, table, write_json

from barrierjax.system import scene as system_scene
from barrierjax.system import stable_step, system_impact
from barrierjax.system.assessment import summary
from barrierjax.system.vehicle import contact_stiffness_bound

SCENE = Path(__file__).resolve().parent.parent / "examples" / "mash_3_11.toml"
DURATION = 0.6  # s: the "about 0.6 s of impact" (the scene runs 1.0 s, to the exit box)

_SETUP = """
    import jax, jax.numpy as jnp
    from barrierjax.system import system_impact
    from barrierjax.system.scene import load_system_scene
    s = load_system_scene({scene!r})
    def deflection(speed, angle):
        r = system_impact(s.vehicle, s.barrier, speed=speed, angle_deg=angle,
                          impact_point=s.impact_point, duration={duration}, friction=s.friction)
        return r.dynamic_deflection
"""


def one_run(s, dt):
    def run():
        r = system_impact(
            s.vehicle,
            s.barrier,
            speed=s.speed,
            angle_deg=s.angle_deg,
            impact_point=s.impact_point,
            duration=DURATION,
            friction=s.friction,
        )
        return jax.block_until_ready(r)

    start = time.perf_counter()
    result = run()
    first = time.perf_counter() - start
    seconds = steady(run, reps=3)
    numbers = {k: float(v) for k, v in summary(result).items()}
    steps = int(np.ceil(DURATION / dt))
    return {"first_in_process_s": first, "run_s": seconds, "steps": steps, **numbers}


def batched(s, n):
    rng = np.random.default_rng(20261125)
    speeds = jnp.asarray(rng.uniform(90, 110, n) / 3.6)
    angles = jnp.asarray(rng.uniform(20, 30, n))

    def deflection(speed, angle):
        r = system_impact(
            s.vehicle,
            s.barrier,
            speed=speed,
            angle_deg=angle,
            impact_point=s.impact_point,
            duration=DURATION,
            friction=s.friction,
        )
        return jnp.stack([r.dynamic_deflection, r.exit_angle_deg])

    # The batch is timed once, compiled ahead (a warm-up call would cost as much as a run).
    many = jax.jit(jax.vmap(deflection)).lower(speeds, angles).compile()
    one = jax.jit(deflection)
    start = time.perf_counter()
    jax.block_until_ready(many(speeds, angles))
    t_many = time.perf_counter() - start
    t_one = steady(one, speeds[0], angles[0], reps=3)
    check = float(
        jnp.max(
            jnp.abs(
                jax.jit(jax.vmap(deflection))(speeds[:2], angles[:2])
                - jnp.stack([one(speeds[0], angles[0]), one(speeds[1], angles[1])])
            )
        )
    )
    return {
        "variants": n,
        "batch_s": t_many,
        "per_run_s": t_many / n,
        "one_run_s": t_one,
        "per_run_over_one": t_many / n / t_one,
        "vmap_vs_loop": check,
    }


def gradient(s, dt):
    def deflection(speed, angle, strength):
        posts = dataclasses.replace(s.barrier.posts, strength=strength)
        barrier = dataclasses.replace(s.barrier, posts=posts)
        r = system_impact(
            s.vehicle,
            barrier,
            speed=speed,
            angle_deg=angle,
            impact_point=s.impact_point,
            duration=DURATION,
            friction=s.friction,
            dt=dt,
        )
        return r.dynamic_deflection

    x = (jnp.asarray(s.speed), jnp.asarray(s.angle_deg), s.barrier.posts.strength)
    forward = jax.jit(deflection)
    grad = jax.jit(jax.grad(deflection, argnums=(0, 1, 2)))
    t_f, t_g = steady(forward, *x, reps=3), steady(grad, *x, reps=3)
    g = [float(v) for v in grad(*x)]
    return {
        "forward_s": t_f,
        "gradient_s": t_g,
        "ratio": t_g / t_f,
        "d_speed": g[0],
        "d_angle": g[1],
        "d_post_strength": g[2],
    }


def main(argv=None):
    args = argument_parser(__doc__).parse_args(argv)
    s = system_scene.load_system_scene(SCENE)
    dt = stable_step(s.barrier, contact_stiffness_bound(s.vehicle))
    data = {"run": one_run(s, dt)}
    r = data["run"]
    print(f"system_impact: MASH 3-11 on the MGS, {r['steps']} steps")
    table(
        "One run (0.6 s of impact) after compilation",
        [r],
        [
            ("run s", "run_s", ".3f"),
            ("first call in process s", "first_in_process_s", ".1f"),
            ("deflection m", "dynamic_deflection", ".3f"),
            ("exit deg", "exit_angle", ".1f"),
            ("OIV x m/s", "oiv_x", ".2f"),
            ("OIV y m/s", "oiv_y", ".2f"),
        ],
    )
    data["batch"] = batched(s, 8 if args.quick else 1000)
    table(
        "Variants of speed and angle in one vmap",
        [data["batch"]],
        [
            ("variants", "variants", "d"),
            ("batch s", "batch_s", ".1f"),
            ("per run s", "per_run_s", ".4f"),
            ("one run s", "one_run_s", ".3f"),
            ("per run / one run", "per_run_over_one", ".3f"),
            ("vmap - loop", "vmap_vs_loop", ".1e"),
        ],
    )
    data["gradient"] = gradient(s, dt)
    table(
        "Gradient of the dynamic deflection (speed, angle, post strength)",
        [data["gradient"]],
        [
            ("forward s", "forward_s", ".3f"),
            ("gradient s", "gradient_s", ".3f"),
            ("gradient / forward", "ratio", ".2f"),
        ],
    )
    setup = _SETUP.format(scene=str(SCENE), duration=DURATION)
    data["first_call"] = first_calls(
        {
            "MASH 3-11, one run": (setup, "deflection(s.speed, s.angle_deg)"),
            "its gradient (speed, angle)": (
                setup,
                "jax.grad(deflection, argnums=(0, 1))(s.speed, s.angle_deg)",
            ),
        },
        timeout=900.0,
    )
    write_json(args, "system_impact", data)


if __name__ == "__main__":
    main()
