"""Combined shear waves in a half-space (report 2.1, (2.1.10))."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

from barrierjax.materials import j2, shear_waves

RHO = 1.0
G = 1.0
C = 1.0
K = 1.0 / np.sqrt(3.0)  # yield_stress 1
H = 0.3  # isotropic_modulus; h = H/3 in shear
G_T = G * (H / 3) / (G + H / 3)
C_SLOW = np.sqrt(G_T / RHO)
N_CELLS, DURATION = 300, 0.8


def law(isotropic_modulus=H):
    return j2.J2Plasticity(2.0 * (1 + 0.3) * G, 0.3, 1.0, isotropic_modulus)


def run(boundary, controlled, initial=(0.0, 0.0), n_cells=N_CELLS, courant=0.9):
    n_steps = int(np.ceil(DURATION * n_cells / courant))
    return shear_waves.solve(
        law(),
        RHO,
        boundary,
        controlled,
        depth=1.0,
        n_cells=n_cells,
        duration=DURATION,
        n_steps=n_steps,
        initial_shear_stress=initial,
    )


def test_characteristic_speeds_are_roots_of_det():
    for isotropic in (0.0, H):
        for plastic in (False, True):
            m = law(isotropic)
            speeds = shear_waves.characteristic_speeds(m, RHO, plastic=plastic)
            c, d = shear_waves.wave_matrices(
                m, RHO, jnp.array([0.6 * K, -0.8 * K]), plastic=plastic
            )
            numeric = np.sort(np.linalg.eigvals(np.linalg.solve(c, d)).real)
            assert np.allclose(numeric, speeds, atol=1e-12)
            for lam in speeds:
                assert abs(np.linalg.det(lam * c - d)) < 1e-12
    elastic = shear_waves.characteristic_speeds(law(), RHO, plastic=False)
    assert np.allclose(elastic, [-C, -C, C, C])
    assert np.allclose(
        shear_waves.characteristic_speeds(law(0.0), RHO, plastic=True), [-C, 0, 0, C]
    )
    assert np.allclose(
        shear_waves.characteristic_speeds(law(), RHO, plastic=True), [-C, -C_SLOW, C_SLOW, C]
    )


def test_printed_d_for_perfect_plasticity():
    s13, s23 = 0.6 * K, -0.8 * K
    _, d = shear_waves.wave_matrices(law(0.0), RHO, jnp.array([s13, s23]), plastic=True)
    printed = np.array(
        [
            [G * (1 - s13**2 / K**2), 0, -G * s13 * s23 / K**2, 0],
            [0, 1 / RHO, 0, 0],
            [-G * s13 * s23 / K**2, 0, G * (1 - s23**2 / K**2), 0],
            [0, 0, 0, 1 / RHO],
        ]
    )
    assert np.allclose(d, printed, atol=1e-14)


def pulse(t):
    amplitude, centre, width = 0.2 * K, 0.3, 0.06
    return jnp.stack([amplitude * jnp.exp(-(((t - centre) / width) ** 2)), jnp.zeros_like(t)])


@pytest.mark.parametrize("courant", [1.0, 0.8])
def test_elastic_pulse_is_dalembert(courant):
    solution = run(pulse, (False, False), courant=courant)
    x = np.asarray(solution.x)
    exact_stress = -np.asarray(jax.vmap(pulse)(jnp.asarray(DURATION - x / C)))[:, 0]
    amplitude = 0.2 * K
    error = np.max(np.abs(np.asarray(solution.shear_stress[:, 0]) - exact_stress)) / amplitude
    velocity_error = (
        np.max(np.abs(np.asarray(solution.velocity[:, 0]) + exact_stress / (RHO * C))) / amplitude
    )
    assert error < (1e-10 if courant == 1.0 else 1e-2), error
    assert velocity_error < (1e-10 if courant == 1.0 else 1e-2)
    assert np.max(np.abs(np.asarray(solution.shear_stress[:, 1]))) == 0.0


def front(x, values, before, after):
    """Position where `values` cross halfway from `before` to `after`."""
    fraction = (np.asarray(values) - before) / (after - before)
    return x[np.argmin(np.abs(fraction - 0.5))]


def test_step_beyond_yield_in_one_component():
    velocity = 2.0 * K / (RHO * C)
    solution = run(lambda t: jnp.array([velocity, 0.0]), (True, True))
    x = np.asarray(solution.x)
    tau = np.asarray(solution.shear_stress[:, 0])
    behind = -(K + RHO * C_SLOW * (velocity - K / (RHO * C)))
    dx = 1.0 / N_CELLS
    assert abs(tau[x < 0.5 * C_SLOW * DURATION].mean() - behind) < 1e-6 * K
    plateau = (x > 1.5 * C_SLOW * DURATION) & (x < 0.8 * C * DURATION)
    assert np.allclose(tau[plateau], -K, rtol=1e-4)
    assert abs(front(x, tau, -K, behind) - C_SLOW * DURATION) < 3 * dx
    assert abs(front(x, tau, 0.0, -K) - C * DURATION) < 3 * dx
    f = jax.vmap(j2.yield_function, in_axes=(None, 0, 0))(
        law(), jax.vmap(shear_waves._shear_tensor)(solution.shear_stress), solution.state
    )
    yielded = np.asarray(solution.state.equivalent_plastic_strain) > 0
    assert yielded.sum() > 50
    assert np.max(np.abs(np.asarray(f)[yielded])) < 1e-10 * K


def test_combined_fast_and_slow_waves():
    """sigma13 held at yield, then a step in v2: a fast wave turns the stress on the yield
    circle at speed c, a slow wave at c_s expands it (Riemann solution in closed form)."""
    v2 = 0.5 * K / (RHO * C)

    def boundary_v2(theta):
        r = K / np.cos(theta)
        return -K * np.sin(theta) / (RHO * C) - (r - K) * np.sin(theta) / (RHO * C_SLOW) - v2

    theta = brentq(boundary_v2, -1.5, 0.0)
    middle = K * np.array([np.cos(theta), np.sin(theta)])
    boundary = middle / np.cos(theta)
    solution = run(lambda t: jnp.array([-K, v2]), (False, True), initial=(K, 0.0))
    x = np.asarray(solution.x)
    tau = np.asarray(solution.shear_stress)
    near = x < 0.5 * C_SLOW * DURATION
    between = (x > 1.5 * C_SLOW * DURATION) & (x < 0.8 * C * DURATION)
    assert np.allclose(tau[near].mean(axis=0), boundary, rtol=1e-4)
    assert np.allclose(tau[between], middle, rtol=5e-5)
    v_middle = -(middle - np.array([K, 0.0])) / (RHO * C)
    assert np.allclose(np.asarray(solution.velocity)[between], v_middle, rtol=1e-3)
    dx = 1.0 / N_CELLS
    assert abs(front(x, tau[:, 1], 0.0, middle[1]) - C * DURATION) < 3 * dx
    radius = np.hypot(tau[:, 0], tau[:, 1])
    r_boundary = np.hypot(*boundary)
    assert abs(front(x, radius, K, r_boundary) - C_SLOW * DURATION) < 3 * dx


def test_bad_inputs():
    with pytest.raises(ValueError, match="n_steps must be large enough"):
        shear_waves.solve(law(), RHO, pulse, depth=1.0, n_cells=100, duration=1.0, n_steps=50)
    with pytest.raises(ValueError, match="density must be positive"):
        shear_waves.solve(law(), 0.0, pulse, depth=1.0, n_cells=10, duration=1.0, n_steps=50)
    with pytest.raises(ValueError, match="initial_shear_stress must be inside the yield circle"):
        shear_waves.solve(
            law(),
            RHO,
            pulse,
            depth=1.0,
            n_cells=10,
            duration=1.0,
            n_steps=50,
            initial_shear_stress=(K, 0.1),
        )


def _boundary_stress(velocity, hardening):
    """The shear stress at the loaded face after a velocity step beyond yield (60 cells)."""
    solution = shear_waves.solve(
        j2.J2Plasticity(2.0 * (1 + 0.3) * G, 0.3, 1.0, hardening),
        RHO,
        lambda t: jnp.stack([velocity, 0.0 * velocity]),
        (True, True),
        depth=1.0,
        n_cells=60,
        duration=0.5,
        n_steps=40,
    )
    return solution.shear_stress[0, 0]


def test_vmap_equals_loop_and_gradients_match_finite_differences():
    """Beyond yield the face's stress is smooth in the step's velocity and the hardening
    modulus: vmap over velocities equals a loop, and jax.grad matches central differences."""
    velocities = jnp.array([2.0, 3.0]) * K / (RHO * C)
    batched = jax.jit(jax.vmap(_boundary_stress, in_axes=(0, None)))(velocities, H)
    looped = [float(_boundary_stress(v, H)) for v in velocities]
    np.testing.assert_allclose(np.asarray(batched), looped, rtol=1e-12)
    grad = jax.jit(jax.grad(_boundary_stress, argnums=(0, 1)))(velocities[0], H)
    for i, step in enumerate((1e-5 * velocities[0], 1e-5)):
        args = [velocities[0], H]
        up, down = list(args), list(args)
        up[i], down[i] = args[i] + step, args[i] - step
        fd = (_boundary_stress(*up) - _boundary_stress(*down)) / (2 * step)
        np.testing.assert_allclose(float(grad[i]), float(fd), rtol=1e-5)
