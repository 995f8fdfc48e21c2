"""Normal impact (report 3.2): closed forms, limits, invariants, batching, gradients, bad input."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from barrierjax.hinge import normal_impact

METHODS = ["closed_form", "ode"]
CASES = [(1.0, 2.0, 0.7), (300.0, 1.3, 3.0), (1e-2, 50.0, 0.1), (25.0, 1.45, 0.12)]


def rel(a, b):
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)) / np.abs(np.asarray(b))))


# --- An independent reference: QUADPACK's algebraic-weight rule on (3.2.19)-(3.2.20). ---


def reference(mu, phi, v0):
    """T**, W_final and damage from the report's formulas, re-derived, with numpy's cubic
    roots and scipy's QAWS rule for the end singularity (alpha - S)^(A-1)."""
    s_star = math.sqrt(phi**2 + 3) - phi
    accel = (phi - s_star) / s_star
    t_star = v0 / (phi / mu + accel)
    v_star, w_star = accel * t_star, 0.5 * accel * t_star**2
    roots = np.sort(np.roots([1.0, 3.0 * mu, -3.0, -3.0 * mu]).real)
    alpha, beta, gamma = roots[2], -roots[1], -roots[0]
    a = (3 + alpha**2) / ((alpha + beta) * (alpha + gamma))
    b = (3 + beta**2) / ((alpha + beta) * (beta - gamma))
    c = (3 + gamma**2) / ((gamma + alpha) * (gamma - beta))

    def smooth_velocity(s):  # V / (alpha - S)^A
        return (
            v_star
            * (alpha - s_star) ** -a
            * ((s + beta) / (s_star + beta)) ** b
            * ((s + gamma) / (s_star + gamma)) ** c
        )

    def smooth_rate(s):  # dT/dS / (alpha - S)^(A-1)
        return 2 * s * (s + 2 * mu) * smooth_velocity(s) / ((s + beta) * (s + gamma))

    options = dict(weight="alg", epsabs=0.0, epsrel=1e-12, limit=200)
    dt = quad(smooth_rate, s_star, alpha, wvar=(0.0, a - 1.0), **options)[0]
    dw = quad(
        lambda s: smooth_rate(s) * smooth_velocity(s), s_star, alpha, wvar=(0.0, 2 * a - 1.0), **options
    )[0]
    return dict(duration=t_star + dt, barrier_displacement=w_star + dw, damage=0.5 * v0 * t_star, hinge_position=alpha)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mu, phi, v0", CASES)
def test_matches_independent_quadrature(method, mu, phi, v0):
    result = normal_impact(mu, phi, v0, method=method, rtol=1e-10)
    expected = reference(mu, phi, v0)
    for field, value in expected.items():
        assert rel(getattr(result, field), value) < 1e-8, field


def test_accelerative_phase_closed_form():
    """(3.2.11)-(3.2.14) with (3.2.10) corrected, and D = V0 T*/2 (docs/errata.md, 3.2.10)."""
    mu, phi, v0 = 3.0, 1.7, 0.9
    r = normal_impact(mu, phi, v0)
    s = float(r.s_star)
    assert abs(s**2 + 2 * phi * s - 3) < 1e-14  # q0 xi^2 + P0 xi - 12 M0 = 0
    t_star = mu * v0 * s / (phi * s + mu * (phi - s))
    assert rel(r.t_star, t_star) < 1e-14
    assert rel(r.v_star, mu * v0 * (phi - s) / (phi * s + mu * (phi - s))) < 1e-14
    assert rel(r.damage, 0.5 * v0 * t_star) < 1e-14
    # The report's printed D/V0^2 lacks the factor 1/2 (docs/errata.md, 3.2 damage).
    printed = mu * (math.sqrt(phi**2 + 3) - phi) / (
        phi * math.sqrt(phi**2 + 3) - phi**2 + mu * (2 * phi - math.sqrt(phi**2 + 3))
    )
    assert rel(r.damage / v0**2, 0.5 * printed) < 1e-14


def test_final_hinge_is_root_of_cubic():
    for mu in [1e-3, 0.5, 7.0, 1e4]:
        alpha = float(normal_impact(mu, 2.0, 1.0).hinge_position)
        assert 1.0 <= alpha <= math.sqrt(3.0)
        assert abs(alpha**3 + 3 * mu * alpha**2 - 3 * alpha - 3 * mu) < 1e-12 * (1 + mu)


def test_heavy_rigid_vehicle_limit():
    """mu -> infinity, phi -> infinity (report, after 3.2.20): T = (2V0/3) ln(1/(1 - S^2))
    and V/V0 = ((1 - S)/(1 + S))^(2/(3 mu)); errors are O(1/mu) and O(1/phi)."""
    mu, phi, v0 = 1e4, 1e5, 2.0
    h = normal_impact(mu, phi, v0, n_history=400).history
    s, t, v = np.asarray(h.hinge_position), np.asarray(h.time), np.asarray(h.barrier_velocity)
    mask = (np.arange(s.size) >= s.size // 2) & (s > 0.2) & (s < 0.9)
    assert mask.sum() > 5
    approx_t = 2 * v0 / 3 * np.log(1 / (1 - s[mask] ** 2))
    assert np.max(np.abs(t[mask] - approx_t) / approx_t) < 2e-3
    approx_v = v0 * ((1 - s[mask]) / (1 + s[mask])) ** (2 / (3 * mu))
    assert np.max(np.abs(v[mask] - approx_v) / approx_v) < 1e-4


def test_speed_only_rescales():
    """Report, after 3.2.20: for fixed S, T and V are proportional to V0 and W to V0^2."""
    a = normal_impact(2.0, 1.8, 1.0)
    b = normal_impact(2.0, 1.8, 7.0)
    assert rel(b.duration, 7.0 * a.duration) < 1e-14
    assert rel(b.barrier_displacement, 49.0 * a.barrier_displacement) < 1e-14
    assert rel(b.hinge_position, a.hinge_position) < 1e-14


@pytest.mark.parametrize("method", METHODS)
def test_rigid_barrier_when_force_ratio_at_most_one(method):
    mu, v0 = 4.0, 0.5
    for phi in [0.3, 1.0]:
        r = normal_impact(mu, phi, v0, method=method)
        assert float(r.barrier_displacement) == 0.0 and float(r.hinge_position) == 0.0
        assert rel(r.damage, mu * v0**2 / (2 * phi)) < 1e-14
        assert rel(r.duration, mu * v0 / phi) < 1e-14
    # Continuous as phi -> 1+: the barrier barely moves and the vehicle does the crushing.
    r = normal_impact(mu, 1.0 + 1e-9, v0, method=method)
    assert rel(r.damage, mu * v0**2 / 2) < 1e-8
    assert float(r.barrier_displacement) < 1e-8


# --- Energy: vehicle KE = crush + backing + hinge work + beam KE + vehicle KE, always. ---


def energy_residual(result, mu, phi, v0):
    h = result.history
    crush_work = phi * h.crush
    total = (
        h.vehicle_kinetic_energy + crush_work + h.backing_work + h.hinge_work + h.beam_kinetic_energy
    )
    return np.max(np.abs(np.asarray(total) - 0.5 * mu * v0**2)) / (0.5 * mu * v0**2)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mu, phi, v0", CASES + [(0.5, 0.8, 1.0)])
def test_energy_balance_at_every_saved_time(method, mu, phi, v0):
    result = normal_impact(mu, phi, v0, method=method, rtol=1e-10, n_history=50)
    assert energy_residual(result, mu, phi, v0) < 1e-8
    final = result.crush_work + result.backing_work + result.hinge_work
    assert rel(final, 0.5 * mu * v0**2) < 1e-8


@pytest.mark.parametrize("method", METHODS)
def test_histories_are_physical(method):
    h = normal_impact(5.0, 2.0, 1.0, method=method, n_history=60).history
    n = h.time.shape[0] // 2
    assert np.all(np.diff(np.asarray(h.time)) >= 0)
    assert np.all(np.diff(np.asarray(h.hinge_position)) >= -1e-12)
    assert np.all(np.diff(np.asarray(h.barrier_displacement)) >= 0)
    assert np.all(np.diff(np.asarray(h.barrier_velocity[n:])) <= 0)
    assert np.all(np.asarray(h.contact_force) > 0) and float(h.barrier_velocity[-1]) == 0.0
    # Vehicle and beam share their velocity throughout the decelerative phase.
    assert np.array_equal(np.asarray(h.vehicle_velocity[n:]), np.asarray(h.barrier_velocity[n:]))


def test_a_new_tolerance_runs_the_same_program(compilations):
    loose = normal_impact(1.0, 2.0, 0.7, method="ode", rtol=1e-4)
    with compilations() as programs:
        tight = normal_impact(1.0, 2.0, 0.7, method="ode", rtol=1e-10)
    assert not [m for m in programs if "normal_impact" in m], programs
    # The tolerance reaches the solver: the tighter run is the closer to the closed form.
    exact = float(normal_impact(1.0, 2.0, 0.7, rtol=1e-12).duration)
    assert abs(float(tight.duration) - exact) < 1e-3 * abs(float(loose.duration) - exact)


# --- Batches and gradients. ---


@pytest.mark.parametrize("method", METHODS)
def test_vmap_equals_loop(method, compilations):
    mu, phi, v0 = (jnp.array(x) for x in zip(*CASES, strict=True))
    batched = jax.vmap(lambda a, b, c: normal_impact(a, b, c, method=method))(mu, phi, v0)
    direct = normal_impact(mu, phi, v0, method=method)  # arrays are batched internally
    with compilations() as programs:  # three run the program of four, padded with a copy
        three = normal_impact(mu[:3], phi[:3], v0[:3], method=method)
    assert not [m for m in programs if "normal_impact" in m], programs
    np.testing.assert_allclose(three.damage, direct.damage[:3], rtol=1e-13)
    for i, case in enumerate(CASES):
        single = normal_impact(*case, method=method)
        for field in ("damage", "barrier_displacement", "duration", "hinge_position", "hinge_work"):
            assert float(getattr(batched, field)[i]) == pytest.approx(float(getattr(single, field)), rel=1e-13)
            assert float(getattr(direct, field)[i]) == pytest.approx(float(getattr(single, field)), rel=1e-13)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("mu, phi, v0", [(1.0, 2.0, 0.7), (300.0, 1.3, 3.0), (0.05, 20.0, 0.2)])
def test_gradients_match_finite_differences(method, mu, phi, v0):
    x = jnp.array([mu, phi, v0])
    fields = ("damage", "barrier_displacement", "duration")

    def outputs(x):
        r = normal_impact(x[0], x[1], x[2], method=method, rtol=1e-11)
        return jnp.stack([getattr(r, f) for f in fields])

    jacobian = jax.jacrev(outputs)(x)
    assert jnp.allclose(jax.jacfwd(outputs)(x), jacobian, rtol=1e-10, atol=0.0)
    for i in range(3):
        h = 1e-5 * x[i]
        fd = (outputs(x.at[i].add(h)) - outputs(x.at[i].add(-h))) / (2 * h)
        scale = jnp.maximum(jnp.abs(fd), 1e-6 * jnp.max(jnp.abs(jacobian), axis=1))
        assert float(jnp.max(jnp.abs(jacobian[:, i] - fd) / scale)) < 1e-5, (fields, i)


# --- Stability over the whole parameter range (issue item 9). ---

log_uniform = lambda lo, hi: st.floats(math.log(lo), math.log(hi)).map(math.exp)


@settings(max_examples=60, deadline=None)
@given(
    mu=log_uniform(1e-3, 1e4),
    phi_minus_one=log_uniform(1e-6, 1e3 - 1),
    v0=log_uniform(1e-4, 1e2),
)
def test_property_ode_agrees_with_closed_form(mu, phi_minus_one, v0):
    phi = 1.0 + phi_minus_one
    cf = normal_impact(mu, phi, v0, n_history=20)
    ode = normal_impact(mu, phi, v0, method="ode", rtol=1e-10, n_history=20)
    for r in (cf, ode):
        finite = eqx.tree_at(lambda r: r.t_string, r, None)  # inf: no axial force, no string
        assert all(np.all(np.isfinite(np.asarray(leaf))) for leaf in jax.tree.leaves(finite))
        assert np.isinf(r.t_string)
        assert energy_residual(r, mu, phi, v0) < 1e-8
    for field in ("damage", "barrier_displacement", "duration"):
        assert rel(getattr(ode, field), getattr(cf, field)) < 1e-7, field


def test_property_range_batched():
    """A dense log-uniform sample of the same ranges, in one call per method: on a CPU of
    two or more cores, in parts solved side by side (`_solve.batching.solve_padded`)."""
    rng = np.random.default_rng(0)
    n = 2400
    mu = np.exp(rng.uniform(np.log(1e-3), np.log(1e4), n))
    phi = 1.0 + np.exp(rng.uniform(np.log(1e-6), np.log(1e3 - 1), n))
    v0 = np.exp(rng.uniform(np.log(1e-4), np.log(1e2), n))
    cf = normal_impact(mu, phi, v0)
    ode = normal_impact(mu, phi, v0, method="ode", rtol=1e-10)
    for field in ("damage", "barrier_displacement", "duration"):
        assert np.all(np.isfinite(np.asarray(getattr(cf, field))))
        assert rel(getattr(ode, field), getattr(cf, field)) < 1e-7, field
    balance = (cf.crush_work + cf.backing_work + cf.hinge_work) / (0.5 * mu * v0**2)
    assert np.max(np.abs(np.asarray(balance) - 1.0)) < 1e-8


# --- Bad input. ---


@pytest.mark.parametrize(
    "kwargs, field",
    [
        (dict(mass_ratio=-1.0), "mass_ratio"),
        (dict(mass_ratio=0.0), "mass_ratio"),
        (dict(force_ratio=float("nan")), "force_ratio"),
        (dict(speed=float("inf")), "speed"),
        (dict(speed=0.0), "speed"),
    ],
)
def test_bad_input_names_the_field(kwargs, field):
    args = dict(mass_ratio=1.0, force_ratio=2.0, speed=1.0) | kwargs
    with pytest.raises(ValueError, match=field):
        normal_impact(**args)


def test_bad_options():
    with pytest.raises(ValueError, match="method"):
        normal_impact(1.0, 2.0, 1.0, method="euler")
    with pytest.raises(ValueError, match="rtol"):
        normal_impact(1.0, 2.0, 1.0, rtol=0.0)
    with pytest.raises(ValueError, match="n_history"):
        normal_impact(1.0, 2.0, 1.0, n_history=1)
    # A solver's name, not a solver: an AttributeError from deep inside diffrax.
    with pytest.raises(ValueError, match="solver must be a diffrax solver"):
        normal_impact(1.0, 2.0, 1.0, method="ode", solver="Tsit5")


def test_bad_traced_input_fails_loudly():
    run = jax.jit(lambda mu: normal_impact(mu, 2.0, 1.0).duration)
    assert np.isfinite(float(run(1.0)))
    with pytest.raises(Exception, match="mass_ratio"):
        float(run(-1.0))
