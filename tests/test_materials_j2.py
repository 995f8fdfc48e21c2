"""J2 radial return (report 2.1) and the Perzyna-type viscoplastic updates (2.2.9)-(2.2.13)."""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from barrierjax.materials import j2, perzyna

E, NU, SY = 200e3, 0.3, 250.0  # MPa
G = E / (2 * (1 + NU))
K_SHEAR = SY / np.sqrt(3.0)


def strain_path(n):
    """Increments of a smooth non-proportional path far into the plastic range."""
    s = np.linspace(0.0, 1.0, n + 1)
    eps = np.zeros((n + 1, 3, 3))
    eps[:, 0, 0] = 6e-3 * s
    eps[:, 1, 1] = -3e-3 * s
    eps[:, 0, 1] = eps[:, 1, 0] = 4e-3 * np.sin(2 * np.pi * s)
    eps[:, 1, 2] = eps[:, 2, 1] = 2e-3 * (1 - np.cos(2 * np.pi * s))
    return jnp.asarray(np.diff(eps, axis=0))


@functools.partial(jax.jit, static_argnums=0)
def drive(update, law, state, increments, *extra):
    def step(carry, increment):
        stress, state = update(law, *carry, increment, *extra)
        return (stress, state), (stress, state)

    return jax.lax.scan(step, (jnp.zeros((3, 3)), state), increments)[1]


def final_stress(update, law, state, increments, *extra):
    return drive(update, law, state, increments, *extra)[0][-1]


def effective(stress):
    """J2^(1/2) of each stress."""
    dev = stress - jnp.trace(stress, axis1=-2, axis2=-1)[..., None, None] / 3 * jnp.eye(3)
    return jnp.sqrt(0.5 * jnp.sum(dev**2, axis=(-2, -1)))


@pytest.fixture(scope="module")
def laws():
    return {
        "perfect": j2.J2Plasticity(E, NU, SY),
        "isotropic": j2.J2Plasticity(E, NU, SY, isotropic_modulus=2e3),
        "kinematic": j2.J2Plasticity(E, NU, SY, kinematic_modulus=3e3),
        "combined": j2.J2Plasticity(E, NU, SY, isotropic_modulus=1e3, kinematic_modulus=2e3),
    }


def power(x):
    return x + x**3


def viscoplastic_laws(tau):
    return {
        "2.2.10": perzyna.PerzynaLinearOverstress(E, NU, SY, tau),
        "2.2.11": perzyna.PerzynaQuadraticOverstress(E, NU, SY, tau),
        "2.2.12": perzyna.RelativeOverstress(E, NU, SY, tau),
        "2.2.13": perzyna.Craggs(E, NU, SY, tau),
        "2.2.9": perzyna.Perzyna(E, NU, SY, tau, power),
    }


# --- rate-independent J2 -------------------------------------------------------------------


def test_stays_on_yield_surface(laws):
    worst = 0.0
    for law in laws.values():
        stresses, states = drive(j2.update, law, j2.initial_state(), strain_path(50))
        f = jax.vmap(j2.yield_function, in_axes=(None, 0, 0))(law, stresses, states)
        radius = np.sqrt(2 / 3) * SY + 2 / 3 * law.isotropic_modulus * np.asarray(
            states.equivalent_plastic_strain
        )
        plastic = np.asarray(states.equivalent_plastic_strain) > 0
        assert plastic.sum() > 40
        worst = max(worst, np.max(np.abs(np.asarray(f)[plastic]) / radius[plastic]))
    assert worst < 1e-10, worst


def test_first_order_convergence_non_proportional(laws):
    law = laws["combined"]
    reference = final_stress(j2.update, law, j2.initial_state(), strain_path(12800))
    steps = (25, 50, 100, 200)
    errors = [
        float(
            jnp.linalg.norm(
                final_stress(j2.update, law, j2.initial_state(), strain_path(n)) - reference
            )
        )
        for n in steps
    ]
    order = -np.polyfit(np.log(steps), np.log(errors), 1)[0]
    assert 0.85 < order < 1.3, (order, errors)
    assert errors[-1] / float(jnp.linalg.norm(reference)) < 1e-2


def test_tangent_matches_jacfwd_and_finite_differences(laws):
    increments = strain_path(20)
    for law in laws.values():
        stresses, states = drive(j2.update, law, j2.initial_state(), increments)
        i = 12  # a plastic step mid-path
        stress = stresses[i - 1]
        state = jax.tree.map(lambda a: a[11], states)
        increment = increments[i]
        new_stress = jax.jit(
            functools.partial(lambda law, s, st, d: j2.update(law, s, st, d)[0], law, stress, state)
        )

        tangent = j2.consistent_tangent(law, stress, state, increment)
        assert states.equivalent_plastic_strain[i] > states.equivalent_plastic_strain[i - 1]
        scale = float(jnp.max(jnp.abs(tangent)))
        assert float(jnp.max(jnp.abs(tangent - jax.jacfwd(new_stress)(increment)))) < 1e-12 * scale
        h = 1e-9
        basis = jnp.eye(9).reshape(9, 3, 3)
        fd = jnp.stack(
            [
                (new_stress(increment + h * b) - new_stress(increment - h * b)) / (2 * h)
                for b in basis
            ]
        )
        fd = jnp.moveaxis(fd.reshape(3, 3, 3, 3), (0, 1), (2, 3))
        assert float(jnp.max(jnp.abs(tangent - fd))) < 1e-6 * scale
        assert jnp.allclose(tangent, jnp.transpose(tangent, (2, 3, 0, 1)))


def test_no_nan_gradient_at_zero_stress(laws):
    grad = jax.grad(
        lambda d: j2.update(laws["combined"], jnp.zeros((3, 3)), j2.initial_state(), d)[0][0, 1]
    )
    assert np.all(np.isfinite(np.asarray(grad(jnp.zeros((3, 3))))))


def uniaxial_step(update, tangent, law, stress, state, d11, *extra):
    """One step of uniaxial stress: the lateral strains make sigma22 = sigma33 = 0 (Newton on
    the consistent tangent)."""

    def increment(lateral):
        return jnp.diag(jnp.stack([d11, lateral, lateral]))

    lateral = -NU * d11
    for _ in range(4):
        residual = update(law, stress, state, increment(lateral), *extra)[0][1, 1]
        c = tangent(law, stress, state, increment(lateral), *extra)
        lateral = lateral - residual / (c[1, 1, 1, 1] + c[1, 1, 2, 2])
    return update(law, stress, state, increment(lateral), *extra)


@functools.partial(jax.jit, static_argnums=(0, 1))
def uniaxial_path(update, tangent, law, state, increments, *extra):
    def step(carry, d11):
        carry = uniaxial_step(update, tangent, law, *carry, d11, *extra)
        return carry, carry[0][0, 0]

    return jax.lax.scan(step, (jnp.zeros((3, 3)), state), increments)[1]


def test_uniaxial_bilinear_closed_form(laws):
    strain = np.linspace(0.0, 1e-2, 201)
    for law in laws.values():
        sigma = uniaxial_path(
            j2.update, j2.consistent_tangent, law, j2.initial_state(), jnp.asarray(np.diff(strain))
        )
        h = float(law.isotropic_modulus + law.kinematic_modulus)
        tangent = E * h / (E + h)
        exact = np.minimum(E * strain, SY + tangent * (strain - SY / E))[1:]
        assert np.max(np.abs(np.asarray(sigma) - exact)) < 1e-9 * SY


def test_vmap_equals_loop(laws):
    law = laws["combined"]
    yields = jnp.array([200.0, 250.0, 300.0])
    increments = strain_path(30)
    batched = jax.vmap(
        lambda y: final_stress(
            j2.update, eqx.tree_at(lambda m: m.yield_stress, law, y), j2.initial_state(), increments
        )
    )(yields)
    for i, y in enumerate(yields):
        single = final_stress(
            j2.update, eqx.tree_at(lambda m: m.yield_stress, law, y), j2.initial_state(), increments
        )
        assert jnp.allclose(batched[i], single, rtol=1e-13, atol=1e-10)


def finite_difference_gradient(objective, law, names, relative=1e-6):
    out = {}
    for name in names:
        value = getattr(law, name)
        h = relative * max(abs(float(value)), 1.0)
        where = functools.partial(lambda name, m: getattr(m, name), name)
        plus = objective(eqx.tree_at(where, law, value + h))
        minus = objective(eqx.tree_at(where, law, value - h))
        out[name] = (float(plus) - float(minus)) / (2 * h)
    return out


def assert_gradients(objective, law, names):
    grads = jax.grad(objective)(law)
    fd = finite_difference_gradient(objective, law, names)
    for name in names:
        g = float(getattr(grads, name))
        assert abs(g - fd[name]) <= 1e-5 * abs(fd[name]) + 1e-9, (name, g, fd[name])


def test_gradients_match_finite_differences(laws):
    increments = strain_path(30)

    def objective(law):
        stress = final_stress(j2.update, law, j2.initial_state(), increments)
        return stress[0, 0] + 0.7 * stress[0, 1] - 0.3 * stress[1, 2]

    names = ("young", "poisson", "yield_stress", "isotropic_modulus", "kinematic_modulus")
    assert_gradients(objective, laws["combined"], names)


@pytest.mark.parametrize(
    "field, kwargs, rule",
    [
        ("poisson", {"poisson": 0.5}, r"in \(-1, 0.5\)"),
        ("poisson", {"poisson": -1.0}, r"in \(-1, 0.5\)"),
        ("young", {"young": 0.0}, "positive"),
        ("yield_stress", {"yield_stress": -1.0}, "positive"),
        ("isotropic_modulus", {"isotropic_modulus": -1.0}, "non-negative"),
        ("kinematic_modulus", {"kinematic_modulus": np.inf}, "non-negative"),
    ],
)
def test_bad_j2_inputs(field, kwargs, rule):
    arguments = {"young": E, "poisson": NU, "yield_stress": SY} | kwargs
    with pytest.raises(ValueError, match=rf"J2Plasticity\.{field} must be {rule}"):
        j2.J2Plasticity(**arguments)


# --- viscoplastic --------------------------------------------------------------------------


def test_stiff_end_is_the_rate_independent_return(laws):
    """tau = 1e-7 s, dt = 1e-3 s (dt/tau = 1e4): every step lies within the overstress that
    dt/tau allows of the J2 perfectly plastic step, and ends on the static surface."""
    increments = strain_path(40)
    reference = drive(j2.update, laws["perfect"], j2.initial_state(), increments)[0]
    for name, law in viscoplastic_laws(1e-7).items():
        stresses = drive(perzyna.update, law, perzyna.initial_state(), increments, 1e-3)[0]
        q = np.asarray(effective(stresses)) / K_SHEAR
        assert np.all(q < 1.0 + 1e-3), name
        assert abs(q[-1] - 1.0) < 1e-3, (name, q[-1])
        gap = np.max(np.abs(np.asarray(stresses - reference))) / SY
        assert gap < 2e-3, (name, gap)


def test_any_time_step_is_stable():
    """Huge dt/tau (1e12) gives the static surface to round-off; tiny gives elastic."""
    increment = strain_path(1)[0]
    for name, law in viscoplastic_laws(1e-3).items():
        stress = perzyna.update(law, jnp.zeros((3, 3)), perzyna.initial_state(), increment, 1e9)[0]
        assert abs(float(effective(stress)) / K_SHEAR - 1.0) < 1e-9, name
        stress = perzyna.update(law, jnp.zeros((3, 3)), perzyna.initial_state(), increment, 1e-15)[
            0
        ]
        elastic = j2.update(
            j2.J2Plasticity(E, NU, 1e9), jnp.zeros((3, 3)), j2.initial_state(), increment
        )[0]
        assert jnp.allclose(stress, elastic, rtol=1e-5), name


def uniaxial_phi(name):
    return {
        "2.2.10": lambda x: 1 - 1 / np.sqrt(1 + x),
        "2.2.11": lambda x: x,
        "2.2.12": lambda x: x / (1 + x),
        "2.2.13": lambda x: np.sqrt(x / (1 + x)),
        "2.2.9": power,
    }[name]


def one_dimensional_backward_euler(phi, strains, dt, tau_eff):
    """Backward Euler of E eps' = sigma' + (E/tau_eff) Phi((sigma^2 - s0^2)/s0^2) sigma, step by
    step with brentq (independent of the library)."""
    sigma, out = 0.0, []
    for d in np.diff(strains):
        trial = sigma + E * d
        if trial <= SY:
            sigma = trial
        else:

            def g(s, trial=trial):
                return s + dt / tau_eff * phi((s**2 - SY**2) / SY**2) * s - trial

            sigma = brentq(g, SY, trial, xtol=1e-14, rtol=1e-15)
        out.append(sigma)
    return np.array(out)


def test_uniaxial_reductions():
    """Under uniaxial stress every form is the 1-D law E eps' = sigma' + Phi sigma/tau'
    with tau' = 3 G tau/E ((2.2.3) for (2.2.10)); the 3-D updates reproduce its backward
    Euler steps, and (2.2.10) converges to the closed form of (2.2.3) at constant rate."""
    tau, rate = 1e-4, 1.0
    tau_eff = 3 * G * tau / E
    duration, n = 1.5e-3, 120
    dt = duration / n
    strains = rate * dt * np.arange(n + 1)
    for name, law in viscoplastic_laws(tau).items():
        sigma = uniaxial_path(
            perzyna.update,
            perzyna.consistent_tangent,
            law,
            perzyna.initial_state(),
            jnp.asarray(np.diff(strains)),
            dt,
        )
        reference = one_dimensional_backward_euler(uniaxial_phi(name), strains, dt, tau_eff)
        assert np.max(np.abs(np.asarray(sigma) - reference)) < 1e-8 * SY, name

    def closed_form(t):
        t_yield = SY / (E * rate)
        over = E * rate * tau_eff * (1 - np.exp(-(t - t_yield) / tau_eff))
        return np.where(t < t_yield, E * rate * t, SY + over)

    law = perzyna.PerzynaLinearOverstress(E, NU, SY, tau)
    errors = []
    for n in (120, 240):
        dt = duration / n
        sigma = uniaxial_path(
            perzyna.update,
            perzyna.consistent_tangent,
            law,
            perzyna.initial_state(),
            jnp.full(n, rate * dt),
            dt,
        )
        errors.append(abs(float(sigma[-1]) - closed_form(duration)))
    overstress = closed_form(duration) - SY
    assert errors[-1] < 1e-2 * overstress
    assert 1.7 < errors[0] / errors[1] < 2.3, errors


def test_viscoplastic_tangents():
    increments = strain_path(10)
    for name, law in viscoplastic_laws(1e-3).items():
        for dt in (1e-5, 1e2):
            stresses, states = drive(perzyna.update, law, perzyna.initial_state(), increments, dt)
            stress, increment = stresses[4], increments[5]
            state = jax.tree.map(lambda a: a[4], states)

            jac_err, fd_err = tangent_errors(law, stress, state, increment, dt)
            assert jac_err < 1e-11 and fd_err < 1e-6, (name, dt, jac_err, fd_err)


@jax.jit
def tangent_errors(law, stress, state, increment, dt):
    """Relative gaps of the viscoplastic tangent to jacrev and to central differences."""

    def new_stress(d):
        return perzyna.update(law, stress, state, d, dt)[0]

    tangent = perzyna.consistent_tangent(law, stress, state, increment, dt)
    scale = jnp.max(jnp.abs(tangent))
    jac_err = jnp.max(jnp.abs(tangent - jax.jacrev(new_stress)(increment)))
    h = 1e-9
    fd_err = 0.0
    for b in (jnp.zeros((3, 3)).at[0, 1].set(1.0), jnp.eye(3).at[2, 2].set(-2.0)):
        fd = (new_stress(increment + h * b) - new_stress(increment - h * b)) / (2 * h)
        fd_err = jnp.maximum(fd_err, jnp.max(jnp.abs(jnp.tensordot(tangent, b) - fd)))
    return jac_err / scale, fd_err / scale


def test_viscoplastic_vmap_equals_loop():
    law = perzyna.PerzynaQuadraticOverstress(E, NU, SY, 1e-3)
    taus = jnp.array([1e-5, 1e-3, 1e-1])
    increments = strain_path(20)
    batched = jax.vmap(
        lambda t: final_stress(
            perzyna.update,
            eqx.tree_at(lambda m: m.relaxation_time, law, t),
            perzyna.initial_state(),
            increments,
            1e-3,
        )
    )(taus)
    for i, t in enumerate(taus):
        single = final_stress(
            perzyna.update,
            eqx.tree_at(lambda m: m.relaxation_time, law, t),
            perzyna.initial_state(),
            increments,
            1e-3,
        )
        assert jnp.allclose(batched[i], single, rtol=1e-12, atol=1e-10)


@pytest.mark.parametrize("name", ["2.2.10", "2.2.11", "2.2.13", "2.2.9"])
def test_viscoplastic_gradients(name):
    law = viscoplastic_laws(2e-3)[name]
    increments = strain_path(20)

    def objective(law):
        stress = final_stress(perzyna.update, law, perzyna.initial_state(), increments, 1e-3)
        return stress[0, 0] + 0.7 * stress[0, 1] - 0.3 * stress[1, 2]

    assert_gradients(objective, law, ("young", "poisson", "yield_stress", "relaxation_time"))


@pytest.mark.parametrize(
    "field, kwargs, rule",
    [
        ("poisson", {"poisson": 0.6}, r"in \(-1, 0.5\)"),
        ("relaxation_time", {"relaxation_time": 0.0}, "positive"),
        ("young", {"young": -5.0}, "positive"),
        ("yield_stress", {"yield_stress": 0.0}, "positive"),
    ],
)
def test_bad_viscoplastic_inputs(field, kwargs, rule):
    arguments = {"young": E, "poisson": NU, "yield_stress": SY, "relaxation_time": 1e-3} | kwargs
    with pytest.raises(ValueError, match=rf"Craggs\.{field} must be {rule}"):
        perzyna.Craggs(**arguments)
    law = perzyna.PerzynaLinearOverstress(E, NU, SY, 1e-3)
    with pytest.raises(ValueError, match="dt must be positive"):
        perzyna.update(law, jnp.zeros((3, 3)), perzyna.initial_state(), jnp.zeros((3, 3)), 0.0)
