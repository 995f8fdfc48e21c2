"""Normal impact with axial force, the beam stage of report 3.4: `axial_impact(...,
axial_ratio=eta0)`."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.phases import SOLVED, STEPS_SPENT
from barrierjax.hinge import axial_impact, normal_impact
from barrierjax.hinge.axial.api import _axial_impact
from barrierjax.hinge.response import kinetic_energy_balance

# (mass ratio, force ratio, speed): light, medium and heavy vehicles, weak and strong barriers.
CASES = [(0.5, 2.0, 1.0), (5.0, 1.5, 0.3), (0.05, 8.0, 2.0), (100.0, 1.2, 1.0)]
FIELDS = (
    "t_star",
    "w_star",
    "damage",
    "hinge_position",
    "duration",
    "barrier_displacement",
    "backing_work",
    "hinge_work",
)


def _axial(mu, phi, v, eta0, rtol=1e-10):
    return axial_impact(mu, phi, v, rtol=rtol, axial_ratio=eta0)


def test_zero_axial_ratio_is_the_model_without_axial_force():
    mu, phi, v = (jnp.asarray(x) for x in zip(*CASES))
    with_zero = _axial(mu, phi, v, jnp.zeros(len(CASES)), rtol=1e-12)
    without = normal_impact(mu, phi, v, rtol=1e-12)
    for field in FIELDS:
        np.testing.assert_allclose(
            getattr(with_zero, field), getattr(without, field), rtol=1e-10, err_msg=field
        )
    assert np.all(np.isinf(with_zero.t_string)) and np.all(np.isinf(without.t_string))
    plain = axial_impact(mu, phi, v, rtol=1e-12, axial_ratio=0)  # 0: the 3.2 model itself
    np.testing.assert_array_equal(plain.barrier_displacement, without.barrier_displacement)


@pytest.mark.parametrize(
    "case, eta0",
    [
        (CASES[0], 0.5),
        (CASES[0], 2.0),
        (CASES[0], 5.0),
        (CASES[1], 0.5),
        (CASES[2], 3.0),
        (CASES[3], 0.005),
    ],
)
def test_rest_on_the_cubic_and_energy_balance(case, eta0):
    mu, phi, v = case
    r = _axial(mu, phi, v, eta0)
    n_final = 2.0 * eta0 * float(r.barrier_displacement)  # N/N0 = 2 eta0 W0 (3.4.33)
    assert 0.0 < n_final < 1.0
    k = 1.0 + n_final**2
    s = float(r.hinge_position)
    cubic = s**3 + 3 * mu * s**2 - 3 * k * s - 3 * mu * k  # (3.4.40)
    assert abs(cubic) < 1e-8 * (s**3 + 3 * mu * k)
    assert 1.0 < s <= np.sqrt(3.0 * k)
    kinetic = 0.5 * mu * v**2
    work = float(r.crush_work + r.backing_work + r.hinge_work)
    assert work == pytest.approx(kinetic, rel=1e-8)


def test_axial_force_stiffens_the_barrier():
    """The report's example of figure 3.4.9 (mu 0.5, phi 2, speed 1): the final
    displacement and the duration fall as eta0 grows, the final hinge distance rises."""
    eta0 = jnp.asarray([0.0, 2.0, 2.5, 5.0])
    r = _axial(jnp.full(4, 0.5), jnp.full(4, 2.0), jnp.ones(4), eta0)
    assert np.all(np.diff(r.barrier_displacement) < 0) and np.all(np.diff(r.duration) < 0)
    assert np.all(np.diff(r.hinge_position) > 0)
    # The hinges stiffen only once the beam has deflected: the crushing phase barely changes.
    np.testing.assert_allclose(r.damage, r.damage[0], rtol=1e-2)


def test_beam_that_locks_while_the_vehicle_crushes():
    # phi near 1 and a strong axial force: V0' turns negative before N reaches N0 and
    # before the velocities meet, so the beam stops (the backing never pushes it back)
    # and the vehicle crushes to rest against it. The beam, driven by the constant crush
    # force alone, moves the same whatever the vehicle's mass and speed; the vehicle stops
    # at T = mu V / phi.
    phi, eta0 = 1.12764131948091, 16.449052816866732
    mu = jnp.array([1.4531843284914956, 3.0, 1.4531843284914956])
    v = jnp.array([0.8251699965190115, 0.8251699965190115, 1.3])
    r = _axial(mu, phi, v, eta0)
    assert np.all(np.isinf(r.t_string))
    np.testing.assert_allclose(r.barrier_displacement, r.barrier_displacement[0], rtol=1e-9)
    np.testing.assert_allclose(r.duration, mu * v / phi, rtol=1e-12)
    assert np.all(np.asarray(r.t_star) < np.asarray(r.duration))
    work = r.crush_work + r.backing_work + r.hinge_work
    np.testing.assert_allclose(work, 0.5 * mu * v**2, rtol=1e-9)


def test_history_energy_at_every_saved_time():
    """The vehicle's lost kinetic energy equals crush, backing and hinge work (bending and
    stretching) and the beam's kinetic energy at every sample; N/N0 = 2 eta0 W0 (3.4.33);
    the hinges never move back (3.4.24)."""
    mu, phi, v, eta0 = 0.5, 2.0, 1.0, 5.0
    r = axial_impact(mu, phi, v, rtol=1e-10, axial_ratio=eta0, n_history=40)
    h = r.history
    # Three blocks of 40 (the string block repeats the state at rest: no string here).
    assert h.time.shape == (120,) and np.all(np.diff(h.time[:80]) > 0)
    assert np.all(h.time[80:] == r.duration) and np.all(h.string_work == 0.0)
    lost = 0.5 * mu * v**2 - h.vehicle_kinetic_energy
    work = phi * h.crush + h.backing_work + h.hinge_work + h.beam_kinetic_energy
    np.testing.assert_allclose(work, lost, atol=1e-8 * 0.5 * mu * v**2)
    np.testing.assert_allclose(h.axial_force, 2.0 * eta0 * h.barrier_displacement, rtol=1e-12)
    assert np.all(np.diff(h.hinge_position) >= -1e-8)  # (to the dense output's error near rest)
    assert h.barrier_displacement[-1] == r.barrier_displacement and h.hinge_position[-1] == r.hinge_position


def test_velocities_that_meet_tangentially_end_the_crushing_phase():
    # examples/axial_scene.toml with a 1,434 kg vehicle at 108.5 km/h (drawn by a sweep of
    # it): vehicle and beam decelerate alike as they meet, so their relative velocity dips
    # through zero by 1.3e-3 of the impact speed and rises again. The crushing phase's
    # switch, the least of three functions, was located by Newton's method, which cycled
    # within the step and failed at the default rtol (1e-8); it is bisected.
    case = (15.807376821466205, 1.4140040957997215, 0.3125818730591418, 4.713346985999072)
    default, tight = axial_impact(*case), _axial(*case, rtol=1e-12)
    assert float(default.t_star) < float(default.t_string)  # they met before the string
    for field in FIELDS:
        np.testing.assert_allclose(
            getattr(default, field), getattr(tight, field), rtol=1e-7, err_msg=field
        )


def test_a_beam_stopped_by_the_axial_force_near_phi_one_is_solved_to_the_tolerance():
    # A vehicle that barely yields the barrier: the axial force stops the beam while it
    # crushes (locked), where the hinge's equation is stiff in 1/V0 and the steps had shrunk
    # to nothing before V0 = 0 (the solve spent its step budget).
    case = (64.89727224169185, 1.017468009021648, 0.48961131438240557, 13.982820223004214)
    default, tight = axial_impact(*case), _axial(*case, rtol=1e-11)
    assert np.isinf(float(tight.t_string)) and float(tight.t_star) < float(tight.duration)
    for field in FIELDS:
        np.testing.assert_allclose(
            getattr(default, field), getattr(tight, field), rtol=5e-8, err_msg=field
        )


def test_vmap_equals_loop(compilations):
    mu, phi, v = (jnp.asarray(x) for x in zip(*CASES))
    eta0 = jnp.asarray([1.0, 0.5, 0.2, 0.005])
    batched = _axial(mu, phi, v, eta0)
    with compilations() as programs:  # three run the program of four, padded with a copy
        three = _axial(mu[:3], phi[:3], v[:3], eta0[:3])
    assert not [m for m in programs if "axial_impact" in m], programs
    np.testing.assert_allclose(three.damage, batched.damage[:3], rtol=1e-13)
    for i, case in enumerate(CASES):
        single = _axial(*case, float(eta0[i]))
        for field in FIELDS:
            np.testing.assert_allclose(
                getattr(batched, field)[i], getattr(single, field), rtol=1e-10, err_msg=field
            )


def test_a_spent_step_budget_is_solved_again_for_those_scenarios_alone():
    # Heavy vehicles that barely yield the barrier: the crushing phase needs explicit steps
    # in proportion to 1 / (phi - 1), more than the first budget. The first (phi - 1 =
    # 2.3e-3) is solved again with 4 times the budgets; the second (3e-5) needs more than
    # that, and is solved again in implicit steps. The axial force stops both beams while
    # the vehicle crushes, which then crushes to rest at its crush force: the duration is
    # mu V / phi in closed form. The batch's other scenarios keep the first solve's answers.
    heavy, stiff = (43.61, 1.00234, 0.03555, 26.81), (50.0, 1.00003, 1.0, 1.0)
    cases = [(*CASES[0], 1.0), (*CASES[1], 0.5), heavy, stiff]
    mu, phi, v, eta0 = (jnp.asarray(x) for x in zip(*cases))
    attempt = lambda *x, budget, stiff: _axial_impact(
        *x, jnp.asarray(1e-10, x[0].dtype), n_history=0, string_cells=128, string_courant=1.0,
        budget=budget, stiff=stiff,
    )  # fmt: skip
    first, failures = attempt(mu, phi, v, eta0, budget=1, stiff=False)
    assert [int(f[0]) for f in failures] == [SOLVED, SOLVED, STEPS_SPENT, STEPS_SPENT]
    second = attempt(mu[2:], phi[2:], v[2:], eta0[2:], budget=4, stiff=False)[1]
    assert [int(f[0]) for f in second] == [SOLVED, STEPS_SPENT]
    r = _axial(mu, phi, v, eta0)
    for field in FIELDS:
        np.testing.assert_array_equal(getattr(r, field)[:2], getattr(first, field)[:2])
    np.testing.assert_allclose(r.duration[2:], (mu * v / phi)[2:], rtol=1e-12)
    assert np.all(np.asarray(r.t_star[2:]) < np.asarray(r.duration[2:]))
    lost = kinetic_energy_balance(r, mu, v, 0.0) / (0.5 * mu * v**2)
    np.testing.assert_allclose(lost, 0.0, atol=1e-10)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"axial_ratio": -1.0}, "axial_ratio"),
        ({"axial_ratio": np.nan}, "axial_ratio"),
        ({"axial_ratio": 1.0, "rtol": 0.0}, "rtol"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        axial_impact(0.5, 2.0, 1.0, **kwargs)


def test_float32_is_refused_with_the_switch_to_float64():
    # In float32 every solve failed in the crushing phase ("a step size fell to nothing").
    with jax.enable_x64(False):
        with pytest.raises(ValueError, match="axial_impact needs float64.*jax_enable_x64"):
            axial_impact(0.5, 2.0, 1.0, axial_ratio=5.0, rtol=1e-4)


def test_the_model_of_3_2_has_no_axial_force():
    # 3.4's beam stage has no closed form: it is axial_impact's, not normal_impact's.
    with pytest.raises(TypeError, match="axial_ratio"):
        normal_impact(0.5, 2.0, 1.0, axial_ratio=1.0)
