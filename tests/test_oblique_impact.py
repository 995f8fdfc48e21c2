"""barrierjax.hinge.oblique_impact and moving_load (report 3.3)."""

import contextlib
import itertools
import math
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.hermite import quintic_hermite
from barrierjax.hinge import SolveError, normal_impact
from barrierjax.hinge.oblique import api as oblique_api
from barrierjax.hinge.oblique import moving_load, oblique_impact, results, transitions
from barrierjax.hinge.oblique.phases import at_rest
from barrierjax.hinge.response import kinetic_energy_balance
from barrierjax.hinge.oblique.results import displacement_field, vehicle_path
from barrierjax.hinge.oblique.transitions import initial_carry, step_loop

# Light and moderate vehicles (mu <= 5); see the module's notes on heavy ones.
NORMAL_CASES = [(5.0, 2.0, 0.6), (0.05, 20.0, 0.2), (1.0, 1.5, 0.7)]
OBLIQUE_CASES = [
    (5.0, 2.0, 0.6 * math.sin(math.radians(a)), 0.6 * math.cos(math.radians(a)))
    for a in (15.0, 30.0, 45.0)
] + [(5.0, 2.0, 0.4, 0.23), (0.2, 3.0, 0.5, 0.5)]


# Each `traced_apart` block's own offset of the random seeds, which no model reads.
_TRACE_CONTEXTS = itertools.count(1)


@contextlib.contextmanager
def traced_apart():
    """Within it, programs are traced and compiled anew (a module patched in the block is
    read), and those traced before it are used again after it: the jit caches and the
    traces key on the trace context, here an offset of the random seeds of the block's
    own. (`jax.clear_caches()` did the same, and every later test compiled anew what it
    ran: this file alone took 4.6 s longer, 97.1 s of tests against 92.5.)"""
    before = jax.config.jax_random_seed_offset
    jax.config.update("jax_random_seed_offset", next(_TRACE_CONTEXTS))
    try:
        yield
    finally:
        jax.config.update("jax_random_seed_offset", before)


@pytest.fixture(scope="module")
def oblique_batch():
    mu, phi, vn, vh = (jnp.array(c) for c in zip(*OBLIQUE_CASES))
    return oblique_impact(mu, phi, vn, vh, rtol=1e-9, n_history=400)


@pytest.mark.parametrize("phi, vh", [(2.0, 1.0), (3.0, 0.5)])
def test_moving_load_reaches_steady_state(phi, vh):
    root = math.sqrt(phi**2 - 1.0)
    r = moving_load(phi, vh, 60.0 / vh, rtol=1e-10)
    assert float(r.s1) == pytest.approx(phi - root, rel=1e-6)
    assert float(r.s2) == pytest.approx(phi + root, rel=1e-6)
    assert float(r.v0) == pytest.approx(root / vh, rel=1e-6)


@pytest.mark.parametrize("mu, phi, v0", NORMAL_CASES)
def test_no_tangential_speed_is_normal_impact(mu, phi, v0):
    r = oblique_impact(mu, phi, v0, 0.0, rtol=1e-10)
    n = normal_impact(mu, phi, v0, rtol=1e-12)
    for field in ("t_star", "duration", "barrier_displacement", "damage"):
        assert float(getattr(r, field)) == pytest.approx(float(getattr(n, field)), rel=1e-7), field
    assert float(r.hinge_position) == pytest.approx(float(n.hinge_position), rel=1e-7)
    assert float(r.rear_hinge_position) == pytest.approx(float(n.hinge_position), rel=1e-7)


def test_hinges_meet_at_rest_and_vehicle_leaves(oblique_batch):
    r = oblique_batch
    np.testing.assert_allclose(r.hinge_position, r.rear_hinge_position, rtol=1e-6)
    assert np.all(np.asarray(r.exit_normal_speed) < 0.0)  # (3.3.3): theta V_H with theta < 0
    assert np.all(np.asarray(r.exit_angle_deg) > 0.0)
    assert np.all(np.asarray(r.max_deflection) >= np.asarray(r.barrier_displacement))


@jax.jit
def _recorded(mu, phi, vn, vh, rtol):
    loop = step_loop(rtol, 4096)
    solution = loop.solve(initial_carry(loop, mu, phi, vn, vh, 0.0 * mu, history=True))
    return solution.recording.samples, solution.recording.count


def _recorded_steps(mu, phi, vn, vh, rtol):
    """The samples the step loop recorded for one scenario, and how many (one compilation
    serves every scenario)."""
    return _recorded(*(jnp.asarray(x, float) for x in (mu, phi, vn, vh, rtol)))


@jax.jit
def _final_shape(samples, count, x):
    """The last recorded step's displacement field: one program (not an operation at a
    time) for each number of recorded steps."""
    return displacement_field(samples, count, x)[-1]


def test_max_deflection_is_the_peak_of_the_final_shape(oblique_batch):
    # The final shape on 16385 points spanning every plastic zone, from the recorded
    # steps: its peak lies between the load's first and last positions (where
    # max_deflection looks for it), and max_deflection finds it.
    r = oblique_batch
    for i, case in enumerate(OBLIQUE_CASES):
        recorded, count = _recorded_steps(*case, rtol=1e-9)
        n = int(count)
        samples = {k: np.asarray(recorded[k])[:n] for k in ("time", "v0", "s1", "s2", "position")}
        x = np.linspace(
            np.min(samples["position"] - samples["s2"]),
            np.max(samples["position"] + samples["s1"]),
            16385,
        )
        shape = np.asarray(_final_shape(samples, count, x))
        peak = int(np.argmax(shape))
        assert 0.0 <= float(x[peak]) <= float(samples["position"][-1]) + float(x[1] - x[0])
        assert float(r.max_deflection[i]) == pytest.approx(shape[peak], rel=1e-5)
        # The history's last sample is the last recorded step's shape, on its own grid.
        # The two sum the same recorded steps' increments in other orders and programs:
        # up to 2.3e-11 of the peak apart under XLA's MLIR fusion emitters, 7.1e-11 under
        # its LLVM IR emitters (barrierjax's default on jaxlib 0.10), where the solves'
        # damage agrees to 1e-15; hence 1e-10 of the peak where the shape is near zero.
        on_grid = np.asarray(_final_shape(samples, count, r.history.x[i]))
        np.testing.assert_allclose(
            r.history.deflected_shape[i, -1], on_grid, rtol=1e-9, atol=1e-10 * np.max(on_grid)
        )


@pytest.mark.parametrize("case", [OBLIQUE_CASES[0], OBLIQUE_CASES[-1]])
def test_vehicle_path_at_the_steps_is_the_integral_of_its_velocity(case):
    from scipy.integrate import cumulative_trapezoid

    recorded, count = _recorded_steps(*case, rtol=1e-9)
    n = int(count)
    s = {k: np.asarray(v[:n]) for k, v in recorded.items()}
    sunk = s["contact_displacement"] + s["crush"]
    along, normal = vehicle_path(
        s["time"], s["force"], s["position"], s["vehicle_normal"], s["vehicle_tangential"], sunk
    )
    integral = cumulative_trapezoid(s["vehicle_normal"], s["time"], initial=0.0)
    np.testing.assert_allclose(normal, integral, atol=1e-4 * np.max(np.abs(integral)))
    integral = cumulative_trapezoid(s["vehicle_tangential"], s["time"], initial=0.0)
    np.testing.assert_allclose(along, integral, rtol=1e-6, atol=1e-9)


def _energy_imbalance(r, mu, phi):
    """At every saved step: |what the vehicle's initial kinetic energy went into, over
    that energy, - 1|. Arrays of scenarios along the first axis, or one scenario."""
    h = r.history
    mu, phi = (jnp.asarray(x)[..., None] for x in (mu, phi))
    spent = (
        h.vehicle_kinetic_energy
        + phi * h.crush
        + h.friction_work
        + h.slope_work
        + h.backing_work
        + h.hinge_work
        + h.beam_kinetic_energy
    )
    return jnp.abs(spent / h.vehicle_kinetic_energy[..., :1] - 1.0)


def test_energy_balance_at_every_saved_step(oblique_batch):
    mu, phi = (jnp.array([c[k] for c in OBLIQUE_CASES]) for k in (0, 1))
    assert float(jnp.max(_energy_imbalance(oblique_batch, mu, phi))) < 1e-6


def test_error_falls_with_the_tolerance(oblique_batch):
    # The memory is read through an interpolant of the recorded hinge trace, outside the
    # step control. With cubic Hermite the exit angle at rtol 1e-9 was 3e-7 degrees off
    # the rtol 1e-12 solution here, and the speeds 1.3e-8 (error ~ rtol^0.5); the quintic
    # keeps them at 9e-9 degrees and 5e-10.
    mu, phi, vn, vh = (jnp.array(c) for c in zip(*OBLIQUE_CASES))
    reference = oblique_impact(mu, phi, vn, vh, rtol=1e-12, n_history=400)  # the batch's program
    for field in ("duration", "barrier_displacement", "damage", "exit_normal_speed"):
        error = jnp.abs(getattr(oblique_batch, field) / getattr(reference, field) - 1.0)
        assert float(jnp.max(error)) < 5e-9, field
    angle_error = jnp.abs(oblique_batch.exit_angle_deg - reference.exit_angle_deg)
    assert float(jnp.max(angle_error)) < 3e-8


def test_quintic_hermite_is_exact_on_quintics():
    coefficients = jnp.array([0.3, 1.2, -0.7, 2.1, -1.5, 0.9])
    f = lambda x: jnp.polyval(coefficients[::-1], x)
    df, d2f = jax.grad(f), jax.grad(jax.grad(f))
    a, b = 0.4, 1.1
    ends = [(f(x), df(x), d2f(x)) for x in (a, b)]
    for x in np.linspace(a, b, 7):
        value, slope, curvature = quintic_hermite((x - a) / (b - a), b - a, *ends)
        assert float(value) == pytest.approx(float(f(x)), abs=1e-13)
        assert float(slope) == pytest.approx(float(df(x)), abs=1e-12)
        assert float(curvature) == pytest.approx(float(d2f(x)), abs=1e-11)


@pytest.mark.parametrize("friction", [0.0, 0.3])
def test_force_ratio_near_one_starts_and_closes_the_energy_balance(friction):
    # phi = 1.01: the hinge equations are stiff near T = 0 in proportion to 1 / V0'(0),
    # and the first explicit step from T = 0 was never accepted at rtol 1e-8 (the step
    # shrank to 1e-306). The steps now start from the expansion about T = 0.
    mu, phi = 0.1, 1.01
    vn, vh = 0.5, 0.5 * math.sqrt(3.0)
    r = oblique_impact(mu, phi, vn, vh, friction=friction, rtol=1e-9, n_history=200)
    assert float(jnp.max(_energy_imbalance(r, mu, phi))) < 1e-6
    assert float(r.hinge_position) == pytest.approx(float(r.rear_hinge_position), rel=1e-6)


def test_vmap_equals_loop(oblique_batch):
    for i, case in enumerate(OBLIQUE_CASES[:2]):
        single = oblique_impact(*case, rtol=1e-9)
        for field in ("damage", "barrier_displacement", "duration", "exit_angle_deg", "exit_normal_speed"):
            assert float(getattr(oblique_batch, field)[i]) == pytest.approx(
                float(getattr(single, field)), rel=1e-9, abs=1e-14
            )


def test_batched_gradient_equals_the_loop_of_scalar_gradients():
    # A batch takes its derivatives through another path than a scalar (the directions
    # solved as problems of their own, `_solve.sensitivity`). The cases: contact to rest,
    # a light vehicle sliding with friction, friction stopping the slide in contact, and
    # a vehicle that separates at 10 degrees.
    cases = [
        (5.0, 2.0, 0.4, 0.23, 0.0),
        (0.2, 3.0, 0.5, 0.5, 0.1),
        (0.333, 7.49, 0.3, 0.0816, 0.326),
        (1.0, 10.0, math.sin(math.radians(10.0)), math.cos(math.radians(10.0)), 0.1),
    ]

    def total(*x):
        r = oblique_impact(*x[:4], friction=x[4], rtol=1e-11)
        return jnp.sum(r.exit_angle_deg + r.exit_normal_speed + r.damage + r.barrier_displacement)

    gradient = jax.grad(total, argnums=tuple(range(5)))
    batched = np.stack(gradient(*(jnp.array(c) for c in zip(*cases))), axis=-1)
    for case, row in zip(cases, batched):
        # (Unpacked from an array, as the finite-difference tests below pass them: they
        # then share the scalar gradient's compilation.)
        loop = np.array(gradient(*jnp.array(case)))
        np.testing.assert_allclose(row, loop, rtol=_GRADIENT_ROUNDING, atol=1e-12 * np.max(np.abs(loop)))
    # Three of them run the program of four, padded with a copy of the third (whose
    # derivatives then add nothing to the real ones').
    three = np.stack(gradient(*(jnp.array(c) for c in zip(*cases[:3]))), axis=-1)
    np.testing.assert_allclose(three, batched[:3], rtol=1e-13, atol=1e-13 * np.max(np.abs(batched)))


# The rounding floor of these gradients at rtol 1e-11: moving the mass ratio of the last
# case by one ulp (1 + 1e-15) moves its scalar gradient by 9e-9 relative (and by 2.4e-8 at
# 1 + 1e-13), though the forward moves by 4e-14; the batched and scalar gradients add up
# the same tangents in different orders, and differ by as much (2.2e-8).
_GRADIENT_ROUNDING = 5e-8


def _jacobian_against_finite_differences(
    x,
    tolerance,
    fields=(
        "exit_angle_deg",
        "exit_tangential_speed",
        "damage",
        "barrier_displacement",
        "duration",
        "hinge_position",
    ),
    inputs=range(5),
):
    def outputs(x):
        r = oblique_impact(x[0], x[1], x[2], x[3], friction=x[4], rtol=1e-11)
        return jnp.stack([getattr(r, f) for f in fields])

    jacobian = jax.jacrev(outputs)(x)
    for i in inputs:
        h = 1e-5 * x[i]
        fd = (outputs(x.at[i].add(h)) - outputs(x.at[i].add(-h))) / (2 * h)
        scale = jnp.maximum(jnp.abs(fd), 1e-6 * jnp.max(jnp.abs(jacobian), axis=1))
        assert float(jnp.max(jnp.abs(jacobian[:, i] - fd) / scale)) < tolerance, (fields, i)


def test_gradients_match_finite_differences_before_the_memory_is_read():
    # V_H small enough that the load never reaches the initial hinge position S*: the
    # slope under it is -Phi, with no lookup of the recorded hinge trace.
    _jacobian_against_finite_differences(jnp.array([5.0, 2.0, 0.3, 0.2, 0.1]), 1e-5)


def test_gradients_match_finite_differences_reading_the_memory():
    # The load crosses S* and H(T*), where the deposited curvature has a kink and a jump,
    # and the jump propagates (`barrierjax.hinge.oblique.transitions.transition`).
    _jacobian_against_finite_differences(jnp.array([5.0, 2.0, 0.3, 0.52, 0.1]), 1e-4)


def test_gradients_of_a_vehicle_left_at_rest_against_the_barrier():
    # Friction stops the slide before the barrier stops, and the vehicle stays in contact:
    # it ends at rest, its exit angle undefined (0 by convention). Its derivatives were NaN
    # (arctan2 at (0, 0)), and with them the whole gradient of a sum over a batch; they
    # are 0.
    x = jnp.array([0.333, 7.49, 0.300, 0.0816, 0.326])
    fields = ("exit_angle_deg", "exit_tangential_speed", "exit_normal_speed", "damage", "duration")

    def outputs(x):
        r = oblique_impact(x[0], x[1], x[2], x[3], friction=x[4], rtol=1e-11)
        return jnp.stack([getattr(r, f) for f in fields])

    jacobian = np.asarray(jax.jacrev(outputs)(x))
    assert np.all(np.asarray(outputs(x))[:3] == 0.0)
    assert np.all(jacobian[:3] == 0.0)
    assert np.all(np.isfinite(jacobian)) and np.all(jacobian[3:, :4] != 0.0)


def test_gradients_match_finite_differences_where_friction_stops_the_slide_in_contact():
    # The same scenario: friction switches off where the slide stops, and the force jumps.
    # Inside a step, the stop carried no derivative (duration's and barrier_displacement's with respect to
    # mu were 3e-4 to 7e-4 off, with respect to V_H and f 0.8 to 17 times their size); it
    # is an event now.
    x = jnp.array([0.333, 7.49, 0.300, 0.0816, 0.326])
    _jacobian_against_finite_differences(x, 1e-5, fields=("damage", "barrier_displacement", "duration"))


def test_gradients_match_finite_differences_where_friction_stops_the_slide_while_crushing():
    # A light vehicle at a steep angle: the slide stops at T = 4e-4, before T* = 9e-4.
    # Both stage ends are linear in T, where the event's location went wrong
    # (test_recorded_rk): t_star's derivative was 0.7 % off at this rtol (and 1 % at rtol
    # 1e-10 before the stop was an event). (Those with respect to V_H are 1e-13 of the
    # others, below what differences resolve.)
    x = jnp.array([0.01, 1.1, 0.0996, 0.00872, 0.2])
    fields = ("damage", "barrier_displacement", "duration", "t_star")
    _jacobian_against_finite_differences(x, 1e-5, fields=fields, inputs=(0, 1, 2, 4))


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(mass_ratio=-1.0), "mass_ratio"),
        (dict(force_ratio=0.0), "force_ratio"),
        (dict(normal_speed=float("nan")), "normal_speed"),
        (dict(tangential_speed=-0.1), "tangential_speed"),
        (dict(friction=-0.2), "friction"),
        (dict(rtol=1.0), r"rtol must be in \(0, 1\)"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    args = dict(mass_ratio=5.0, force_ratio=2.0, normal_speed=0.3, tangential_speed=0.5) | kwargs
    friction = args.pop("friction", 0.0)
    with pytest.raises(ValueError, match=field):
        oblique_impact(**args, friction=friction)


def test_spent_step_budget_grows_or_says_what_to_pass():
    # Six times the steady-state test's run: about 1400 steps, past the first budget.
    phi, vh, t_end = 2.0, 1.0, 360.0
    with pytest.raises(RuntimeError) as given:
        moving_load(phi, vh, t_end, max_steps=1024)
    message = str(given.value)
    assert "\n" not in message and "max_steps=1024 was spent in the moving load" in message
    suggested = int(re.search(r"pass max_steps=(\d+) or more", message).group(1))
    assert suggested > 1024
    # With no budget given it grows by itself to the one suggested, which completes.
    grown = moving_load(phi, vh, t_end)
    assert int(grown.steps) > 1024
    # It grew to the budget suggested: a run given that budget is the same run.
    given = moving_load(phi, vh, t_end, max_steps=suggested)
    assert int(given.steps) == int(grown.steps) and float(given.s1) == float(grown.s1)
    assert float(grown.s1) == pytest.approx(phi - math.sqrt(phi**2 - 1.0), rel=1e-6)


def test_a_budget_grows_under_grad():
    # The moving load's budget grows in proportion to the time left, t_end among its
    # inputs: under `grad` outside a `jit` it read them with their tangents and raised
    # JAX's TracerArrayConversionError. At the steady state S1 = phi - (phi^2 - 1)^1/2
    # ((3.3.18)), whatever t_end.
    phi, vh, t_end = 2.0, 1.0, 360.0
    s1 = lambda *x: moving_load(*x, n_history=2).s1
    d_phi, d_t_end = jax.grad(s1, argnums=(0, 2))(phi, vh, t_end)
    assert float(d_phi) == pytest.approx(1.0 - phi / math.sqrt(phi**2 - 1.0), rel=1e-5)
    assert abs(float(d_t_end)) < 1e-9


def test_a_spent_budget_under_grad_says_what_to_pass():
    # Outside a `jit`, the outcome's times carry tangents under `grad`: its message read
    # them as numbers and raised JAX's TracerArrayConversionError instead.
    exit_angle = lambda mu: oblique_impact(mu, 2.0, 0.3, 0.5, max_steps=16).exit_angle_deg
    with pytest.raises(SolveError, match=r"max_steps=16 was spent in the crushing phase"):
        jax.grad(exit_angle)(5.0)


def test_a_spent_budget_grows_for_the_scenarios_that_spent_it_alone(monkeypatch):
    # A heavy vehicle that barely yields the barrier (mu 100, phi - 1 = 3e-3) spends the
    # first budget, 1,024 steps, while it crushes (explicit steps in proportion to
    # 1 / (phi - 1)); the light ones beside it do not. It alone is solved again, by the
    # scalar program with 4,096: its answer is its own scalar solve's with that budget, and
    # the others' are those of their batch without it (the same padded program).
    light, heavy = [(1.0, 2.0, 0.3, 0.5), (2.0, 3.0, 0.4, 0.2)], (100.0, 1.003, 0.3, 0.5)
    batches = []

    def batch_solved(mu, *args, max_steps, **options):
        batches.append((mu.shape, max_steps))
        return api_batch_solved(mu, *args, max_steps=max_steps, **options)

    api_batch_solved = oblique_api._oblique_batch_solved
    monkeypatch.setattr(oblique_api, "_oblique_batch_solved", batch_solved)
    solve = lambda cases: oblique_impact(*(jnp.asarray(x) for x in zip(*cases)), rtol=1e-6)
    with pytest.raises(SolveError, match="max_steps=1024 was spent in the crushing phase"):
        oblique_impact(*heavy, rtol=1e-6, max_steps=1024)
    batch = solve([*light, heavy])
    assert batches == [((4,), 1024)]
    alone = oblique_impact(*heavy, rtol=1e-6, max_steps=4096)
    without = solve([*light, light[1]])
    same = lambda rows, expected: np.testing.assert_array_equal(np.asarray(rows), expected)
    jax.tree.map(lambda b, a: same(b[2], a), batch, alone)
    jax.tree.map(lambda b, w: same(b[:2], w[:2]), batch, without)
    # With the budget given, it cannot grow: the error names the heavy vehicle and carries
    # the batch's result, the light ones' rows as solved (what a sweep keeps).
    with pytest.raises(SolveError) as raised:
        oblique_impact(*(jnp.asarray(x) for x in zip(*light, heavy)), rtol=1e-6, max_steps=1024)
    assert list(raised.value.failures) == [2] and "max_steps=1024 was spent" in str(raised.value)
    jax.tree.map(lambda r, w: same(r[:2], w[:2]), raised.value.result, without)


def test_float32_defaults_to_a_tolerance_it_can_meet():
    # As for a user who has not enabled float64. A default rtol of 1e-8, below float32's
    # resolution, shrank the steps until the budget was spent.
    with jax.enable_x64(False):
        r = moving_load(2.0, 1.0, 100.0)
        assert r.s1.dtype == jnp.float32
        assert float(r.s1) == pytest.approx(2.0 - math.sqrt(3.0), rel=1e-4)
        with pytest.raises(ValueError, match=r"rtol must be at least 1.2e-05 in float32"):
            moving_load(2.0, 1.0, 100.0, rtol=1e-8)


def test_a_result_whose_energy_balance_does_not_close_is_refused():
    # A heavy vehicle in float32 (a 100 t vehicle at 27.8 m/s and 60 degrees on the default
    # scene's barrier) left faster than it came, with no error; in float64 the same impact
    # is refused as outside the model (the load catches up with the hinge), and with
    # friction it closes to 5e-6 of the energy. A light vehicle's closes in float32 too.
    heavy = (1111.66, 1.41737, 0.249144, 0.143843)
    with jax.enable_x64(False):
        with pytest.raises(SolveError, match=r"energy balance does not close: .* unaccounted for .*float64"):
            oblique_impact(*heavy)
        light = oblique_impact(25.2, 1.41737, 0.249144, 0.143843)
        assert light.exit_speed.dtype == jnp.float32
    with pytest.raises(SolveError, match="caught up with the hinge"):
        oblique_impact(*heavy)
    r = oblique_impact(*heavy, friction=0.1)
    lost = kinetic_energy_balance(r, heavy[0], heavy[2], heavy[3])
    assert abs(float(lost)) < 1e-5 * 0.5 * heavy[0] * (heavy[2] ** 2 + heavy[3] ** 2)


def test_load_catching_up_with_the_hinge_is_an_error_not_a_blow_up():
    # A fast slide: S1 -> 0 in the contact phase, where V0 and the force grow without
    # bound (the three-hinge mechanism of 3.3 no longer holds).
    with pytest.raises(Exception, match="caught up with the hinge"):
        jax.block_until_ready(oblique_impact(20.8, 1.92, 0.589, 0.649, rtol=1e-9).damage)


def test_friction_stops_the_slide_and_takes_its_kinetic_energy():
    # A light vehicle at a steep angle with friction: the slide stops in contact, and the
    # vehicle then stays with the barrier (static friction), never sliding backwards.
    mu, vh = 0.01, 0.00872
    r = oblique_impact(mu, 1.1, 0.0996, vh, friction=0.2, rtol=1e-9)
    assert float(r.exit_tangential_speed) == 0.0
    assert float(r.friction_work) == pytest.approx(0.5 * mu * vh**2, rel=1e-6)


@pytest.mark.parametrize("mu", [0.1, 10.0])
def test_energy_balance_once_friction_has_stopped_the_slide(mu):
    # At 89 degrees the slide stops early in the crushing phase; the rest of the contact
    # must carry no friction term (it once did, and lost 0.3 of the energy at mu = 10).
    vn, vh = math.sin(math.radians(89.0)), math.cos(math.radians(89.0))
    r = oblique_impact(mu, 3.0, vn, vh, friction=0.3, rtol=1e-9, n_history=200)
    assert float(r.exit_tangential_speed) == 0.0
    assert float(jnp.max(_energy_imbalance(r, mu, 3.0))) < 1e-6


def test_a_step_bounded_to_zero_ends_the_solve_and_says_so(monkeypatch):
    # A step that `max_step` bounds to length zero never recovers (the controller grows the
    # last length): the solve ends there and says so, where it spent every budget up to
    # 65,536 steps and then asked for a larger one (the stall below).
    bounded = transitions.max_step
    stuck = lambda y, f, stage, past, p: jnp.where(y.time > 0.5, 0.0, bounded(y, f, stage, past, p))
    monkeypatch.setattr(transitions, "max_step", stuck)
    with traced_apart():  # (read where the program is traced)
        with pytest.raises(SolveError, match=r"T = 0\.5.*the step length is no longer positive"):
            oblique_impact(5.0, 2.0, 0.3, 0.5)
        with pytest.raises(Exception, match="the step length is no longer positive"):
            jax.block_until_ready(jax.jit(lambda m: oblique_impact(m, 2.0, 0.3, 0.5).damage)(5.0))
    monkeypatch.undo()


def test_a_crushing_load_that_crosses_the_trace_start_in_one_step_goes_on():
    # A fast slide and a force ratio near 1: the load reaches S*, where the right hinge's
    # trace starts, while the vehicle still crushes. The step that crossed S* could take
    # the load past more of the trace's short first intervals than the next step's view
    # holds; the next step's length was then zero for good, and rtol 1e-8 and 1e-9 spent
    # any budget (rtol 1e-7 and 1e-10 did not).
    mu, phi, vn, vh = 3.3273375834774193, 1.1295625195745322, 0.4916109728906413, 0.8553097921851373
    fine = oblique_impact(mu, phi, vn, vh, rtol=1e-10)
    s_star = 3.0 / (math.sqrt(phi**2 + 3.0) + phi)
    assert vh * float(fine.t_star) > s_star  # (no friction: the load moves at V_H)
    for rtol in (1e-8, 1e-9):
        r = oblique_impact(mu, phi, vn, vh, rtol=rtol)
        for name in ("duration", "t_star", "damage", "exit_angle_deg"):
            assert float(getattr(r, name)) == pytest.approx(float(getattr(fine, name)), rel=1e-7)


def test_a_crushing_end_that_dips_within_one_step_is_not_missed():
    # The vehicle's normal speed comes down to the load point's and the two part again
    # (their difference, the crushing phase's event, touches zero and rises): the crushing
    # ends there. At rtol 1e-6 and 1e-8 one step straddled the dip, its ends both positive,
    # and the vehicle crushed on to T = 2.83 instead of 0.79: the exit angle 19.33 degrees,
    # where rtol 1e-7 and 1e-9 to 1e-12 give 25.87 (benchmarks/oblique_impact.py's box,
    # rng 1, scenario 1741 of 8,192).
    mu, phi, vn, vh = 6.8035394917747825, 1.673856917492205, 0.6889817610205201, 0.6789526769284858
    fine = oblique_impact(mu, phi, vn, vh, rtol=1e-10)
    assert float(fine.t_star) == pytest.approx(0.7867, abs=1e-4)
    for rtol, within in ((1e-6, 1e-3), (1e-8, 1e-6)):
        r = oblique_impact(mu, phi, vn, vh, rtol=rtol)
        for name in ("t_star", "duration", "exit_angle_deg"):
            assert float(getattr(r, name)) == pytest.approx(float(getattr(fine, name)), rel=within)


def test_a_crushing_load_that_reaches_a_cluster_of_the_trace_goes_on():
    # A force ratio near 1: where the load crossed S*, the steps restarted short and the
    # hinge recorded a cluster of intervals of about 1e-6; when the load came up to that
    # cluster, its step's margin past a piece carried it past more of them than the next
    # step's view holds, and rtol 1e-9 and 1e-10 stalled (1e-8 did not).
    mu, phi, vn, vh = 8.223, 1.011, 0.2443, 1.141
    fine = oblique_impact(mu, phi, vn, vh, rtol=1e-10)
    r = oblique_impact(mu, phi, vn, vh, rtol=1e-9)
    for name in ("duration", "t_star", "damage", "exit_angle_deg"):
        assert float(getattr(r, name)) == pytest.approx(float(getattr(fine, name)), rel=1e-7)


@pytest.mark.parametrize(
    "mu, phi, vn, vh, friction",
    [(3.6486, 3.0642, 0.36637, 0.27559, 0.0), (2.5345, 3.7609, 0.29556, 0.45929, 0.17545)],
)
def test_contact_ending_just_short_of_a_breakpoint(mu, phi, vn, vh, friction):
    # The segment's end event is the minimum of the contact's own end and the distance to
    # the next breakpoint of Psi': a kink where regula falsi alone crawled, and the Newton
    # step after it flew off (a spent step budget, then NaN). Both tolerances must agree.
    coarse, fine = (
        oblique_impact(mu, phi, vn, vh, friction=friction, rtol=rtol) for rtol in (1e-6, 1e-9)
    )
    for name in ("duration", "barrier_displacement", "damage", "exit_angle_deg"):
        assert float(getattr(coarse, name)) == pytest.approx(float(getattr(fine, name)), rel=1e-5)


# --------------------------------------------------------------------------------------
# A barrier the vehicle cannot yield (phi <= 1): the rigid wall, in closed form.


@pytest.mark.parametrize("friction", [0.0, 0.2, 3.0])
def test_unyielding_barrier_is_a_rigid_wall(friction):
    """phi <= 1: the vehicle crushes at phi until V_N is spent, D = mu V_N^2 / (2 phi), at
    T* = mu V_N / phi, sliding under friction phi meanwhile (to rest along the barrier
    where friction 3.0 stops the slide first); it leaves along the barrier (angle 0) with
    what is left of V_H; the barrier does not move; the energy balances."""
    mu, phi, vn, vh = 5.0, 0.8, 0.3, 0.5
    r = oblique_impact(mu, phi, vn, vh, friction=friction, n_history=200)
    t_star = mu * vn / phi
    vh_end = max(vh - friction * vn, 0.0)
    assert float(r.damage) == pytest.approx(0.5 * mu * vn**2 / phi, rel=1e-14)
    assert float(r.duration) == pytest.approx(t_star, rel=1e-14)
    assert float(r.exit_speed) == pytest.approx(vh_end, rel=1e-14, abs=1e-15)
    assert float(r.exit_angle_deg) == 0.0 and float(r.max_deflection) == 0.0
    energy = float(r.crush_work + r.friction_work) + 0.5 * mu * vh_end**2
    assert energy == pytest.approx(0.5 * mu * (vn**2 + vh**2), rel=1e-14)
    h = r.history
    assert float(h.vehicle_displacement[-1]) == pytest.approx(float(r.damage), rel=1e-12)
    assert float(h.vehicle_tangential_velocity[-1]) == pytest.approx(vh_end, abs=1e-15)
    assert float(h.friction_work[-1]) == pytest.approx(float(r.friction_work), rel=1e-12)
    assert float(jnp.max(jnp.abs(h.deflected_shape))) == 0.0


def test_an_unyielding_barrier_is_a_rigid_wall_whatever_the_mechanism_would_do():
    # A 1,000-fold heavier vehicle sliding fast: on a yielding barrier its load catches up
    # with the hinge (an error); on one it cannot yield, the rigid wall. Its lane was solved
    # at the vehicle's own inputs with phi = 2, and raised that error for it.
    mu, vn, vh = 1111.66, 0.249144, 0.143843
    with pytest.raises(SolveError, match="caught up with the hinge"):
        oblique_impact(mu, 1.41737, vn, vh)
    r = oblique_impact(jnp.asarray([mu, 5.0]), jnp.asarray([0.9, 2.0]), vn, vh)
    assert float(r.damage[0]) == pytest.approx(0.5 * mu * vn**2 / 0.9, rel=1e-14)
    assert float(r.damage[1]) == pytest.approx(float(oblique_impact(5.0, 2.0, vn, vh).damage))


def test_batches_across_phi_one_equal_single_runs_and_their_derivatives_match(compilations):
    """A batch with lanes on both sides of phi = 1 equals single runs; the derivatives of
    the rigid wall's crush and exit speed are the closed form's, and across phi = 1 the
    crush is continuous (the barrier starts to yield at phi = 1 and takes little just
    above it: 1 % at phi = 1.001, where the step loop needs 5614 steps, in proportion to
    1 / (phi - 1)). The second gradient, with respect to another argument, compiles no
    program of the model: every derivative runs the first one's."""
    mu = jnp.array([5.0, 5.0, 8.0, 8.0])
    phi = jnp.array([0.7, 1.0, 1.001, 2.5])
    vn, vh = jnp.array([0.3, 0.2, 0.25, 0.3]), jnp.array([0.5, 0.4, 0.3, 0.2])
    options = dict(friction=0.1, rtol=1e-9, max_steps=8192)
    batch = oblique_impact(mu, phi, vn, vh, **options)
    with compilations() as programs:  # three run the program of four, padded with a copy
        three = oblique_impact(mu[:3], phi[:3], vn[:3], vh[:3], **options)
    assert not [m for m in programs if "oblique" in m], programs
    np.testing.assert_allclose(three.damage, batch.damage[:3], rtol=1e-13)
    for k in range(4):
        one = oblique_impact(mu[k], phi[k], vn[k], vh[k], **options)
        assert float(one.damage) == pytest.approx(float(batch.damage[k]), rel=1e-9)
        assert float(one.exit_speed) == pytest.approx(float(batch.exit_speed[k]), rel=1e-9)
    rigid_at_one = 0.5 * 8.0 * 0.25**2 / 1.0
    assert float(batch.damage[2]) == pytest.approx(rigid_at_one, rel=1.2e-2)
    grad = jax.grad(lambda a: oblique_impact(5.0, 0.7, a[0], a[1], friction=0.1).exit_speed)(
        jnp.array([0.3, 0.5])
    )
    np.testing.assert_allclose(grad, [-0.1, 1.0], rtol=1e-12)
    with compilations() as programs:
        d_damage = jax.grad(lambda p: oblique_impact(5.0, p, 0.3, 0.5).damage)(0.7)
    assert programs and not [m for m in programs if "oblique" in m], programs
    assert float(d_damage) == pytest.approx(-0.5 * 5.0 * 0.3**2 / 0.7**2, rel=1e-12)


def test_the_closed_run_out_to_rest_gives_what_the_solve_gives_run_on(monkeypatch):
    """The decelerative phases end at V0* rtol^1/2 e^-1 and `run_out_to_rest` closes the
    rest in form, to second order in that speed, the hinges on the cubic of their rest
    (`phases.at_rest`). Run on to V0* rtol^2 e^-1 instead, with the hinges where the
    integration leaves them, the solve gives the same to its own error at rtol 1e-10. A
    term of the run-out's first order left out (the exit slope read again at rest, the
    hinges' rest, the slide's friction), or the cubic's V_H^2 Psi' term, puts a field
    1e-7 off or more. The cases: contact to rest, a light vehicle sliding with friction,
    friction stopping the slide in contact, a vehicle that separates (the free phase's
    run-out), the normal impact, and a heavy vehicle that comes to rest past S*, where
    the right hinge has left a curvature Psi' under the load."""
    cases = [
        (5.0, 2.0, 0.4, 0.23, 0.0),
        (0.2, 3.0, 0.5, 0.5, 0.1),
        (0.333, 7.49, 0.3, 0.0816, 0.326),
        (1.0, 10.0, math.sin(math.radians(10.0)), math.cos(math.radians(10.0)), 0.1),
        (1.0, 2.0, 0.7, 0.0, 0.0),
        (9.8, 1.6, 0.2, 0.7, 0.0),
    ]
    fields = (
        "duration", "barrier_displacement", "max_deflection", "damage", "hinge_position",
        "rear_hinge_position", "exit_normal_speed", "exit_tangential_speed", "backing_work",
        "hinge_work", "friction_work", "slope_work",
    )

    def solve():
        impacts = [oblique_impact(*c[:4], friction=c[4], rtol=1e-10) for c in cases]
        return {f: np.array([float(getattr(r, f)) for r in impacts]) for f in fields}

    closed = solve()
    integrated = lambda y, stage, past, p: (y.s1, y.s2, at_rest(y, stage, past, p)[2])
    monkeypatch.setattr(transitions, "REST_SPEED", 2.0)
    monkeypatch.setattr(results, "at_rest", integrated)
    with traced_apart():  # (both are read where the program is traced)
        run_on = solve()
    monkeypatch.undo()
    assert any(not np.array_equal(closed[f], run_on[f]) for f in fields), "the patch was not read"
    for f in fields:
        scale = np.max(np.abs(run_on[f]))
        np.testing.assert_allclose(closed[f], run_on[f], rtol=1e-9, atol=1e-12 * scale, err_msg=f)
