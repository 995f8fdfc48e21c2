"""The hereditary-integral law (2.2.15)-(2.2.17), uniaxial form.

Multiplying the linear Mises law (2.2.12) by s_ij/2 gives J2'/2 + (J2 - k^2)/tau = G w', so
J2 = k^2 + 2G int_0^t exp(-2(t - t')/tau) w'(t') dt'; (2.2.15) replaces the exponential by a
relaxation function psi with psi(0) = 1. Uniaxially, for an incompressible material (E = 3G,
J2 = sigma^2/3, k^2 = sigma0^2/3, w' = sigma eps'):

    sigma^2 = sigma0^2 + 2E int psi(t - t') sigma(t') eps'(t') dt',

and with psi a Prony series sum_i w_i exp(-t/theta_i) (sum w_i = 1) the integral is
sum_i w_i h_i, with memories h_i' = -h_i/theta_i + sigma eps'. Differentiating,
E eps' = sigma' + lambda sigma with lambda = E sum_i (w_i/theta_i) h_i / sigma^2; in 3-D this is
lambda = -G int psi' w' / J2, so the printed (2.2.17) has 2G where G belongs (with one term,
theta = tau/2, only G gives back the 1/tau of (2.2.12)). One term with theta = tau/2 is
`QuadraticOverstress(E, sigma0, tau)`.

Relaxation test: after an instantaneous strain to the stress sigma* the memories all hold
(sigma*^2 - sigma0^2)/(2E), so psi(t) = (sigma^2(t) - sigma0^2)/(sigma*^2 - sigma0^2). The
report's psi = (sigma^2 - 3k^2)/sigma*^2 (with w' = sigma*^2/E delta(t)) omits the work below
the static curve, which the integral's start at J2 = k^2 excludes; it is the limit
sigma* >> sigma0.

The report's integral starts at J2 = k^2; the law describes the plastic range only. Here the
material is elastic (sigma' = E eps', memories zero) while |sigma| < sigma0, and the integral
starts where the stress reaches sigma0; a state that would fall back below sigma0 unloads
elastically and forgets its memory.
"""

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._checks import check, positive


class HereditaryState(NamedTuple):
    memory: jnp.ndarray  # h_i, one per Prony term


class HereditaryLaw(eqx.Module):
    """sigma^2 = sigma0^2 + 2E sum_i w_i h_i beyond the static yield stress sigma0, psi(t) =
    sum_i weights[i] exp(-t / relaxation_times[i]); weights non-negative, summing to 1."""

    E: jnp.ndarray
    sigma0: jnp.ndarray
    weights: jnp.ndarray
    relaxation_times: jnp.ndarray

    def __init__(self, E, sigma0, weights, relaxation_times):
        if np.ndim(weights) != 1 or np.shape(weights) != np.shape(relaxation_times):
            raise ValueError(
                "weights and relaxation_times must be 1-d of equal length; got shapes "
                f"{np.shape(weights)} and {np.shape(relaxation_times)}"
            )
        self.E = positive("E", E)
        self.sigma0 = positive("sigma0", sigma0)
        self.weights = check(
            "weights",
            weights,
            lambda w: (w >= 0) & (abs(w.sum() - 1) <= 1e-6),
            "non-negative, summing to 1",
        )
        self.relaxation_times = positive("relaxation_times", relaxation_times)

    def relaxation_function(self, t):
        """psi(t) (2.2.16) for t >= 0."""
        t = jnp.asarray(t)[..., None]
        return jnp.sum(self.weights * jnp.exp(-t / self.relaxation_times), axis=-1)

    def init_state(self):
        return HereditaryState(jnp.zeros_like(self.weights))

    def update(self, stress, state, d_strain, dt):
        """Exact decay of the memories over the step, work rate sigma eps' by the trapezoidal
        rule (so an instantaneous step, dt = 0, is the elastic jump it should be); the end
        stress solves the resulting quadratic sigma^2 - b sigma - c = 0 in closed form."""
        theta = self.relaxation_times
        decay = jnp.exp(-dt / theta)
        positive_dt = dt > 0
        safe_dt = jnp.where(positive_dt, dt, jnp.ones_like(dt))
        # the mean of exp(-(t_end - t')/theta) over the step
        mean_decay = jnp.where(positive_dt, -theta * jnp.expm1(-safe_dt / theta) / safe_dt, 1)

        trial = stress + self.E * d_strain
        on_curve = jnp.abs(stress) >= self.sigma0
        start = jnp.where(on_curve, stress, jnp.sign(trial) * self.sigma0)
        plastic_strain_step = d_strain - (start - stress) / self.E
        b = self.E * jnp.sum(self.weights * mean_decay) * plastic_strain_step
        c = self.sigma0**2 + 2 * self.E * jnp.sum(self.weights * decay * state.memory)
        c = c + b * start
        discriminant = b**2 + 4 * c
        safe = jnp.where(discriminant > 0, discriminant, jnp.ones_like(discriminant))
        hereditary = (b + jnp.sign(start) * jnp.sqrt(safe)) / 2

        beyond = (
            (on_curve | (jnp.abs(trial) > self.sigma0))
            & (discriminant > 0)
            & (jnp.sign(start) * hereditary >= self.sigma0)
        )
        memory = decay * state.memory + mean_decay * (start + hereditary) / 2 * plastic_strain_step
        return (
            jnp.where(beyond, hereditary, trial),
            HereditaryState(jnp.where(beyond, memory, jnp.zeros_like(memory))),
        )
