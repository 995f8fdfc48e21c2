"""The incremental elastic-viscoplastic beam element of report 4.2 and the examples of 4.3."""

import math
import os
import subprocess
import sys

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.linalg

from barrierjax.beam.examples import example_model, final_state, report_example
from barrierjax.beam.integrate import integrate, stable_step, step_sizes
from barrierjax.beam.layered import layered_section, rectangular_section, section_update
from barrierjax.beam.model import (
    beam_model,
    cantilever,
    init_sections,
    internal_forces,
    linear_matrices,
    tangent_stiffness,
)
from barrierjax.materials.overstress import CowperSymonds
from barrierjax.materials.plasticity import RateIndependentPlasticity

E, RHO = 30e6, 0.000736


def _free(model, K, M):
    free = model.free()
    K, M = np.asarray(K), np.asarray(M)
    return K[np.ix_(free, free)], M[np.ix_(free, free)]


def _elastic_cantilever(n_elements=4, L=10.0, B=0.5, H=0.1, impulse=1e-5, duration=1e-3):
    law = RateIndependentPlasticity(E, 1e12)
    section = rectangular_section(B, H, law)
    return cantilever(L, n_elements, section, RHO, tip_impulse=impulse, duration=duration)


# --- section ------------------------------------------------------------------------------


def test_section_elastic_tangent_and_plastic_moment():
    B, H = 0.644, 0.177
    law = RateIndependentPlasticity(E, 29000.0)
    section = rectangular_section(B, H, law, points=5, rule="gauss")
    stress, state = section.init()
    out = section_update(section, stress, state, 0.0, 1e-6, 0.0)
    expected = np.diag([E * B * H, E * B * H**3 / 12])
    np.testing.assert_allclose(np.asarray(out.tangent), expected, rtol=1e-12, atol=1e-6)
    # Fully plastic: M -> sigma0 B H^2 / 4 (midpoint layers converge as 1/n^2).
    fine = rectangular_section(B, H, law, points=200, rule="midpoint")
    stress, state = fine.init()
    out = section_update(fine, stress, state, 0.0, 1.0, 0.0)
    np.testing.assert_allclose(float(out.M), 29000.0 * B * H**2 / 4, rtol=1e-4)
    assert abs(float(out.N)) < 1e-6
    # A two-layer T: elastic ES about the centroid vanishes.
    tee = layered_section([0.2, 0.05], [0.1, 1.0], law)
    stress, state = tee.init()
    out = section_update(tee, stress, state, 0.0, 1e-6, 0.0)
    assert abs(float(out.tangent[0, 1])) < 1e-6 * float(out.tangent[0, 0])


def test_section_report_scheme_is_alpha_E():
    law = CowperSymonds(E, 29000.0, 40.0, 5.0)
    section = rectangular_section(1.0, 0.2, law)
    stress = jnp.full(section.z.shape, 35000.0)
    _, state = section.init()
    out = section_update(section, stress, state, 0.0, 0.0, 1e-4, scheme="report")
    g_prime = E * 40.0 * 5.0 * (35000.0 / 29000.0 - 1) ** 4 / 29000.0
    alpha = 1 / (1 + 1e-4 / 2 * g_prime)
    np.testing.assert_allclose(float(out.tangent[0, 0]), alpha * E * 0.2, rtol=1e-12)


@jax.jit
def _run_linear(model, dts):
    """Average acceleration with a constant mass: shared (one compilation) by the linear tests."""
    return integrate(model, dts, scheme="newmark", iterations=2, line_search=1, update_mass=False)


# --- element and assembly -------------------------------------------------------------------


def test_cantilever_frequencies_match_euler_bernoulli():
    L, B, H = 100.0, 1.0, 0.1  # slender: rotary inertia shifts omega_3 by ~1e-5
    model = _elastic_cantilever(n_elements=20, L=L, B=B, H=H)
    K, M = _free(model, *jax.jit(linear_matrices)(model))
    omega = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)[:3])
    EI, mass = E * B * H**3 / 12, RHO * B * H
    beta_L = np.array([1.8751040687, 4.6940911330, 7.8547574382])
    exact = beta_L**2 * np.sqrt(EI / (mass * L**4))
    np.testing.assert_allclose(omega, exact, rtol=1e-3)
    assert np.allclose(K, K.T, rtol=0, atol=1e-9 * np.abs(K).max())


def _newmark_modes(omega, p_steps, dts, beta, gamma):
    """Each mode q'' + omega^2 q = p stepped by the same Newmark scheme (a_n from equilibrium
    with the step's load, as in `integrate`): the discrete modal superposition."""
    q = np.zeros_like(omega)
    v = np.zeros_like(omega)
    out = [q]
    for p, dt in zip(p_steps, dts):
        a = p - omega**2 * q
        base = q + dt * v + dt**2 * (0.5 - beta) * a
        q1 = (p + base / (beta * dt**2)) / (omega**2 + 1 / (beta * dt**2))
        a1 = (q1 - base) / (beta * dt**2)
        v = v + dt * ((1 - gamma) * a + gamma * a1)
        q = q1
        out.append(q)
    return np.asarray(out)


def test_pulse_response_matches_modal_superposition():
    duration = 1e-3
    model = _elastic_cantilever(impulse=1e-5, duration=duration)
    dts = step_sizes(0.01, 1e-4, pulse=duration, pulse_steps=5)
    history = _run_linear(model, jnp.asarray(dts))
    K, M = _free(model, *linear_matrices(model))
    w2, phi = scipy.linalg.eigh(K, M)  # mass-normalised modes
    omega = np.sqrt(w2)
    free = list(np.flatnonzero(model.free()))
    tip_dof = free.index(model.load_dofs[0])
    force = float(model.load_force[0])
    t = np.asarray(history.times)
    # Step-averaged load, as `integrate` applies it: the pulse covers [0, duration].
    overlap = np.clip(np.minimum(t[1:], duration) - t[:-1], 0, None) / np.diff(t)
    p_steps = np.outer(overlap * force, phi[tip_dof])
    q = _newmark_modes(omega, p_steps, np.diff(t), 0.25, 0.5)
    discrete = q @ phi[tip_dof]
    computed = np.asarray(history.displacement[:, model.load_dofs[0]])
    peak = np.max(np.abs(discrete))
    assert np.max(np.abs(computed - discrete)) < 1e-6 * peak
    # And the exact modal solution of the continuous-time problem, to the scheme's accuracy.
    tt = t[:, None]
    during = 1 - np.cos(omega * np.minimum(tt, duration))
    after = np.cos(omega * (tt - duration)) - np.cos(omega * tt)
    exact = (np.where(tt <= duration, during, after) * phi[tip_dof] / w2 * force) @ phi[tip_dof]
    assert np.max(np.abs(computed - exact)) < 5e-2 * peak


def test_energy_balance_average_acceleration():
    model = _elastic_cantilever(impulse=2e-6)  # w / H ~ 1e-3: linear
    dts = step_sizes(0.01, 1e-4, pulse=1e-3, pulse_steps=5)
    history = _run_linear(model, jnp.asarray(dts))
    K, M = linear_matrices(model)
    u, v = np.asarray(history.displacement), np.asarray(history.velocity)
    energy = 0.5 * np.einsum("ti,ij,tj->t", v, M, v) + 0.5 * np.einsum("ti,ij,tj->t", u, K, u)
    work = np.asarray(history.external_work)
    assert work[-1] > 0
    # Exact for a linear structure; what is left is the membrane coupling, of relative order
    # 12 (w / H)^2 ~ 1e-5.
    assert np.max(np.abs(energy - work)) < 1e-4 * work[-1]


@pytest.mark.parametrize("factor, stable", [(0.9, True), (1.1, False)])
def test_linear_acceleration_stability_limit(factor, stable):
    law = CowperSymonds(E, 1e12, 40.0, 5.0)  # elastic; the report's fibre scheme
    model = cantilever(
        2.0, 2, rectangular_section(0.5, 0.1, law), RHO, tip_impulse=1e-6, duration=1e-4
    )
    K, M = _free(model, *linear_matrices(model))
    omega_max = np.sqrt(scipy.linalg.eigh(K, M, eigvals_only=True)[-1])
    dt = factor * stable_step(omega_max)  # 2 sqrt(3) / omega_max
    assert np.isclose(stable_step(omega_max) * omega_max, 2 * np.sqrt(3))
    history = integrate(model, jnp.full(150, dt), scheme="report", iterations=2, line_search=1)
    u = np.asarray(history.displacement)
    peak_early = np.max(np.abs(u[:30]))
    if stable:
        assert np.all(np.isfinite(u)) and np.max(np.abs(u)) < 10 * peak_early
    else:
        assert not np.all(np.isfinite(u)) or np.max(np.abs(u[-20:])) > 1e3 * peak_early


# --- examples ------------------------------------------------------------------------------


@pytest.mark.parametrize("shallow", [True, False])
def test_tangent_stiffness_is_the_derivative_of_the_internal_forces(shallow):
    """The assembled [K1] + [K2], built from the sections' tangents and the strains' second
    derivatives, against forward-mode differentiation of the internal forces, at a
    displacement that rotates the chords and yields the outer fibres (Cowper-Symonds, a
    step of 1e-4 s from the unstressed state)."""
    model = example_model(1, n_elements=3)
    model = beam_model(
        model.coords,
        model.connectivity,
        model.section,
        model.rho,
        fixed=(0, 1, 2),
        shallow=shallow,
    )
    u_old = jnp.zeros(model.n_dofs)
    u = u_old.at[3::3].set(jnp.asarray([-0.01, -0.05, -0.12]))
    u = u.at[4::3].set(jnp.asarray([0.3, 1.1, 2.3])).at[5::3].set(jnp.asarray([0.1, 0.18, 0.21]))
    stress, state = init_sections(model)
    dt = jnp.asarray(1e-4)
    K, f, out = jax.jit(lambda u: tangent_stiffness(model, u, u_old, stress, state, dt))(u)
    forces = lambda u: internal_forces(model, u, u_old, stress, state, dt)[0]
    reference = jax.jit(jax.jacfwd(forces))(u)
    assert np.any(np.asarray(out[1].plastic_strain) != 0)  # some fibres flow
    np.testing.assert_allclose(np.asarray(f), np.asarray(jax.jit(forces)(u)), rtol=1e-12, atol=1e-9)
    scale = np.max(np.abs(np.asarray(reference)))
    np.testing.assert_allclose(np.asarray(K), np.asarray(reference), rtol=1e-9, atol=1e-12 * scale)


@pytest.mark.parametrize("rate_dependent", [False, True])
def test_held_tangents_give_newtons_answer(rate_dependent):
    # Example 1 into its plastic hinge: Newton's tangent held from step to step (chord
    # steps, chord=0.1) against a tangent at every iteration (chord=0, the default).
    model = example_model(1, rate_dependent=rate_dependent, n_elements=4, points=5)
    dts = jnp.asarray(step_sizes(0.012, 2e-4, pulse=1e-3, pulse_steps=4))
    runs = {
        chord: jax.jit(lambda d, chord=chord: integrate(model, d, iterations=12, chord=chord))(dts)
        for chord in (0.1, 0.0)
    }
    held, newton = runs[0.1], runs[0.0]
    assert np.any(np.asarray(newton.plastic_strain) != 0)
    assert float(held.residual.max()) < 1e-8 and float(newton.residual.max()) < 1e-8
    u_held, u_newton = np.asarray(held.displacement), np.asarray(newton.displacement)
    np.testing.assert_allclose(u_held, u_newton, rtol=0, atol=1e-8 * np.abs(u_newton).max())


def test_held_factors_solve_on_the_free_dofs_definite_or_not():
    from barrierjax.beam.integrate import _factor_free, _solve_factored

    free = (True, False, True, True)
    rng = np.random.default_rng(3)
    root = rng.normal(size=(4, 4))
    b = rng.normal(size=4)
    kept = np.ix_([0, 2, 3], [0, 2, 3])
    for A in (root @ root.T + 4 * np.eye(4), root + root.T):  # definite, then indefinite
        x = np.asarray(_solve_factored(_factor_free(free, jnp.asarray(A)), jnp.asarray(b)))
        assert x[1] == 0.0
        np.testing.assert_allclose(x[[0, 2, 3]], np.linalg.solve(A[kept], b[[0, 2, 3]]), rtol=1e-10)
    assert np.linalg.eigvalsh((root + root.T)[kept]).min() < 0


def test_rate_independent_example_1_is_sensible():
    result = report_example(1, rate_dependent=False, t_end=0.004, n_elements=4, dt=5e-4)
    tip, tip_rotation, root_rotation = final_state(result)
    assert np.all(np.isfinite(np.asarray(result.tip_displacement)))
    speed = 0.975 / 0.00381  # upper bound: the impulse into the tip mass alone
    assert 0 < tip[1] < speed * 0.004
    assert tip[0] < 0  # the tip swings in, towards the root
    assert 0 < root_rotation < tip_rotation < 0.5
    M0 = 29000.0 * 0.644 * 0.177**2 / 4
    assert np.max(np.abs(np.asarray(result.root_moment))) < 1.01 * M0
    assert float(result.residual.max()) < 1e-6
    assert result.node_coordinates.shape == (result.times.shape[0], 5, 2)


def test_vmap_equals_loop():
    dts = jnp.asarray(step_sizes(2e-3, 5e-4, pulse=1e-3, pulse_steps=2))

    def tip(tip_mass):
        model = example_model(1, n_elements=2, tip_mass=tip_mass)
        history = integrate(model, dts, scheme="damped-newmark", iterations=5)
        return history.displacement[-1, -2]

    masses = jnp.asarray([0.003, 0.005])
    batched = jax.jit(jax.vmap(tip))(masses)
    looped = jnp.stack([jax.jit(tip)(m) for m in masses])
    np.testing.assert_allclose(np.asarray(batched), np.asarray(looped), rtol=1e-10)


@pytest.mark.parametrize("chord", [0.0, 0.1])
def test_gradients_match_finite_differences(chord):
    dts = jnp.asarray(step_sizes(2e-3, 5e-4, pulse=1e-3, pulse_steps=2))

    def tip(p):
        model = example_model(1, n_elements=2, sigma0=p[0], tip_mass=p[1], D=p[2], q=p[3])
        history = integrate(model, dts, scheme="damped-newmark", iterations=8, chord=chord)
        return history.displacement[-1, -2]

    p = jnp.asarray([29000.0, 0.00381, 40.0, 5.0])
    f = jax.jit(tip)
    grad = np.asarray(jax.jit(jax.grad(tip))(p))
    for i in range(4):
        h = 1e-4 * float(p[i])
        fd = (float(f(p.at[i].add(h))) - float(f(p.at[i].add(-h)))) / (2 * h)
        np.testing.assert_allclose(grad[i], fd, rtol=2e-4, atol=1e-10 * abs(float(f(p))) / h)


# --- bad inputs ------------------------------------------------------------------------------


def test_bad_inputs_name_the_field():
    law = RateIndependentPlasticity(E, 29000.0)
    with pytest.raises(ValueError, match="width must be positive"):
        rectangular_section(-1.0, 0.1, law)
    with pytest.raises(ValueError, match="rule must be one of"):
        rectangular_section(1.0, 0.1, law, rule="simpson")
    section = rectangular_section(1.0, 0.1, law)
    with pytest.raises(ValueError, match="n_elements must be a positive integer"):
        cantilever(1.0, 0, section, RHO)
    with pytest.raises(ValueError, match="rho must be positive"):
        cantilever(1.0, 2, section, -RHO)
    with pytest.raises(ValueError, match="fixed must be dof indices"):
        beam_model([[0.0, 0.0], [1.0, 0.0]], [(0, 1)], section, RHO, fixed=(7,))
    with pytest.raises(ValueError, match="connectivity must be pairs"):
        beam_model([[0.0, 0.0], [1.0, 0.0]], [(0, 0)], section, RHO)
    with pytest.raises(ValueError, match="n must be one of"):
        report_example(4)
    with pytest.raises(ValueError, match=r"chord must be in \[0, 1\)"):
        integrate(cantilever(1.0, 2, section, RHO), jnp.asarray([1e-4]), chord=1.0)
    with pytest.raises(ValueError, match="scheme must be one of"):
        report_example(1, scheme="euler")
    with pytest.raises(ValueError, match="dt must be positive"):
        step_sizes(0.1, -1e-3)
    model = cantilever(1.0, 2, section, RHO, tip_impulse=1.0, duration=1e-3)
    with pytest.raises(ValueError, match="dts must be positive"):
        integrate(model, jnp.asarray([1e-4, -1e-4]))
    with pytest.raises(ValueError, match="duration must be positive"):
        cantilever(1.0, 2, section, RHO, tip_impulse=1.0, duration=0.0)


_SIXTEEN_VARIANTS = """
import math, jax, jax.numpy as jnp
import barrierjax
from barrierjax.beam.examples import EXAMPLES, example_model
from barrierjax.beam.integrate import integrate
jax.config.update("jax_enable_x64", True)
data = EXAMPLES[1]
dts = jnp.full(20, data["dt"] / math.ceil(data["dt"] / data["max_substep"]))
tip = lambda s0: integrate(example_model(1, sigma0=s0), dts, scheme="damped-newmark").displacement[-1, -2]
s0s = float(data["sigma0"]) * jnp.linspace(0.8, 1.2, 16)
print(float(jnp.sum(jax.jit(jax.grad(lambda s: jax.vmap(tip)(s).sum()))(s0s))))
"""


def test_gradient_of_sixteen_vmapped_runs_finishes():
    """With XLA's concurrency-optimized CPU scheduler this program never finished (every
    pool thread idle, the caller waiting; four variants did finish): barrierjax turns the
    scheduler off (`barrierjax/_xla_flags.py`). A fresh process, so that the flag is read
    as a user's script reads it, stopped after 240 s rather than hanging the suite. The
    gradient is taken under `jit`, as a sizing script takes it: one program with the
    batched factorisations of both passes (eager, the two passes compile apart, 30 s
    against 17)."""
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    proc = subprocess.run(
        [sys.executable, "-c", _SIXTEEN_VARIANTS], check=False, env=env, capture_output=True,
        text=True, timeout=240,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    total = float(proc.stdout.strip().splitlines()[-1])
    assert math.isfinite(total) and total != 0.0
