"""The barrier-system impact (`barrierjax.system`): limits against closed forms and an
independent integrator, the energy audit, vmap against a loop, gradients against finite
differences, and bad inputs."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from barrierjax import system
from barrierjax.materials.plasticity import RateIndependentPlasticity
from barrierjax.system.impact import time_grid
from barrierjax.system.vehicle import periphery

# A pickup-like vehicle (the numbers are the tests' own, not a preset's).
CAR = {"mass": 2270.0, "yaw_inertia": 4400.0, "length": 5.8, "width": 2.0, "front_to_cg": 1.5,
       "cg_to_front_axle": 0.6, "wheelbase": 3.6, "track": 1.7}  # fmt: skip


def _car(**changes):
    data = {**CAR, "crush_stiffness": 1.5e6, "crush_strength": 2.5e5, **changes}
    return system.vehicle(**data)


def _wall():
    return system.RigidWall(jnp.asarray(-20.0), jnp.asarray(80.0))


def _rail(strength=45e3, failure=0.4, spacing=1.905, density=7850.0, spans=16,
          elements_per_span=4):  # fmt: skip
    section = system.rail_section(1.29e-3, 1.4e-6, RateIndependentPlasticity(200e9, 345e6))
    posts = system.post_springs(1.5e6, strength, failure, 1e6, 30e3)
    return system.guardrail(spans * spacing, spacing, section=section, density=density, posts=posts,
                            anchor_stiffness=1e7, elements_per_span=elements_per_span)  # fmt: skip


def test_head_on_crush_against_a_wall_is_the_elastic_plastic_spring_in_closed_form():
    """At 90 degrees, frictionless, the front edge meets the wall at once: one
    elastic-plastic spring of stiffness k and strength F on the vehicle's mass. It stops
    at crush F/k + (E - F^2/2k)/F and leaves at F/sqrt(k M) (the elastic energy given
    back), straight back. (The speed keeps the crush short of the side's first point.)"""
    car = _car(tyre_friction=0.0, crush_strength=2e5)
    points, share = (np.asarray(a) for a in periphery(car))
    front = np.isclose(points[:, 0], CAR["front_to_cg"])
    k, F = 1.5e6 * np.sum(share[front]), 2e5 * np.sum(share[front])
    M, speed = CAR["mass"], 5.7
    crush = F / k + (0.5 * M * speed**2 - F**2 / (2 * k)) / F
    assert crush < CAR["front_to_cg"] - np.max(points[~front, 0])
    r = system.system_impact(car, _wall(), speed=speed, angle_deg=90.0, impact_point=0.0,
                             duration=0.3, dt=1e-5, save_every=2, friction=0.0)  # fmt: skip
    reached = np.max(np.asarray(r.history.position[:, 1])) + CAR["front_to_cg"]
    assert reached == pytest.approx(crush, rel=1e-4)
    assert float(r.exit_speed) == pytest.approx(F / np.sqrt(k * M), rel=1e-3)
    assert abs(float(r.exit_angle_deg) + 90.0) < 1e-6
    assert np.max(np.abs(np.asarray(r.history.energy_error))) < 1e-6


def _elastic_reference(car, speed, angle, k_points, body_points):
    """The same vehicle on elastic (never yielding), frictionless periphery springs against
    the wall y = 0, by scipy's adaptive Runge-Kutta: exit velocity and yaw rate."""
    M, I = CAR["mass"], CAR["yaw_inertia"]
    corner = np.array([CAR["front_to_cg"], CAR["width"] / 2])

    def rot(p):
        return np.array([[np.cos(p), -np.sin(p)], [np.sin(p), np.cos(p)]])

    cg = -rot(angle) @ corner

    def rhs(t, s):
        _, y, p, vx, vy, w = s
        r = body_points @ rot(p).T
        depth = np.maximum(y + r[:, 1], 0.0)
        fy = -k_points * depth
        return [vx, vy, w, 0.0, np.sum(fy) / M, np.sum(r[:, 0] * fy) / I]

    start = [cg[0], cg[1], angle, speed * np.cos(angle), speed * np.sin(angle), 0.0]
    sol = solve_ivp(rhs, (0.0, 0.4), start, method="DOP853", rtol=1e-10, atol=1e-12, max_step=1e-4)
    return sol.y[:, -1]


def test_elastic_frictionless_impact_on_a_wall_against_an_independent_integrator():
    car = _car(crush_strength=1e12, tyre_friction=0.0)
    points, share = (np.asarray(a) for a in periphery(car))
    speed, angle = 15.0, 20.0
    r = system.system_impact(car, _wall(), speed=speed, angle_deg=angle, impact_point=0.0,
                             duration=0.4, dt=1e-5, save_every=10, friction=0.0)  # fmt: skip
    ref = _elastic_reference(car, speed, np.radians(angle), 1.5e6 * share, points)
    V, w = np.asarray(r.history.velocity[-1]), float(r.history.yaw_rate[-1])
    np.testing.assert_allclose(V, ref[3:5], rtol=0, atol=2e-3 * speed)
    assert w == pytest.approx(ref[5], abs=2e-3)
    # No dissipation: the kinetic energy (with the yaw) comes back whole.
    kinetic = 0.5 * CAR["mass"] * np.sum(V**2) + 0.5 * CAR["yaw_inertia"] * w**2
    assert kinetic == pytest.approx(0.5 * CAR["mass"] * speed**2, rel=1e-4)


def test_guardrail_energy_audit_closes_and_converges_at_second_order():
    errors = []
    rail = _rail()
    dt0 = system.stable_step(rail, 1.5e6 * CAR["length"])
    for dt in (dt0, dt0 / 2):
        r = system.system_impact(_car(), rail, speed=25.0, angle_deg=25.0, impact_point=8.0,
                                 duration=0.4, dt=dt, save_every=10)  # fmt: skip
        errors.append(float(np.max(np.abs(np.asarray(r.history.energy_error)))))
        assert float(r.dynamic_deflection) > 0.1 and bool(jnp.all(jnp.isfinite(r.exit_speed)))
        # The rail is pulled taut where it deflects, never past its plastic axial force.
        tension = np.asarray(r.history.rail_tension)
        assert tension.shape == (r.history.time.shape[0], len(rail.rail.connectivity))
        assert 0.1 * 1.29e-3 * 345e6 < np.max(tension) <= 1.29e-3 * 345e6 * (1 + 1e-9)
    assert errors[0] < 1e-4
    assert errors[1] < errors[0] / 2.5  # second order: a quarter, give or take


def test_the_stable_step_of_a_new_mesh_is_one_compiled_program(compilations):
    """The rail's linear stiffness runs as one program per mesh (op by op, a new mesh
    compiled a few hundred small programs: 7.9 s), on concrete data also inside a
    caller's jit."""
    rail = _rail(spans=11, elements_per_span=3)
    with compilations() as programs:  # 34 elements: a mesh no other test builds
        dt = system.stable_step(rail, 1.5e6 * CAR["length"])
    assert len(programs) <= 4, programs
    inside = jax.jit(lambda x: x * system.stable_step(rail, 1.5e6 * CAR["length"]))(1.0)
    assert float(inside) == dt


def test_stable_steps_that_differ_run_one_program(compilations):
    """The step is an argument of the compiled integrator: a denser rail (a longer stable
    step, as many saved samples) runs the program of the first."""
    car, light, heavy = _car(), _rail(), _rail(density=7850.0 * 1.004)
    steps = [time_grid(car, rail, 0.1, save_every=20) for rail in (light, heavy)]
    assert steps[0][0] < steps[1][0] and len(steps[0][1]) == len(steps[1][1])
    run = lambda rail: system.system_impact(
        car, rail, speed=25.0, angle_deg=25.0, impact_point=8.0, duration=0.1, save_every=20
    )
    first = run(light)
    with compilations() as programs:
        second = run(heavy)
    assert not [m for m in programs if "_integrate" in m], programs
    np.testing.assert_allclose(np.asarray(second.history.time), steps[1][1], rtol=1e-12)
    deflections = float(second.dynamic_deflection), float(first.dynamic_deflection)
    assert deflections[0] == pytest.approx(deflections[1], rel=0.05)


def test_vmap_over_speed_and_angle_equals_the_loop():
    rail = _rail()
    dt = system.stable_step(rail, 1.5e6 * CAR["length"])

    def run(speed, angle):
        r = system.system_impact(_car(), rail, speed=speed, angle_deg=angle, impact_point=8.0,
                                 duration=0.2, dt=dt, save_every=10)  # fmt: skip
        return jnp.stack([r.dynamic_deflection, r.exit_speed, r.exit_angle_deg])

    speeds, angles = jnp.asarray([22.0, 27.0]), jnp.asarray([20.0, 25.0])
    batched = jax.jit(jax.vmap(run))(speeds, angles)
    looped = jnp.stack([jax.jit(run)(s, a) for s, a in zip(speeds, angles)])
    np.testing.assert_allclose(np.asarray(batched), np.asarray(looped), rtol=1e-9, atol=1e-12)


def test_gradients_match_finite_differences():
    """The rail's dynamic deflection against the impact speed and the posts' strength (no
    post fails: the failure displacement is out of reach). The discrete map is smooth only
    between kinks (a point coming into contact between two steps, the largest sample
    changing), a few 1e-4 m/s apart in the speed here: central differences of 1e-6
    relative, within one smooth piece."""
    dt = system.stable_step(_rail(), 1.5e6 * CAR["length"])

    def deflection(speed, strength):
        rail = _rail(strength=strength, failure=10.0)
        r = system.system_impact(_car(), rail, speed=speed, angle_deg=25.0, impact_point=8.0,
                                 duration=0.25, dt=dt, save_every=10)  # fmt: skip
        return r.dynamic_deflection

    f = jax.jit(deflection)
    x = (25.0, 45e3)
    grad = jax.jit(jax.grad(deflection, argnums=(0, 1)))(*x)
    for i in range(2):
        h = 1e-6 * x[i]
        up, down = list(x), list(x)
        up[i], down[i] = x[i] + h, x[i] - h
        fd = (float(f(*up)) - float(f(*down))) / (2 * h)
        assert float(grad[i]) == pytest.approx(fd, rel=1e-3)


def test_a_gradient_keeps_the_saved_samples_not_every_step():
    """Reverse mode keeps the state at each saved sample and computes each interval's steps
    again, so that what a gradient holds falls with the samples saved (every step's
    intermediates, kept, took 2.5 GB for a gradient of MASH 3-11's 0.6 s, benchmarks/
    README.md "The first answer"): twice the steps between samples, about half of it."""
    dt = system.stable_step(_rail(), 1.5e6 * CAR["length"])

    def held(save_every):
        deflection = lambda speed: system.system_impact(
            _car(), _rail(), speed=speed, angle_deg=25.0, impact_point=8.0, duration=0.03,
            dt=dt, save_every=save_every,
        ).dynamic_deflection  # fmt: skip
        _, backward = jax.vjp(deflection, jnp.asarray(25.0))
        return sum(leaf.nbytes for leaf in jax.tree.leaves(backward) if hasattr(leaf, "nbytes"))

    assert held(40) < 0.6 * held(20)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: system.system_impact(_car(), _rail(), speed=25.0, angle_deg=25.0,
                                      impact_point=100.0, duration=0.1), "impact_point"),
        (lambda: system.system_impact(_car(), _rail(), speed=25.0, angle_deg=95.0,
                                      impact_point=8.0, duration=0.1), "angle_deg"),
        (lambda: system.system_impact(_car(), _rail(), speed=-1.0, angle_deg=25.0,
                                      impact_point=8.0, duration=0.1), "speed"),
        (lambda: _rail(spacing=0.0), "post_spacing"),
        (lambda: system.system_impact(_car(), _rail(), speed=25.0, angle_deg=25.0,
                                      impact_point=8.0, duration=0.1, dt=1e-3), "dt"),
        (lambda: _car(mass=-1.0), "mass"),
        (lambda: _car(front_to_cg=7.0), "front_to_cg"),
        (lambda: system.guardrail(10.0, 1.905, section=None, density=7850.0, posts=None,
                                  anchor_stiffness=1e7), "length"),
    ],
)  # fmt: skip
def test_bad_inputs_name_the_field(call, message):
    with pytest.raises(ValueError, match=message):
        call()


def test_critical_impact_point_sweep_equals_single_runs_and_picks_the_largest():
    from barrierjax.system.critical import critical_impact_point

    rail = _rail()
    dt = system.stable_step(rail, 1.5e6 * CAR["length"])
    points = jnp.asarray([6.0, 7.0, 8.0])
    options = {"speed": 25.0, "angle_deg": 25.0, "duration": 0.2, "dt": dt, "save_every": 10}
    sweep = critical_impact_point(_car(), rail, points, **options)
    single = [
        float(
            system.system_impact(_car(), rail, impact_point=float(p), **options).dynamic_deflection
        )
        for p in points
    ]
    np.testing.assert_allclose(np.asarray(sweep.values), single, rtol=1e-9)
    assert float(sweep.critical) == float(points[int(np.argmax(single))])
    with pytest.raises(ValueError, match="points"):
        critical_impact_point(_car(), rail, jnp.asarray([-1.0]), **options)
    with pytest.raises(ValueError, match="criterion"):
        critical_impact_point(_car(), rail, points, criterion="nope", **options)


def test_the_plan_view_animation_moves_the_vehicle_along_its_path(tmp_path):
    # (The run of `test_stable_steps_that_differ_run_one_program`: its compiled program.)
    from PIL import Image, ImageSequence

    from barrierjax.system.plots import animate_plan_view

    car, rail = _car(), _rail()
    r = system.system_impact(car, rail, speed=25.0, angle_deg=25.0, impact_point=8.0,
                             duration=0.1, save_every=20)  # fmt: skip
    path = animate_plan_view(r, car, rail, tmp_path / "plan.gif", frames=6)
    with Image.open(path) as gif:
        frames = [np.asarray(f.convert("RGB"), dtype=float) for f in ImageSequence.Iterator(gif)]
    assert len(frames) == 6 and all(f.shape == frames[0].shape for f in frames)
    # The vehicle's outline (red) in every frame, moving along the barrier (+x, rightwards).
    red = [np.nonzero((f[..., 0] > 150) & (f[..., 1] < 100) & (f[..., 2] < 100))[1] for f in frames]
    assert all(columns.size > 50 for columns in red)
    centres = [float(np.mean(columns)) for columns in red]
    assert centres == sorted(centres) and centres[-1] - centres[0] > 20
    # Each frame's time in its title, above the axes: dark text, another in every frame
    # (frames' palettes differ, so a few levels of difference mean nothing).
    titles = [f[: f.shape[0] // 10] for f in frames]
    assert all(np.any(t < 100) for t in titles)
    assert all(np.sum(np.abs(a - b) > 60) > 10 for a, b in zip(titles, titles[1:]))
