"""Rate-independent uniaxial plasticity with linear isotropic and kinematic hardening.

The classical limit of report 2.2 (tau -> 0 in (2.2.3)): the stress never leaves the yield
surface |sigma - beta| <= sigma0 + H_iso kappa, where beta is the back stress (kinematic
hardening, Bauschinger effect) and kappa the accumulated plastic strain (isotropic hardening).
The return mapping (elastic predictor, radial return) is exact for linear hardening, so the
update is independent of the step size and carries no time scale.

Every law of `barrierjax.materials` shares one per-step interface:
`law.init_state()` and `law.update(stress, state, d_strain, dt) -> (stress, state)`; the
consistent tangent is `barrierjax.materials.response.update_with_tangent`.
"""

from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp

from .._checks import non_negative, positive


class PlasticState(NamedTuple):
    plastic_strain: jnp.ndarray
    kappa: jnp.ndarray
    back_stress: jnp.ndarray


class RateIndependentPlasticity(eqx.Module):
    """Yield condition |sigma - beta| <= sigma0 + isotropic * kappa, back stress rate
    beta' = kinematic * eps_p'; in monotonic loading the plastic modulus is
    isotropic + kinematic and the elastic-plastic tangent E H / (E + H)."""

    E: jnp.ndarray
    sigma0: jnp.ndarray
    isotropic: jnp.ndarray
    kinematic: jnp.ndarray

    def __init__(self, E, sigma0, isotropic=0.0, kinematic=0.0):
        self.E = positive("E", E)
        self.sigma0 = positive("sigma0", sigma0)
        self.isotropic = non_negative("isotropic", isotropic)
        self.kinematic = non_negative("kinematic", kinematic)

    def init_state(self):
        zero = jnp.zeros_like(self.E)
        return PlasticState(zero, zero, zero)

    def yield_function(self, stress, state):
        """|sigma - beta| - (sigma0 + H_iso kappa): zero on the surface, negative inside."""
        return jnp.abs(stress - state.back_stress) - self.sigma0 - self.isotropic * state.kappa

    def update(self, stress, state, d_strain, dt):
        """Radial return; `dt` is unused (rate independence)."""
        del dt
        trial = stress + self.E * d_strain
        relative = trial - state.back_stress
        excess = jnp.abs(relative) - self.sigma0 - self.isotropic * state.kappa
        gamma = jnp.maximum(excess, 0) / (self.E + self.isotropic + self.kinematic)
        direction = jnp.sign(relative)
        new_state = PlasticState(
            state.plastic_strain + gamma * direction,
            state.kappa + gamma,
            state.back_stress + self.kinematic * gamma * direction,
        )
        return trial - self.E * gamma * direction, new_state
