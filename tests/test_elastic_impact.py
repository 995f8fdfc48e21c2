"""Mass impact on an infinite elastic beam and string (report 3.1) and the elastic limit with
delayed yield (report 3.5)."""

import itertools
import math

import jax
import jax.numpy as jnp
import mpmath as mp
import numpy as np
import pytest
import scipy.integrate
import scipy.optimize
import scipy.special

from barrierjax.hinge.elastic import (
    delay_integral,
    delayed_yield_limit_speed,
    elastic_impact,
    elastic_limit_speed,
    impact_rate,
    string_impact,
    timoshenko_initial_deceleration,
)
from barrierjax.materials.delayed_yield import grain_diameter

# A steel W-beam-like section in in, lbf, s: E psi, I in^4, A in^2, rho lb s^2/in^4.
BEAM = {"E": 30e6, "I": 2.3, "A": 2.0, "rho": 7.34e-4}
MASS = 10.0  # lb s^2/in (a 3,900 lb car)
SPEED = 100.0  # in/s


def beam_green_at_load(s, EI, rhoA):
    """W(0)/F of the infinite beam EI W'''' + rhoA s^2 W = F delta(x), as the Fourier
    integral (1/pi) int_0^inf dk / (EI k^4 + rhoA s^2), and the moment -EI W''(0)/F."""
    deflection = mp.quad(lambda k: 1 / (EI * k**4 + rhoA * s**2), [0, mp.inf]) / mp.pi
    moment = mp.quad(lambda k: EI * k**2 / (EI * k**4 + rhoA * s**2), [0, mp.inf]) / mp.pi
    return deflection, moment


def test_green_function_of_the_derivation():
    """The closed form behind (3.1.3): W(0) = F / (8 EI kappa^3), M(0) = F / (4 kappa),
    kappa = (rhoA s^2 / 4EI)^(1/4), checked against the Fourier integral at complex s."""
    mp.mp.dps = 20
    EI, rhoA = 3.0, 0.7
    for s in (mp.mpf(2), mp.mpc(1, 3), mp.mpc(0.3, -1)):
        kappa = (rhoA / (4 * EI)) ** 0.25 * mp.sqrt(s)
        deflection, moment = beam_green_at_load(s, EI, rhoA)
        assert abs(deflection * 8 * EI * kappa**3 - 1) < 1e-15
        assert abs(moment * 4 * kappa - 1) < 1e-15


def test_closed_forms_against_talbot_inversion():
    """Displacement, velocity, deceleration and moment under the mass against mpmath's
    Talbot inversion of the transforms built from the mass's equation
    M (s^2 W - V0) = -F and the Green function W(0) = F / (8 EI kappa^3)."""
    mp.mp.dps = 30
    EI, rhoA = BEAM["E"] * BEAM["I"], BEAM["rho"] * BEAM["A"]
    a = float(impact_rate(MASS, **BEAM))

    def transforms(s):
        # kappa = (rhoA s^2 / 4EI)^(1/4) on the branch continued from s > 0 (Re kappa > 0)
        kappa = (rhoA / (4 * EI)) ** 0.25 * mp.sqrt(s)
        stiffness = 8 * EI * kappa**3  # F / W(0)
        w = MASS * SPEED / (MASS * s**2 + stiffness)
        force = stiffness * w
        return {
            "displacement": w,
            "velocity": s * w,
            "acceleration": s**2 * w - SPEED,
            "moment": force / (4 * kappa),
        }

    times = np.array([0.01, 0.3, 1.0, 4.0, 30.0]) / a**2
    result = elastic_impact(MASS, SPEED, jnp.asarray(times), **BEAM)
    for name in ("displacement", "velocity", "acceleration", "moment"):
        reference = [
            float(mp.invertlaplace(lambda s, n=name: transforms(s)[n], t, method="talbot"))
            for t in times
        ]
        np.testing.assert_allclose(getattr(result, name), reference, rtol=1e-10, err_msg=name)
    np.testing.assert_allclose(result.contact_force, -MASS * result.acceleration, rtol=1e-15)


def test_printed_moment_and_rate():
    """M(0, t) = 2 EI K^2 V0 e^(a^2 t) erfc(a sqrt t), a = 8 EI K^3 / M, as printed in 3.1."""
    E, I, A, rho = BEAM.values()
    K = (rho * A / (4 * E * I)) ** 0.25
    a = 8 * E * I * K**3 / MASS
    assert float(impact_rate(MASS, **BEAM)) == pytest.approx(a, rel=1e-14)
    t = 0.7 / a**2
    result = elastic_impact(MASS, SPEED, t, **BEAM)
    x = a * math.sqrt(t)
    printed = 2 * E * I * K**2 * SPEED * math.exp(x**2) * math.erfc(x)
    assert float(result.moment) == pytest.approx(printed, rel=1e-13)


def test_large_arguments_keep_their_digits():
    """Far into the decay (a sqrt t up to 1e6) the stable forms match mpmath at 40 digits."""
    mp.mp.dps = 40
    a = float(impact_rate(MASS, **BEAM))
    xs = np.array([1e-9, 1e-4, 0.3, 0.49, 0.51, 2.9, 3.1, 30.0, 1e3, 1e6])
    result = elastic_impact(MASS, SPEED, jnp.asarray((xs / a) ** 2), **BEAM)
    for x, w, v, acc in zip(xs, result.displacement, result.velocity, result.acceleration):
        X = mp.mpf(x)
        t = (X / a) ** 2
        erfcx = mp.exp(X**2) * mp.erfc(X)
        assert float(v) == pytest.approx(float(SPEED * erfcx), rel=2e-15)
        exact_w = SPEED / a**2 * (2 * X / mp.sqrt(mp.pi) - 1 + erfcx)
        assert float(w) == pytest.approx(float(exact_w), rel=1e-14)
        exact_acc = SPEED * (a**2 * erfcx - a / mp.sqrt(mp.pi * t))
        assert float(acc) == pytest.approx(float(exact_acc), rel=1e-13)


def test_displacement_is_the_integral_of_velocity_and_asymptotes():
    a = float(impact_rate(MASS, **BEAM))
    t_end = 5.0 / a**2
    times = np.linspace(0.0, t_end, 2001)
    result = elastic_impact(MASS, SPEED, jnp.asarray(times), **BEAM)
    integral = scipy.integrate.quad(
        lambda t: SPEED * scipy.special.erfcx(a * math.sqrt(t)),
        0.0,
        t_end,
        epsabs=0.0,
        epsrel=1e-13,
    )[0]
    assert float(result.displacement[-1]) == pytest.approx(integral, rel=1e-12)
    # velocity = d displacement / dt, acceleration = d velocity / dt (central differences)
    h = times[1] - times[0]
    np.testing.assert_allclose(
        np.gradient(np.asarray(result.displacement), h)[200:-1],
        result.velocity[200:-1],
        rtol=2e-6,  # the central difference's truncation error
    )
    np.testing.assert_allclose(
        np.gradient(np.asarray(result.velocity), h)[200:-1], result.acceleration[200:-1], rtol=1e-4
    )
    late = elastic_impact(MASS, SPEED, 1e8 / a**2, **BEAM)
    t = 1e8 / a**2
    assert float(late.velocity) == pytest.approx(SPEED / (a * math.sqrt(math.pi * t)), rel=1e-8)
    assert float(late.acceleration) == pytest.approx(
        -SPEED / (2 * a * math.sqrt(math.pi) * t**1.5), rel=1e-7
    )


def test_initial_values_and_mass_limits():
    result = elastic_impact(MASS, SPEED, jnp.array([0.0, 1e-3]), **BEAM)
    assert float(result.displacement[0]) == 0.0
    assert float(result.velocity[0]) == SPEED
    assert float(result.acceleration[0]) == -jnp.inf
    initial_moment = SPEED * math.sqrt(BEAM["E"] * BEAM["I"] * BEAM["rho"] * BEAM["A"])
    assert float(result.moment[0]) == pytest.approx(initial_moment, rel=1e-15)
    heavy = elastic_impact(1e12, SPEED, 1e-3, **BEAM)  # M -> infinity: the speed is kept
    assert float(heavy.velocity) == pytest.approx(SPEED, rel=1e-6)
    assert float(heavy.displacement) == pytest.approx(SPEED * 1e-3, rel=1e-6)
    light = elastic_impact(1e-6, SPEED, 1e-3, **BEAM)  # small M: a fast decay
    a = float(impact_rate(1e-6, **BEAM))
    assert float(light.velocity) < 1e-5 * SPEED
    assert float(light.velocity) == pytest.approx(SPEED / (a * math.sqrt(math.pi * 1e-3)), rel=1e-6)


def test_string_closed_form_and_momentum():
    tension, rho = 2e4, 1e-3
    times = jnp.linspace(0.0, 0.05, 11)
    result = string_impact(MASS, SPEED, times, tension=tension, rho=rho)
    c = math.sqrt(tension / rho)
    b = 2 * tension / (MASS * c)
    np.testing.assert_allclose(result.velocity, SPEED * np.exp(-b * times), rtol=1e-14)
    np.testing.assert_allclose(
        result.displacement, SPEED * MASS * c / (2 * tension) * (1 - np.exp(-b * times)), rtol=1e-13
    )
    np.testing.assert_allclose(result.acceleration, -SPEED * b * np.exp(-b * times), rtol=1e-14)
    # the mass's momentum plus the impulse of both sides' forces (T/c) w_t is M V0
    momentum = MASS * result.velocity + 2 * tension / c * result.displacement
    np.testing.assert_allclose(momentum, MASS * SPEED, rtol=1e-14)


def test_timoshenko_initial_deceleration():
    G, A_s = 11.5e6, 0.8
    A, rho = BEAM["A"], BEAM["rho"]
    c2 = math.sqrt(G * A_s / (rho * A))
    value = timoshenko_initial_deceleration(MASS, SPEED, G=G, A_s=A_s, A=A, rho=rho)
    assert float(value) == pytest.approx(-2 * SPEED * G * A_s / (MASS * c2), rel=1e-15)
    printed_c2 = math.sqrt(G / rho)
    same = timoshenko_initial_deceleration(MASS, SPEED, G=G, A_s=A, A=A, rho=rho)
    assert float(same) == pytest.approx(-2 * SPEED * G * A / (MASS * printed_c2), rel=1e-15)


def test_elastic_limit_speed_gives_yield_moment():
    y, sigma_y = 1.5, 36e3
    v = elastic_limit_speed(**BEAM, y=y, yield_stress=sigma_y)
    moment = elastic_impact(MASS, v, 0.0, **BEAM).moment
    assert float(moment * y / BEAM["I"]) == pytest.approx(sigma_y, rel=1e-14)


def test_delay_integral_against_mpmath():
    mp.mp.dps = 30
    betas = jnp.array([2.5, 3.0, 9.0, 30.0])
    values = delay_integral(betas)
    for beta, value in zip(betas, values):
        b = float(beta)

        def integrand(w, b=b):
            u = mp.exp(w)
            return 2 * u**2 * (mp.exp(u**2) * mp.erfc(u)) ** b

        high = 40
        tail = 2 * mp.exp((2 - b) * high) / (mp.pi ** (b / 2) * (b - 2))
        exact = mp.quad(integrand, [-60, -5, 0, 2, 5, 10, 20, high]) + tail + mp.exp(-120)
        assert float(value) == pytest.approx(float(exact), rel=1e-12)


def report_delay(grains):
    G = 11.5e6
    return {"sigma0": 2 * G / 45, "delay_constant": 1.2e-6, "d": grain_diameter(grains)}


def test_delayed_yield_limit_makes_the_delay_integral_one():
    """At the bound, the delay integral (2.3.4) of the extreme fibre's stress (y/I) M(0, t)
    over all time is 1 (scipy quadrature), and 0.99 of the speed stays below 1.

    Units: the section in mm (the delay constants are in mm and s)."""
    E, rho = 206e3, 7.85e-9  # N/mm^2, t/mm^3
    I, A, y = 3.0e6, 2.0e3, 75.0
    mass, beta = 1.5, 9.0  # t
    p = report_delay(2030.0)
    p["sigma0"] = 2 * 79e3 / 45
    v = float(delayed_yield_limit_speed(mass, E=E, I=I, A=A, rho=rho, y=y, beta=beta, **p))
    a = float(impact_rate(mass, E=E, I=I, A=A, rho=rho))

    def delay_integral_at(speed):
        sigma_i = speed * math.sqrt(E * I * rho * A) * y / I
        rate = float(p["d"]) ** 3 / p["delay_constant"] * (sigma_i / p["sigma0"]) ** beta

        def integrand(t):
            return rate * scipy.special.erfcx(a * math.sqrt(t)) ** beta

        pieces = [0.0] + [10.0**k / a**2 for k in range(-4, 9)] + [np.inf]
        return sum(
            scipy.integrate.quad(integrand, lo, hi, epsabs=1e-15, epsrel=1e-12)[0]
            for lo, hi in itertools.pairwise(pieces)
        )

    assert delay_integral_at(v) == pytest.approx(1.0, rel=1e-9)
    speed_at_one = scipy.optimize.brentq(lambda s: delay_integral_at(s) - 1.0, 0.5 * v, 2 * v)
    assert speed_at_one == pytest.approx(v, rel=1e-9)


def test_report_3_5_coefficients():
    """The bound's coefficient (r/y) (sigma0/E) (A/(d^3 lambda))^(1/beta), with 1/a in
    s^(1/2), against the printed 1.75e-3 and 1.295e-3 (see the module docstring)."""
    E, beta = 30e6, 9.0
    lam = float(delay_integral(beta))
    assert lam == pytest.approx(0.0240564819918, rel=1e-11)
    coefficients = {}
    for grains in (2030.0, 346.0):
        p = report_delay(grains)
        d = float(p["d"])
        # a beam with r = y and M / (8 EI K^3) = 1 s^(1/2): the speed is c1 times the coefficient
        section = {"E": E, "I": 1.0, "A": 1.0, "rho": 7.3e-4}
        mass = float(impact_rate(1.0, **section))  # a = 1 / s^(1/2)
        v = delayed_yield_limit_speed(mass, **section, y=1.0, beta=beta, **p)
        coefficient = float(v) / math.sqrt(E / 7.3e-4)
        formula = p["sigma0"] / E * (p["delay_constant"] / (d**3 * lam)) ** (1 / beta)
        assert coefficient == pytest.approx(formula, rel=1e-13)
        coefficients[grains] = coefficient
    assert coefficients[2030.0] / 1.75e-3 == pytest.approx(11.5, rel=0.01)
    assert coefficients[346.0] / 1.295e-3 == pytest.approx(11.6, rel=0.01)
    # both coefficients scale as d^(-3/beta): the printed ratio agrees to 0.6 %
    scaling = (2030 / 346) ** (3 / (2 * beta))
    assert coefficients[2030.0] / coefficients[346.0] == pytest.approx(scaling, rel=1e-13)
    assert 1.75 / 1.295 == pytest.approx(scaling, rel=0.007)


def test_vmap_equals_loop():
    masses = jnp.array([0.1, 1.0, 10.0])
    speeds = jnp.array([50.0, 100.0, 200.0])
    times = jnp.array([1e-5, 1e-3, 1e-1])

    def run(m, v):
        r = elastic_impact(m, v, times, **BEAM)
        return jnp.stack([r.displacement, r.velocity, r.acceleration, r.moment])

    batched = jax.vmap(run)(masses, speeds)
    looped = jnp.stack([run(m, v) for m, v in zip(masses, speeds)])
    np.testing.assert_allclose(batched, looped, rtol=1e-14)
    limits = jax.vmap(
        lambda m: delayed_yield_limit_speed(m, **BEAM, y=1.5, beta=9.0, **report_delay(2030.0))
    )(masses)
    for m, value in zip(masses, limits):
        one = delayed_yield_limit_speed(m, **BEAM, y=1.5, beta=9.0, **report_delay(2030.0))
        assert float(value) == pytest.approx(float(one), rel=1e-14)


def central_difference(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


@pytest.mark.parametrize("field", ["displacement", "velocity", "acceleration", "moment"])
def test_gradients_against_finite_differences(field):
    """d/d(mass, speed, I, A) at times on both sides of the series and fraction switches."""
    a = float(impact_rate(MASS, **BEAM))
    times = jnp.asarray(np.array([0.1, 1.0, 50.0]) ** 2 / a**2)

    def f(mass, speed, I, A):
        section = BEAM | {"I": I, "A": A}
        return jnp.sum(getattr(elastic_impact(mass, speed, times, **section), field))

    x0 = (MASS, SPEED, BEAM["I"], BEAM["A"])
    grads = jax.grad(f, argnums=(0, 1, 2, 3))(*x0)
    for i, g in enumerate(grads):
        h = 1e-5 * x0[i]
        fd = central_difference(lambda x, i=i: f(*x0[:i], x, *x0[i + 1 :]), x0[i], h)
        np.testing.assert_allclose(g, fd, rtol=1e-7, err_msg=f"{field} argument {i}")


def test_limit_speed_gradients():
    p = report_delay(2030.0)

    def f(mass, I):
        return delayed_yield_limit_speed(mass, **(BEAM | {"I": I}), y=1.5, beta=9.0, **p)

    g_mass, g_I = jax.grad(f, argnums=(0, 1))(MASS, BEAM["I"])
    assert float(g_mass) == pytest.approx(float(-2 / 9 * f(MASS, BEAM["I"]) / MASS), rel=1e-13)
    fd = central_difference(lambda x: f(MASS, x), BEAM["I"], 1e-5)
    assert float(g_I) == pytest.approx(float(fd), rel=1e-8)
    g_beta = jax.grad(delay_integral)(9.0)
    fd = central_difference(delay_integral, 9.0, 1e-4)
    assert float(g_beta) == pytest.approx(float(fd), rel=1e-7)


def test_bad_inputs_name_the_field():
    with pytest.raises(ValueError, match="mass must be positive"):
        elastic_impact(0.0, SPEED, 1.0, **BEAM)
    with pytest.raises(ValueError, match="times must be non-negative"):
        elastic_impact(MASS, SPEED, -1.0, **BEAM)
    with pytest.raises(ValueError, match="I must be positive"):
        elastic_impact(MASS, SPEED, 1.0, **(BEAM | {"I": -2.0}))
    with pytest.raises(ValueError, match="tension must be positive"):
        string_impact(MASS, SPEED, 1.0, tension=0.0, rho=1.0)
    with pytest.raises(ValueError, match="A_s must be positive"):
        timoshenko_initial_deceleration(MASS, SPEED, G=1.0, A_s=jnp.nan, A=1.0, rho=1.0)
    with pytest.raises(ValueError, match="beta must be finite and > 2"):
        delay_integral(2.0)
    with pytest.raises(ValueError, match="yield_stress must be positive"):
        elastic_limit_speed(**BEAM, y=1.0, yield_stress=0.0)
