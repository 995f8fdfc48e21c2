"""Elastic-plastic combined shear waves in a half-space x3 >= 0 (report 2.1, (2.1.10)).

Shear tractions t1(t), t2(t) on x3 = 0, uniform in x1, x2, drive the motion v1(x3, t),
v2(x3, t). With x = x3, tau_a = sigma_a3 and the tensor shear strains eps_a3 (a = 1, 2):

    rho v_a,t = tau_a,x,        eps_a3,t = v_a,x / 2,

and the Prandtl-Reuss law (2.1.9) restricted to these components is (2.1.10). With
W = (v1, sigma13, v2, sigma23) the system is C W_t + D W_x = 0 with the printed matrices: C is
right; D is diag(G, 1/rho, G, 1/rho) while elastic and, at yield under plastic loading,
has the block G (I - n n^T) in the (v1, v2) rows, n = (sigma13, sigma23)/k. Both check against
(2.1.6) with lambda = s_ij e_ij'/(2 k^2) (perfect plasticity; J2 = sigma13^2 + sigma23^2 here).

With linear hardening of a `J2Plasticity` law the block becomes G (I - G/(G + h) n n^T),
n = (tau - alpha)/|tau - alpha|, h = (H_i + H_k)/3 the slope of the shear stress against the
engineering plastic shear strain (the printed D is h = 0). det(lambda C - D) = 0 then gives
lambda = +-c = +-(G/rho)^(1/2) (the fast wave: the stress turns on the yield circle, a neutral
change that travels at the elastic speed) and lambda = +-c_s = +-(G_t/rho)^(1/2),
G_t = G h/(G + h) (the slow wave: the radius of the circle grows); for perfect plasticity the
slow pair is the double zero root the report mentions.

The solver is a finite-volume scheme on the elastic characteristic variables
z_a = tau_a - rho c v_a (carried at +c) and w_a = tau_a + rho c v_a (carried at -c): each is
advected one step by the flux-limited upwind scheme (MC limiter, second order where smooth),
which conserves momentum and strain and gives the elastic trial state; then each cell's stress
is returned to the yield surface by the J2 radial return (`j2.update`) at constant velocity.
The plastic waves emerge from the returns; the scheme is exact for elastic waves at c dt = dx.
"""

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import _checks
from .._custom_types import Scalar
from . import j2


def _unit(vector):
    squared = jnp.sum(vector**2)
    positive = squared > 0.0
    size = jnp.where(positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 1.0)
    return vector / size


def _plastic_shear_modulus(law: j2.J2Plasticity):
    """h, the slope of shear stress against engineering plastic shear strain."""
    return (law.isotropic_modulus + law.kinematic_modulus) / 3.0


def wave_matrices(
    law: j2.J2Plasticity, density, shear_stress, back_shear_stress=None, *, plastic: bool
) -> tuple[Float[Array, "4 4"], Float[Array, "4 4"]]:
    """C and D of C W_t + D W_x = 0, W = (v1, sigma13, v2, sigma23), at the stress
    (sigma13, sigma23); `plastic` selects plastic loading at yield (the printed D for a
    perfectly plastic law), otherwise the elastic D. `back_shear_stress` (alpha13, alpha23)
    is zero unless the law hardens kinematically."""
    g = law.shear_modulus
    shear_stress = jnp.asarray(shear_stress)
    dtype = shear_stress.dtype
    if back_shear_stress is None:
        back_shear_stress = jnp.zeros(2, dtype)
    stiffness = g * jnp.eye(2, dtype=dtype)
    if plastic:
        h = _plastic_shear_modulus(law)
        n = _unit(shear_stress - back_shear_stress)
        stiffness = stiffness - g * g / (g + h) * jnp.outer(n, n)
    flip = jnp.array([[0.0, -1.0], [-1.0, 0.0]], dtype)
    c = jnp.kron(jnp.eye(2, dtype=dtype), flip)
    d = jnp.zeros((4, 4), dtype)
    d = d.at[0::2, 0::2].set(stiffness)
    d = d.at[1::2, 1::2].set(jnp.eye(2, dtype=dtype) / density)
    return c, d


def characteristic_speeds(law: j2.J2Plasticity, density, *, plastic: bool) -> Float[Array, "4"]:
    """The roots of det(lambda C - D) = 0, ascending: (-c, -c, c, c) elastic,
    (-c, -c_s, c_s, c) at yield under plastic loading (c_s = 0 for perfect plasticity)."""
    g = law.shear_modulus
    fast = jnp.sqrt(g / density)
    if plastic:
        h = _plastic_shear_modulus(law)
        slow = jnp.sqrt(g * h / (g + h) / density)
    else:
        slow = fast
    return jnp.stack([-fast, -slow, slow, fast])


class ShearWaveSolution(eqx.Module):
    """Cell-centred fields at `time`: `x` (n,), `velocity` and `shear_stress` (n, 2), the
    components (v1, v2) and (sigma13, sigma23), and the J2 `state` of every cell."""

    x: Float[Array, " n"]
    time: Scalar
    velocity: Float[Array, "n 2"]
    shear_stress: Float[Array, "n 2"]
    state: j2.J2State


def _limited_slope(left, right):
    """Monotonised-central slope: minmod(2 left, 2 right, (left + right)/2)."""
    size = jnp.minimum(
        jnp.minimum(2.0 * jnp.abs(left), 2.0 * jnp.abs(right)), 0.5 * jnp.abs(left + right)
    )
    return jnp.where(left * right > 0.0, jnp.sign(left) * size, 0.0)


def _advect_right(u, courant):
    """One step of u_t + c u_x = 0 on u (n + 4 with two ghosts each side): the n interior
    cells, flux-limited upwind."""
    slopes = _limited_slope(u[1:-1] - u[:-2], u[2:] - u[1:-1])  # cells 1 .. n + 2
    faces = u[1:-2] + 0.5 * (1.0 - courant) * slopes[:-1]  # faces 1|2 .. n+1|n+2
    return u[2:-2] - courant * (faces[1:] - faces[:-1])


def _shear_tensor(pair):
    zero = jnp.zeros((), pair.dtype)
    a, b = pair[0], pair[1]
    return jnp.array([[zero, zero, a], [zero, zero, b], [a, b, zero]])


def solve(
    law: j2.J2Plasticity,
    density,
    boundary: Callable,
    velocity_controlled: tuple[bool, bool] = (False, False),
    *,
    depth,
    n_cells: int,
    duration,
    n_steps: int,
    initial_shear_stress=(0.0, 0.0),
) -> ShearWaveSolution:
    """The half-space at rest with uniform (sigma13, sigma23) = `initial_shear_stress`
    (inside or on the yield circle), loaded on x3 = 0 from t = 0 on.

    `boundary(t)` returns two numbers, one per component a = 1, 2: the shear traction t_a(t)
    (sigma_a3(0, t) = -t_a, the outward normal being -e3) or, where `velocity_controlled[a]`,
    the velocity v_a(0, t). The domain is [0, depth] in `n_cells` cells; its far end lets
    waves out. `n_steps` steps reach `duration`; c dt/dx must not exceed 1.
    """
    density = _checks.positive("density", density)
    depth = _checks.positive("depth", depth)
    duration = _checks.positive("duration", duration)
    g = law.shear_modulus
    speed = jnp.sqrt(g / density)
    impedance = density * speed
    dx = depth / n_cells
    dt = duration / n_steps
    courant = _checks.check(
        "n_steps", speed * dt / dx, lambda nu: nu <= 1.0, "large enough that c dt/dx <= 1"
    )
    initial = jnp.asarray(initial_shear_stress, dtype=dx.dtype)
    k = law.yield_stress / np.sqrt(3.0)
    initial = _checks.check(
        "initial_shear_stress",
        initial,
        lambda s: jnp.sqrt(jnp.sum(s**2)) <= k * (1.0 + 1e-12),
        "inside the yield circle sigma13^2 + sigma23^2 <= (yield_stress^2)/3",
    )
    controlled = np.asarray(velocity_controlled, dtype=bool)
    update = jax.vmap(j2.update, in_axes=(None, 0, 0, 0))

    def step(carry, t):
        velocity, stress, state = carry
        w = stress + impedance * velocity
        z = stress - impedance * velocity
        # ghosts at x = -dx/2, -3dx/2 carry what the boundary emits dx/2c, 3dx/2c later
        lag = jnp.array([1.5, 0.5], dx.dtype) * dx / speed
        prescribed = jax.vmap(boundary)(t + lag).astype(dx.dtype)
        z_ghost = jnp.where(
            controlled, w[0] - 2.0 * impedance * prescribed, -2.0 * prescribed - w[0]
        )
        z_ext = jnp.concatenate([z_ghost, z, z[-1:], z[-1:]])
        w_ext = jnp.concatenate([w[:1], w[:1], w, w[-1:], w[-1:]])
        z_new = _advect_right(z_ext, courant)
        w_new = _advect_right(w_ext[::-1], courant)[::-1]
        velocity = (w_new - z_new) / (2.0 * impedance)
        trial = 0.5 * (w_new + z_new)
        tensors = jax.vmap(_shear_tensor)
        new_stress, state = update(
            law, tensors(stress), state, tensors((trial - stress) / (2.0 * g))
        )
        return (velocity, new_stress[:, [0, 1], 2], state), None

    state = jax.vmap(lambda _: j2.initial_state(dx.dtype))(jnp.arange(n_cells))
    start = (
        jnp.zeros((n_cells, 2), dx.dtype),
        jnp.broadcast_to(initial, (n_cells, 2)),
        state,
    )
    times = dt * jnp.arange(n_steps, dtype=dx.dtype)
    (velocity, stress, state), _ = jax.lax.scan(step, start, times)
    x = (jnp.arange(n_cells, dtype=dx.dtype) + 0.5) * dx
    return ShearWaveSolution(x, dt * n_steps, velocity, stress, state)
