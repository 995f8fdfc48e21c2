"""The plastic-string stage of report 3.4 (3.4.45)-(3.4.48): `axial_impact(...,
axial_ratio=eta0)` past N = N0, and its solver `plastic_string_stage`."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax.hinge import axial_impact
from barrierjax.hinge.string import StringStart, plastic_string_stage

# (mass ratio, force ratio, speed, eta0): the string begins after the vehicle stopped
# crushing; while it crushes (and crushes to rest); no string.
STRING_CASES = [(0.5, 2.0, 1.0, 10.0), (5.0, 1.5, 1.0, 5.0), (0.5, 2.0, 1.0, 2.5)]


def _string(mu, phi, v, eta0, **kwargs):
    # The options of tests/test_axial_force.py, whose compilations this file then shares.
    return axial_impact(mu, phi, v, rtol=1e-10, axial_ratio=eta0, **kwargs)


def _energy_error(r, mu, v):
    work = r.crush_work + r.backing_work + r.hinge_work + r.string_work
    return np.abs(np.asarray(work) / (0.5 * mu * v**2) - 1.0)


@pytest.mark.parametrize("cells", [32, 256])
def test_constant_force_on_a_string_at_rest_is_the_characteristics_solution(cells):
    """A vehicle crushing at phi on a straight string at rest. By the Riemann invariants
    W_T -+ c W_X (c = eta^1/2, d/dT = -1/2 along dX/dT = +-c), a front runs out at c
    and behind it the string moves uniformly at W_T = phi/(2c) - T/4 with the slope
    W_X = X/(4 eta) - phi/(2 eta), until it stops at T_s = 2 phi / c everywhere at once
    (eta W_XX = 1/4 < 1/2 keeps it at rest). So W(X) = int from X/c to T_s of W_T dT; the
    vehicle crushes on to rest at T = mu u0 / phi."""
    phi, eta, mu, u0, span = 1.5, 4.0, 10.0, 1.0, 4.0  # the front stops at 3 < span
    c = np.sqrt(eta)
    start = StringStart(jnp.asarray(span), jnp.zeros(cells + 1), jnp.asarray(0.0), jnp.asarray(u0))
    r = plastic_string_stage(
        start, jnp.asarray(mu), jnp.asarray(phi), jnp.asarray(eta), courant=1.0, max_steps=10**5
    )
    x = np.linspace(0.0, span, cells + 1)
    t_stop = 2.0 * phi / c
    passed = np.minimum(x / c, t_stop)
    exact = phi / (2 * c) * (t_stop - passed) - (t_stop**2 - passed**2) / 8.0
    dx = span / cells
    # Second order: the grid's front leads or lags the true one by under a cell.
    np.testing.assert_allclose(r.displacement, exact, rtol=0, atol=0.5 * dx**2)
    assert float(r.displacement[0]) == pytest.approx(phi**2 / (2 * eta), rel=1e-12)
    t_rest = mu * u0 / phi
    assert float(r.duration) == pytest.approx(t_rest, abs=dx**2)
    crush = u0 * t_rest - 0.5 * phi / mu * t_rest**2 - phi**2 / (2 * eta)
    assert float(r.crush) == pytest.approx(crush, abs=dx**2)
    assert bool(r.finished)


def test_energy_balance_converges_at_second_order():
    """The vehicle's kinetic energy equals crush, backing, hinge and string work to the
    discretisation error, which falls about as dX^2 (measured: 5.1e-5, 1.8e-5, 6.6e-6,
    9.5e-7 on 32, 64, 128, 256 cells)."""
    mu, phi, v, eta0 = STRING_CASES[0]
    errors = [
        _energy_error(_string(mu, phi, v, eta0, string_cells=cells), mu, v) for cells in (32, 256)
    ]
    assert errors[1] < 2e-6
    assert errors[0] / errors[1] > 8.0**1.5


def test_string_cases_vmap_equals_loop_and_limits():
    mu, phi, v, eta0 = (jnp.asarray(x) for x in zip(*STRING_CASES))
    batched = _string(mu, phi, v, eta0)
    for i, case in enumerate(STRING_CASES):
        single = _string(*case)
        for field in ("barrier_displacement", "damage", "duration", "t_string", "string_work", "hinge_position"):
            np.testing.assert_allclose(
                getattr(batched, field)[i], getattr(single, field), rtol=1e-12, err_msg=field
            )
    string_after_crushing, string_while_crushing, no_string = (
        jax.tree.map(lambda leaf, i=i: leaf[i], batched) for i in range(3)
    )
    # N/N0 = 2 eta0 W0 reaches 1 where the string begins (3.4.43).
    for r, case in ((string_after_crushing, STRING_CASES[0]), (string_while_crushing, STRING_CASES[1])):
        assert np.isfinite(r.t_string) and r.duration > r.t_string and r.string_work > 0
        assert r.barrier_displacement > 1.0 / (2.0 * case[3])
    assert np.isinf(no_string.t_string) and no_string.string_work == 0.0
    # A vehicle that crushes to rest decelerates at phi/mu throughout: T = mu V / phi.
    mu1, phi1, v1, _ = STRING_CASES[1]
    assert float(string_while_crushing.duration) == pytest.approx(mu1 * v1 / phi1, rel=1e-6)
    assert np.all(_energy_error(batched, mu, v) < 1e-4)


def test_gradients_across_the_switch_into_the_string_match_finite_differences():
    """Final deflection, damage and duration against every input, eta0 included, for a
    string that begins after the crushing, one that begins during it, the beam stage
    alone (report 3.4's example), and a beam that locks while the vehicle crushes."""
    locked = (1.4531843284914956, 1.12764131948091, 0.8251699965190115, 16.449052816866732)
    x0 = np.array([*STRING_CASES, locked])  # (case, input)

    def outputs(x):
        r = _string(x[:, 0], x[:, 1], x[:, 2], x[:, 3])
        return jnp.stack([r.barrier_displacement, r.damage, r.duration])  # (output, case)

    jacobian = np.asarray(jax.jacfwd(outputs)(jnp.asarray(x0)))  # (output, case, case, input)
    for j in range(4):
        step = 1e-5 * x0[:, j]
        up, down = x0.copy(), x0.copy()
        up[:, j] += step
        down[:, j] -= step
        fd = (np.asarray(outputs(up)) - np.asarray(outputs(down))) / (2 * step)
        for case in range(len(x0)):
            np.testing.assert_allclose(
                jacobian[:, case, case, j], fd[:, case], rtol=2e-5, atol=1e-8, err_msg=f"{case} {j}"
            )


def test_history_through_the_string_stage():
    """Energy at every sample of the three blocks (beam phases, string, rest), the centre
    of the sampled profile is the sampled displacement, and the string starts from the
    beam's last state."""
    mu, phi, v, eta0 = STRING_CASES[0]
    r = _string(mu, phi, v, eta0, n_history=40)
    h = r.history
    assert h.time.shape == (120,) and np.all(np.diff(h.time) >= 0)
    assert h.string_profile.shape == (40, 129)
    lost = 0.5 * mu * v**2 - h.vehicle_kinetic_energy
    work = phi * h.crush + h.backing_work + h.hinge_work + h.string_work + h.beam_kinetic_energy
    # 128 cells: 5e-5 at samples within the string stage (velocities there are means of
    # the half-step ones), 7e-6 at rest.
    np.testing.assert_allclose(work, lost, atol=2e-4 * 0.5 * mu * v**2)
    np.testing.assert_allclose(h.string_profile[:, 0], h.barrier_displacement[79:119], rtol=1e-12)
    assert float(h.time[79]) == pytest.approx(float(r.t_string), rel=1e-12)
    np.testing.assert_allclose(h.axial_force[79:119], 1.0)
    assert h.barrier_displacement[-1] == r.barrier_displacement and h.time[-1] == r.duration
    assert np.all(np.diff(h.string_profile, axis=0) >= -1e-15)  # no point moves back


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"string_cells": 1}, "string_cells"),
        ({"string_cells": 2.5}, "string_cells"),
        ({"string_courant": 1.5}, "string_courant"),
        ({"string_courant": 0.0}, "string_courant"),
    ],
)
def test_bad_string_options_name_the_field(kwargs, field):
    with pytest.raises(ValueError, match=field):
        axial_impact(0.5, 2.0, 1.0, axial_ratio=10.0, **kwargs)


def test_the_string_start_pass_takes_diffraxs_constant_steps():
    """The second pass over the beam stage (`stages._trace`: Tsit5's own step in a loop)
    against `diffeqsolve` with the same constant steps, saved at the same times; and no
    step at all where the phase has no length (the string not reached)."""
    import diffrax

    from barrierjax.hinge.axial import stages

    mu, phi, eta = 0.5, 2.0, 5.0
    p = stages._Params(
        jnp.asarray(mu), jnp.asarray(phi), jnp.asarray(eta), 3.0 / (np.sqrt(phi**2 + 3) + phi)
    )
    zero = jnp.zeros(())
    y0 = stages._Accelerating(zero + 1.0, zero, zero, zero, zero, zero, zero, zero)
    hinge, samples, t_end = ("hinge_offset", p.s_star), 33, jnp.asarray(0.05)
    trace = stages._trace(
        stages._accelerating_field, hinge, y0, zero, t_end, p, samples=samples,
        solver=diffrax.Tsit5(),
    )  # fmt: skip

    def field(t, state, args):
        rates = stages._accelerating_field(t, state[0], args)
        return rates, rates.displacement / (p.s_star + state[0].hinge_offset)

    ts = t_end * jnp.linspace(0.0, 1.0, samples)
    reference = diffrax.diffeqsolve(
        diffrax.ODETerm(field), diffrax.Tsit5(), 0.0, t_end, t_end / (samples - 1), (y0, zero),
        args=p, saveat=diffrax.SaveAt(ts=ts), stepsize_controller=diffrax.ConstantStepSize(),
        max_steps=samples,
    ).ys  # fmt: skip
    expected = np.stack(
        [p.s_star + reference[0].hinge_offset, reference[0].displacement, reference[1]]
    )
    assert float(jnp.max(reference[0].displacement)) > 1e-3  # the pass does move
    np.testing.assert_allclose(trace.values, expected, rtol=1e-12, atol=1e-15)
    still = stages._trace(
        stages._accelerating_field, hinge, y0, zero, zero, p, samples=samples,
        solver=diffrax.Tsit5(),
    )  # fmt: skip
    np.testing.assert_array_equal(still.values, np.repeat(still.values[:, :1], samples, axis=1))
    with pytest.raises(TypeError, match="explicit solver's steps; got Kvaerno5"):
        stages._trace(
            stages._accelerating_field, hinge, y0, zero, t_end, p, samples=samples,
            solver=diffrax.Kvaerno5(),
        )  # fmt: skip


def test_the_string_start_pass_steps_only_where_a_member_reaches_the_string():
    """Under `vmap` (a model's vmapped chunk) the second pass steps while any member has a
    phase to trace, and not at all where none has: its `lax.scan` took every step in every
    chunk, and the axial batch of 10^4 ran 3.2 times as long."""
    import diffrax

    from barrierjax.hinge.axial import stages

    steps = []

    class Counted(diffrax.Tsit5):
        def step(self, terms, t0, t1, y0, args, solver_state, made_jump):
            jax.debug.callback(lambda: steps.append(1))
            return super().step(terms, t0, t1, y0, args, solver_state, made_jump)

    phi = 2.0
    p = stages._Params(
        jnp.asarray(0.5), jnp.asarray(phi), jnp.asarray(5.0), 3.0 / (np.sqrt(phi**2 + 3) + phi)
    )
    zero = jnp.zeros(())
    y0 = stages._Accelerating(zero + 1.0, zero, zero, zero, zero, zero, zero, zero)

    @jax.jit
    @jax.vmap
    def traced(t_end):
        return stages._trace(
            stages._accelerating_field, ("hinge_offset", p.s_star), y0, zero, t_end, p,
            samples=17, solver=Counted(),
        ).values  # fmt: skip

    none = jax.block_until_ready(traced(jnp.zeros(2)))
    assert steps == []
    np.testing.assert_array_equal(none, np.repeat(none[:, :, :1], 17, axis=2))
    one = jax.block_until_ready(traced(jnp.asarray([0.0, 0.05])))
    assert len(steps) == 16
    np.testing.assert_array_equal(one[0], none[0])
    assert float(jnp.max(one[1, 1])) > 1e-3
