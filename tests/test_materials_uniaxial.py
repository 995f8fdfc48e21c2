"""Uniaxial laws of report 2.2 and `uniaxial_response` (units: MPa, s)."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax.materials.curves import Bilinear, ElasticPerfectlyPlastic, Tabulated
from barrierjax.materials.hereditary import HereditaryLaw
from barrierjax.materials.overstress import (
    CowperSymonds,
    GilmanJohnston,
    LinearOverstress,
    LogOverstress,
    OverstressState,
    QuadraticOverstress,
    SinhOverstress,
    StrainDependentOverstress,
)
from barrierjax.materials.plasticity import RateIndependentPlasticity
from barrierjax.materials.response import uniaxial_response, update_with_tangent

E, SIGMA0, TAU, RATE = 200e3, 250.0, 1e-3, 5.0
T_YIELD = SIGMA0 / (E * RATE)

response = eqx.filter_jit(uniaxial_response)


def _constant_rate_times(n):
    """Samples on [0, 4 tau + t_y] with one at the yield time, so no step straddles the kink."""
    return jnp.concatenate(
        [jnp.linspace(0, T_YIELD, 3)[:-1], jnp.linspace(T_YIELD, T_YIELD + 4 * TAU, n)]
    )


def _richardson(law, times, substeps=(64, 128, 256)):
    """Backward-Euler stresses at three step sizes, their error ratios and the extrapolation
    that cancels the O(dt) and O(dt^2) terms."""
    strains = RATE * times
    s1, s2, s4 = (response(law, times, strains, substeps=n).stress for n in substeps)
    return (s1, s2, s4), (8 * s4 - 6 * s2 + s1) / 3


def _linear_closed_form(t):
    """(2.2.4) with the elastic-perfectly plastic curve at constant rate."""
    after = jnp.maximum(t - T_YIELD, 0)
    plastic = SIGMA0 + E * RATE * TAU * -jnp.expm1(-after / TAU)
    return jnp.where(t < T_YIELD, E * RATE * t, plastic)


def _relative_error(a, b):
    return float(jnp.max(jnp.abs(a - b)) / jnp.max(jnp.abs(b)))


def test_linear_overstress_closed_form_implicit_first_order():
    times = _constant_rate_times(9)
    (s1, s2, s4), extrapolated = _richardson(LinearOverstress(E, SIGMA0, TAU), times)
    exact = _linear_closed_form(times)
    errors = [_relative_error(s, exact) for s in (s1, s2, s4)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    np.testing.assert_allclose(orders, 1.0, atol=0.03)  # measured 1.00, 1.00
    assert errors[-1] < 6e-4
    assert _relative_error(extrapolated, exact) < 1e-8


def test_linear_overstress_closed_form_diffrax():
    times = _constant_rate_times(9)
    law = LinearOverstress(E, SIGMA0, TAU)
    result = response(law, times, RATE * times, method="diffrax", rtol=1e-11, atol=1e-15)
    assert _relative_error(result.stress, _linear_closed_form(times)) < 1e-8


def test_log_overstress_constant_rate_closed_form():
    """(2.2.8) at constant rate, derived again (the printed form multiplies where it divides)."""
    sigma_c = 20.0
    times = _constant_rate_times(9)
    law = LogOverstress(E, SIGMA0, sigma_c, TAU)
    after = jnp.maximum(times - T_YIELD, 0)
    decay = jnp.exp(-(E * RATE / sigma_c + 1 / TAU) * after)
    plastic = SIGMA0 - sigma_c * jnp.log(decay + (1 - decay) / (1 + E * RATE * TAU / sigma_c))
    exact = jnp.where(times < T_YIELD, E * RATE * times, plastic)
    # the flow saturates on the time scale 1/beta = 2e-5 s, so backward Euler is already
    # close: measured 1.5e-10 (7.7e-10 at 32 substeps)
    stress = response(law, times, RATE * times, substeps=64).stress
    assert _relative_error(stress, exact) < 1e-9
    asymptote = SIGMA0 + sigma_c * np.log(1 + E * RATE * TAU / sigma_c)
    np.testing.assert_allclose(exact[-1], asymptote, rtol=1e-6)


def test_strain_dependent_overstress_closed_form_and_slope():
    """(2.2.5) with mu = eps0/(eps0 - eps): the report's constant-rate solution."""
    eps0 = -0.002
    times = _constant_rate_times(9)
    law = StrainDependentOverstress(E, SIGMA0, TAU, eps0)

    def closed_form(t, rate):
        strain, yield_strain = rate * t, SIGMA0 / E
        m = -eps0 / (rate * TAU)
        ratio = (strain - eps0) / (yield_strain - eps0)
        plastic = SIGMA0 + E * (yield_strain - eps0) / (1 + m) * (ratio - ratio ** (-m))
        return jnp.where(strain < yield_strain, E * strain, plastic)

    _, extrapolated = _richardson(law, times)
    assert _relative_error(extrapolated, closed_form(times, RATE)) < 1e-8
    slopes = [E / (1 - eps0 / (rate * TAU)) for rate in (1.0, 10.0, 100.0)]
    assert slopes[0] < slopes[1] < slopes[2]


@pytest.mark.parametrize(
    "law, steady",
    [
        (CowperSymonds(E, SIGMA0, 40.0, 5.0), SIGMA0 * (1 + (RATE / 40.0) ** (1 / 5))),
        (LogOverstress(E, SIGMA0, 20.0, TAU), SIGMA0 + 20.0 * np.log(1 + E * RATE * TAU / 20.0)),
    ],
    ids=["cowper-symonds", "log"],
)
def test_steady_flow_at_constant_rate(law, steady):
    """Backward Euler's fixed point at constant rate is the exact steady state g(x) = E rate."""
    times = jnp.linspace(0, 1.0, 28)
    result = response(law, times, RATE * times, substeps=2)
    np.testing.assert_allclose(result.stress[-1], steady, rtol=1e-10)


RELAXING = {
    "linear-bilinear": LinearOverstress(E, Bilinear(SIGMA0, 2e3), TAU),
    "strain-dependent": StrainDependentOverstress(E, SIGMA0, TAU, -0.002),
    "log-tabulated": LogOverstress(
        E, Tabulated(jnp.array([0.0, 0.002, 0.02]), jnp.array([SIGMA0, 300.0, 320.0])), 20.0, TAU
    ),
    "sinh": SinhOverstress(E, SIGMA0, 20.0, TAU),
    "cowper-symonds": CowperSymonds(E, SIGMA0, 40.0, 5.0),
    "quadratic": QuadraticOverstress(E, SIGMA0, TAU),
}


ENERGY_LAWS = {
    **RELAXING,
    "gilman-johnston": GilmanJohnston(E, 1e3, SIGMA0 * 7.0),
    "rate-independent": RateIndependentPlasticity(E, SIGMA0, isotropic=2e3, kinematic=1e3),
}


@pytest.mark.parametrize("name", list(ENERGY_LAWS))
def test_energy_balance_and_dissipation(name):
    """Energy over a cycle with holds (load, relax, reverse, relax). With sigma = E (eps -
    eps_p), the work put in, sum sigma_(n+1) d_eps, splits exactly into the stored elastic
    energy sigma^2 / 2E, the plastic work sum sigma_(n+1) d_eps_p and backward Euler's own
    loss sum d_sigma^2 / 2E. The plastic work of every step must be non-negative (the
    second law; with kinematic hardening part of it is stored in the back stress), and the
    numerical loss must vanish at first order in the step, so that the work converges to
    stored energy plus plastic work."""
    law = ENERGY_LAWS[name]
    knots_t = jnp.array([0.0, 1.0, 2.0, 4.0, 5.0]) * 2 * TAU
    knots_e = jnp.array([0.0, 4.0, 4.0, -4.0, -4.0]) * SIGMA0 / E
    losses = []
    for n in (200, 400):
        times = jnp.linspace(0.0, knots_t[-1], n + 1)
        strains = jnp.interp(times, knots_t, knots_e)
        result = response(law, times, strains)
        stress, plastic = result.stress, result.plastic_strain
        plastic_work = stress[1:] * jnp.diff(plastic)
        loss = jnp.sum(jnp.diff(stress) ** 2) / (2 * E)
        scale = SIGMA0 * float(jnp.max(jnp.abs(knots_e)))
        assert float(jnp.min(plastic_work)) >= -1e-12 * scale
        losses.append(float(loss))
    assert losses[1] / losses[0] == pytest.approx(0.5, abs=0.05)


@pytest.mark.parametrize("name", list(RELAXING))
def test_relaxation_ends_on_static_curve(name):
    """Load at 100/s to 1 %, then hold: the stress decays onto k(kappa), never below it.

    Cowper-Symonds relaxes algebraically (x ~ t^(-1/4)), hence the hold to 1e16 s; backward
    Euler takes it in a few geometric steps."""
    law = RELAXING[name]
    loading = jnp.linspace(0, 1e-4, 5)
    times = jnp.concatenate([loading, 1e-4 + jnp.logspace(-6, 16, 23)])
    strains = jnp.minimum(100.0 * times, 0.01)
    result = response(law, times, strains, substeps=2)
    static = law.static_stress(result.plastic_strain)
    hold = result.stress[5:]
    assert np.all(np.diff(np.asarray(hold)) <= 1e-9)
    assert np.all(np.asarray(hold - static[5:]) >= -1e-9)
    np.testing.assert_allclose(hold[-1], static[-1], rtol=2e-5)
    assert hold[0] > static[5] + 10  # it was well above the curve when the hold began


def test_unloading_rules():
    """Reversal from flow: by default flow continues while above the curve; with the report's
    rule (elastic_unloading) the first reversed step is elastic."""
    times = jnp.array([0.0, 1e-3, 1.01e-3, 1.1])
    strains = jnp.array([0.0, 5e-3, 4.9e-3, 4.9e-3])
    drop = {}
    for rule in (False, True):
        law = LinearOverstress(E, SIGMA0, TAU, elastic_unloading=rule)
        stress = response(law, times, strains, substeps=50).stress
        drop[rule] = float(stress[1] - stress[2])
    np.testing.assert_allclose(drop[True], E * 1e-4, rtol=1e-12)
    assert drop[False] > E * 1e-4 * 1.05
    # below the curve the unloading is elastic under both rules
    law = LinearOverstress(E, SIGMA0, TAU)
    times = jnp.array([0.0, 1e-3, 1.1, 1.2])
    stress = response(law, times, jnp.array([0.0, 5e-3, 5e-3, 4e-3]), substeps=50).stress
    np.testing.assert_allclose(stress[2] - stress[3], E * 1e-3, rtol=1e-9)


STIFF = {
    "linear": LinearOverstress(E, SIGMA0, 1e-7),
    "log": LogOverstress(E, SIGMA0, 20.0, 1e-7),
    "cowper-symonds": CowperSymonds(E, SIGMA0, 1e7, 5.0),
}
STIFF_STEADY = {
    "linear": SIGMA0 + E * 1.0 * 1e-7,
    "log": SIGMA0 + 20.0 * np.log(1 + E * 1e-7 / 20.0),
    "cowper-symonds": SIGMA0 * (1 + 1e-7 ** (1 / 5)),
}


@pytest.mark.parametrize("name", list(STIFF))
def test_stiff_end_implicit_stable_explicit_not(name):
    """Rate 1/s with steps dt = 1e-3 s = 1e4 tau (the same compiled function as the steady
    and relaxation tests): backward Euler stays monotone and ends on the steady value; forward
    Euler, stable only for dt < 2 / g'(x), blows up."""
    law = STIFF[name]
    times = jnp.linspace(0, 5.4e-2, 28)  # 2 substeps of 1e-3 s per sample
    strains = 1.0 * times
    implicit = response(law, times, strains, substeps=2).stress
    assert np.all(np.isfinite(implicit)) and np.all(np.diff(np.asarray(implicit)) >= -1e-9)
    np.testing.assert_allclose(implicit[-1], STIFF_STEADY[name], rtol=1e-10)
    explicit = response(law, times, strains, method="explicit", substeps=2).stress
    assert not np.all(np.abs(np.asarray(explicit)) < 10 * SIGMA0)


@pytest.mark.parametrize(
    "make",
    [
        lambda **options: CowperSymonds(2e11, 2.5e8, 40.0, 5.0, **options),
        lambda **options: LogOverstress(2e11, 2.5e8, 2e7, 1e-3, **options),
        lambda **options: SinhOverstress(2e11, 2.5e8, 2e7, 1e-3, **options),
    ],
    ids=["CowperSymonds", "LogOverstress", "SinhOverstress"],
)
def test_backward_euler_converges_within_its_iterations(make):
    """The default iteration count reaches the root that 60 iterations reach, over random
    stresses, plastic strains and strain increments, at slow, fast and stiff steps. (A
    residual of rounding noise once sent the iteration bisecting towards a stale end of its
    bracket, so the result depended on the count: 21 sigma0 off at 8 iterations.)"""
    rng = np.random.default_rng(0)
    n = 2000
    stress = jnp.asarray(rng.uniform(-1.5, 1.5, n) * 2.5e8)
    plastic = jnp.asarray(rng.uniform(-1e-2, 1e-2, n))
    d_strain = jnp.asarray(rng.uniform(-2e-3, 2e-3, n))
    for dt in (1e-7, 1e-4, 1.0):
        results = []
        for law in (make(iterations=60), make()):

            def update(s, p, d, law=law, dt=dt):
                return law.update(s, OverstressState(p, jnp.abs(p)), d, dt)[0]

            results.append(np.asarray(jax.jit(jax.vmap(update))(stress, plastic, d_strain)))
        np.testing.assert_allclose(results[1], results[0], rtol=0, atol=1e-12 * 2.5e8)


def test_report_scheme_second_order_and_stiff_oscillation():
    """(4.2.8)-(4.2.10) is trapezoidal in the flow: second order where the step resolves tau;
    on the stiff end its amplification of the overstress tends to -1: a relaxation step
    reflects the overstress x to -x, and below the curve (4.2.12) freezes the stress there."""
    times = _constant_rate_times(9)
    law = LinearOverstress(E, SIGMA0, TAU)
    errors = [
        _relative_error(
            response(law, times, RATE * times, method="report", substeps=n).stress,
            _linear_closed_form(times),
        )
        for n in (40, 80)
    ]
    assert np.log2(errors[0] / errors[1]) > 1.8
    stiff = LinearOverstress(E, SIGMA0, 1e-7)
    hold = jnp.array([0.0, 1e-3, 2e-3, 3e-3, 4e-3])
    stress = response(stiff, hold, jnp.full(5, 0.0025), method="report").stress
    np.testing.assert_allclose(stress[1] - SIGMA0, -(stress[0] - SIGMA0), rtol=1e-3)
    np.testing.assert_allclose(stress[1:], stress[1], rtol=1e-12)
    implicit = response(stiff, hold, jnp.full(5, 0.0025)).stress
    np.testing.assert_allclose(implicit[1:], SIGMA0, rtol=1e-4)


@eqx.filter_jit
def _every_step(law, increments, dt):
    """(stress, yield function) after each of the strain increments."""

    def step(carry, d_strain):
        stress, state = law.update(*carry, d_strain, dt)
        return (stress, state), (stress, law.yield_function(stress, state))

    return jax.lax.scan(step, (jnp.zeros_like(dt), law.init_state()), increments)[1]


def test_rate_independent_isotropic_and_kinematic_cycles():
    """Strain 0 -> 1 % -> -1 % -> 1 % in steps of 1e-4: the stress never leaves the yield
    surface and lies on it while flowing; reverse yield comes at -peak with isotropic and at
    peak - 2 sigma0 with kinematic hardening (Bauschinger)."""
    H, step = 10e3, 1e-4
    increments = jnp.concatenate([jnp.full(100, step), jnp.full(200, -step), jnp.full(200, step)])
    peak = SIGMA0 + H * (0.01 - SIGMA0 / E) / (1 + H / E)
    for kinematic in (False, True):
        law = RateIndependentPlasticity(
            E, SIGMA0, isotropic=0.0 if kinematic else H, kinematic=H if kinematic else 0.0
        )
        stress, surface = (np.asarray(a) for a in _every_step(law, increments, jnp.asarray(0.01)))
        assert np.all(surface <= 1e-9)
        previous = np.concatenate([[0.0], stress[:-1]])
        plastic = np.abs(stress - previous - E * np.asarray(increments)) > 1e-9
        np.testing.assert_allclose(surface[plastic], 0, atol=1e-9)
        np.testing.assert_allclose(stress[99], peak, rtol=1e-12)
        reverse_yield = previous[100 + np.argmax(plastic[100:])]  # the last elastic stress
        expected = peak - 2 * SIGMA0 if kinematic else -peak
        np.testing.assert_allclose(reverse_yield, expected, atol=E * step)
        if kinematic:
            np.testing.assert_allclose(stress[299], -peak, rtol=1e-9)
        else:  # the surface grew
            assert -stress[299] > peak


@eqx.filter_jit
def _tangents(law, stress, state, d_strain, dt, h=1e-9):
    """The consistent tangent and its central difference."""
    up = law.update(stress, state, d_strain + h, dt)[0]
    down = law.update(stress, state, d_strain - h, dt)[0]
    return update_with_tangent(law, stress, state, d_strain, dt)[2], (up - down) / (2 * h)


@pytest.mark.parametrize(
    "law",
    [
        RateIndependentPlasticity(E, SIGMA0, isotropic=5e3, kinematic=3e3),
        LogOverstress(E, Bilinear(SIGMA0, 2e3), 20.0, TAU),
        CowperSymonds(E, SIGMA0, 40.0, 5.0),
        HereditaryLaw(E, SIGMA0, jnp.array([0.4, 0.6]), jnp.array([1e-4, 1e-2])),
    ],
    ids=["plasticity", "log-bilinear", "cowper-symonds", "hereditary"],
)
def test_consistent_tangent_against_finite_differences(law):
    stress, state = law.update(
        jnp.zeros(()), law.init_state(), jnp.asarray(2e-3), jnp.asarray(1e-3)
    )
    for d_strain in (1e-3, -1e-4, 3e-5):  # loading, unloading, and a slow step
        d_strain, dt = jnp.asarray(d_strain), jnp.asarray(1e-4)
        tangent, expected = _tangents(law, stress, state, d_strain, dt)
        np.testing.assert_allclose(tangent, expected, rtol=1e-5)
    if isinstance(law, RateIndependentPlasticity):
        H = 8e3
        tangent = _tangents(law, stress, state, jnp.asarray(1e-3), dt)[0]
        np.testing.assert_allclose(tangent, E * H / (E + H), rtol=1e-12)


def test_hereditary_relaxation_recovers_psi():
    """Instantaneous strain, then hold: psi(t) = (sigma^2 - sigma0^2) / (sigma*^2 - sigma0^2)."""
    law = HereditaryLaw(E, SIGMA0, jnp.array([0.2, 0.3, 0.5]), jnp.array([1e-4, 1e-2, 1.0]))
    times = jnp.concatenate([jnp.zeros(1), jnp.logspace(-6, 1, 15)])
    stress = response(law, times, jnp.full(16, 0.01)).stress
    measured = (stress**2 - SIGMA0**2) / (stress[0] ** 2 - SIGMA0**2)
    np.testing.assert_allclose(stress[0], E * 0.01, rtol=1e-14)
    np.testing.assert_allclose(measured, law.relaxation_function(times), atol=1e-13)


def test_hereditary_single_term_is_the_quadratic_law():
    """One Prony term, theta = tau/2: the uniaxial (2.2.12); both first order, their
    extrapolations agree."""
    times = jnp.array([0.0, 2e-3, 4e-3, 6e-3, 8e-3])
    strains = jnp.array([0.0, 1e-2, 1e-2, 5e-3, 8e-3])
    hereditary = HereditaryLaw(E, SIGMA0, jnp.ones(1), jnp.array([TAU / 2]))
    quadratic = QuadraticOverstress(E, SIGMA0, TAU)

    def extrapolated(law):
        s1, s2 = (response(law, times, strains, substeps=n).stress for n in (200, 400))
        return 2 * s2 - s1, s2

    (h_extrapolated, h), (q_extrapolated, q) = extrapolated(hereditary), extrapolated(quadratic)
    assert _relative_error(h, q) < 2e-3
    assert _relative_error(h_extrapolated, q_extrapolated) < 2e-5


CYCLE_TIMES = jnp.array([0.0, 3e-4, 6e-4, 1e-3, 2e-3, 3e-3, 4e-3, 5e-3, 8e-3, 1.2e-2])
CYCLE_STRAINS = jnp.array([0.0, 1.5e-3, 3e-3, 4e-3, 6e-3, 4.5e-3, 3e-3, -2e-3, -2e-3, -2e-3])
ALL_LAWS = {
    "plasticity": RateIndependentPlasticity(E, SIGMA0, isotropic=5e3, kinematic=3e3),
    "linear": LinearOverstress(E, Bilinear(SIGMA0, 2e3), TAU),
    "strain-dependent": StrainDependentOverstress(E, SIGMA0, TAU, -0.002),
    "log": LogOverstress(E, SIGMA0, 20.0, TAU),
    "sinh": SinhOverstress(E, SIGMA0, 20.0, TAU),
    "cowper-symonds": CowperSymonds(E, SIGMA0, 40.0, 5.0),
    "gilman-johnston": GilmanJohnston(E, 1e3, 2500.0),
    "quadratic": QuadraticOverstress(E, SIGMA0, TAU),
    "hereditary": HereditaryLaw(E, SIGMA0, jnp.array([0.4, 0.6]), jnp.array([1e-4, 1e-2])),
}


def _total_stress(law, strains):
    return jnp.sum(uniaxial_response(law, CYCLE_TIMES, strains).stress)


def _with_value(law, strains):
    total = _total_stress(law, strains)
    return total, total


_batched_total_stress = eqx.filter_jit(eqx.filter_vmap(_total_stress))
# (derivative, value) from one compiled function, which also serves the loop
_by_reverse_mode = eqx.filter_jit(jax.grad(_with_value, has_aux=True))
_by_forward_mode = eqx.filter_jit(jax.jacfwd(_with_value, has_aux=True))


@pytest.mark.parametrize("name", list(ALL_LAWS))
def test_vmap_equals_loop_and_gradient_matches_finite_differences(name):
    """One vmapped call over laws and strain histories evaluates three scaled members and every
    central difference (relative step 1e-6 per parameter); three members against a loop of
    single calls; the derivative of the summed stress history w.r.t. every parameter, by
    reverse mode (forward mode for odd-numbered laws), against the differences."""
    law = ALL_LAWS[name]
    leaves, treedef = jax.tree.flatten(law)
    flat = [np.asarray(leaf).ravel() for leaf in leaves]
    members = []  # (leaf values, history) per batch member
    for scale in (0.9, 1.0, 1.1):
        members.append(([leaf * scale for leaf in flat], np.asarray(CYCLE_STRAINS) * scale))
    steps = []
    for i, leaf in enumerate(flat):
        for j in range(leaf.size):
            h = 1e-6 * abs(leaf[j])
            steps.append(h)
            for sign in (1, -1):
                bumped = [other.copy() for other in flat]
                bumped[i][j] += sign * h
                members.append((bumped, np.asarray(CYCLE_STRAINS)))
    batch = jax.tree.unflatten(
        treedef,
        [
            jnp.asarray(np.stack([m[0][i] for m in members]).reshape((-1,) + leaves[i].shape))
            for i in range(len(leaves))
        ],
    )
    totals = _batched_total_stress(batch, jnp.asarray(np.stack([m[1] for m in members])))
    differentiate = _by_forward_mode if list(ALL_LAWS).index(name) % 2 else _by_reverse_mode
    for k, (values, history) in enumerate(members[:3]):
        member = jax.tree.unflatten(
            treedef, [jnp.asarray(v.reshape(leaf.shape)) for v, leaf in zip(values, leaves)]
        )
        single = differentiate(member, jnp.asarray(history))[1]
        np.testing.assert_allclose(totals[k], single, rtol=1e-12)

    derivative = differentiate(law, CYCLE_STRAINS)[0]
    gradient = np.concatenate([np.ravel(g) for g in jax.tree.leaves(derivative)])
    central = np.asarray(totals[3::2] - totals[4::2]) / (2 * np.array(steps))
    np.testing.assert_allclose(gradient, central, rtol=1e-5, atol=1e-9 * abs(float(totals[1])))


def test_bad_inputs():
    with pytest.raises(ValueError, match="E must be positive"):
        LinearOverstress(-1.0, SIGMA0, TAU)
    with pytest.raises(ValueError, match="sigma0 must be positive"):
        LinearOverstress(E, 0.0, TAU)
    with pytest.raises(ValueError, match="tau must be positive"):
        LogOverstress(E, SIGMA0, 20.0, 0.0)
    with pytest.raises(ValueError, match="sigma_c must be positive"):
        LogOverstress(E, SIGMA0, -1.0, TAU)
    with pytest.raises(ValueError, match="D must be positive"):
        CowperSymonds(E, SIGMA0, 0.0, 5.0)
    with pytest.raises(ValueError, match="q must be positive"):
        CowperSymonds(E, SIGMA0, 40.0, -5.0)
    with pytest.raises(ValueError, match="eps0 must be negative"):
        StrainDependentOverstress(E, SIGMA0, TAU, 0.01)
    with pytest.raises(ValueError, match="weights must be non-negative, summing to 1"):
        HereditaryLaw(E, SIGMA0, jnp.array([0.5, 0.6]), jnp.array([1.0, 2.0]))
    with pytest.raises(ValueError, match="plastic_strain must be strictly increasing"):
        Tabulated(jnp.array([0.0, 0.0, 1.0]), jnp.array([1.0, 2.0, 3.0]))
    law = LinearOverstress(E, ElasticPerfectlyPlastic(SIGMA0), TAU)
    with pytest.raises(ValueError, match="times must be strictly increasing"):
        uniaxial_response(law, jnp.array([0.0, 1.0, 1.0]), jnp.zeros(3))
    with pytest.raises(ValueError, match="strains must have the shape of times"):
        uniaxial_response(law, jnp.array([0.0, 1.0, 2.0]), jnp.zeros(2))
    with pytest.raises(ValueError, match="method must be one of"):
        uniaxial_response(law, jnp.array([0.0, 1.0]), jnp.zeros(2), method="rk4")
    plasticity = RateIndependentPlasticity(E, SIGMA0)
    with pytest.raises(ValueError, match="method must be 'implicit'"):
        uniaxial_response(plasticity, jnp.array([0.0, 1.0]), jnp.zeros(2), method="report")
