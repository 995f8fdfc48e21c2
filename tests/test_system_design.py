"""Design parameters of the barrier system (`barrierjax.system.design`): a redesign equals
the system built afresh, a vmap over designs equals the loop, and the gradients of the
crash-test numbers equal finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax import system
from barrierjax.materials.plasticity import RateIndependentPlasticity
from barrierjax.system.design import crash_numbers, redesign

CAR = {"mass": 2270.0, "yaw_inertia": 4400.0, "length": 5.8, "width": 2.0, "front_to_cg": 1.5,
       "cg_to_front_axle": 0.6, "wheelbase": 3.6, "track": 1.7, "crush_stiffness": 1.5e6,
       "crush_strength": 2.5e5}  # fmt: skip
IMPACT = {"speed": 25.0, "angle_deg": 25.0, "impact_point": 8.0, "duration": 0.25,
          "save_every": 10}  # fmt: skip


def _rail(spacing=1.905, area=1.29e-3, second_moment=1.4e-6, strength=45e3):
    section = system.rail_section(area, second_moment, RateIndependentPlasticity(200e9, 345e6))
    posts = system.post_springs(1.5e6, strength, 10.0, 1e6, 30e3)
    return system.guardrail(16 * spacing, spacing, section=section, density=7850.0, posts=posts,
                            anchor_stiffness=1e7, elements_per_span=4)  # fmt: skip


def test_a_redesign_is_the_system_built_afresh():
    car, rail = redesign(system.vehicle(**CAR), _rail(), vehicle_mass=1500.0, post_spacing=1.5,
                         rail_thickness_ratio=1.25, post_strength=30e3)  # fmt: skip
    fresh = _rail(spacing=1.5, area=1.25 * 1.29e-3, second_moment=1.25 * 1.4e-6, strength=30e3)
    for mine, theirs in zip(jax.tree.leaves(rail), jax.tree.leaves(fresh), strict=True):
        np.testing.assert_allclose(np.asarray(mine), np.asarray(theirs), rtol=1e-12)
    assert float(car.mass) == 1500.0
    assert float(car.yaw_inertia) == pytest.approx(4400.0 * 1500.0 / 2270.0)


def _numbers(mass, spacing, thickness, strength, dt):
    car, rail = redesign(system.vehicle(**CAR), _rail(), vehicle_mass=mass, post_spacing=spacing,
                         rail_thickness_ratio=thickness, post_strength=strength)  # fmt: skip
    numbers = crash_numbers(car, rail, dt=dt, **IMPACT)
    return jnp.stack([numbers[k] for k in ("working_width", "oiv_y", "exit_angle")])


def test_vmap_over_designs_equals_the_loop():
    dt = system.stable_step(_rail(spacing=1.6), 1.5e6 * CAR["length"])
    designs = [jnp.asarray(x) for x in ([2270.0, 1800.0], [1.905, 1.6], [1.0, 1.3], [45e3, 35e3])]
    run = jax.jit(lambda *x: _numbers(*x, dt))
    batched = jax.jit(jax.vmap(lambda *x: _numbers(*x, dt)))(*designs)
    looped = jnp.stack([run(*x) for x in zip(*designs, strict=True)])
    np.testing.assert_allclose(np.asarray(batched), np.asarray(looped), rtol=1e-9, atol=1e-12)


def test_gradients_of_working_width_oiv_and_exit_angle_match_finite_differences():
    """Forward-mode derivatives with respect to the post spacing, the rail's thickness and
    the posts' strength, against central differences of 1e-7 relative: within one smooth
    piece of the discrete map. The map is rough in the post spacing: contact begins and
    ends between steps at places that move with the rail's nodes, and central differences
    of 1e-5 relative give 0.74, 3.6 and 34 where the derivatives are 2.05, -5.23 and -83.9
    (those in the thickness and the strength are smooth to 1e-4 relative)."""
    dt = system.stable_step(_rail(), 1.5e6 * CAR["length"])
    x = jnp.asarray([1.905, 1.0, 45e3])
    f = jax.jit(lambda p: _numbers(2270.0, p[0], p[1], p[2], dt))
    jacobian = np.asarray(jax.jit(jax.jacfwd(f))(x))
    for i in range(3):
        h = 1e-7 * float(x[i])
        fd = (np.asarray(f(x.at[i].add(h))) - np.asarray(f(x.at[i].add(-h)))) / (2 * h)
        np.testing.assert_allclose(jacobian[:, i], fd, rtol=2e-3, atol=1e-9 * np.max(np.abs(fd)))
    assert np.all(np.abs(jacobian[0]) > 0)  # the working width moves with every parameter
