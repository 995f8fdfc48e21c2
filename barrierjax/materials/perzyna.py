"""Multiaxial elastic-viscoplastic laws of Perzyna type (report 2.2(ii), (2.2.9)-(2.2.13)).

The static yield surface is the Mises condition J2 = 1/2 s_ij s_ij = k^2, k = sigma_y/sqrt(3),
without hardening; the stress may lie outside it, and the plastic strain rate grows with the
overstress. Every printed form is

    2G eps_p' = (1/tau) Phi(x) s,     x = (J2 - k^2)/k^2,     Phi(x) = 0 for x <= 0,   (*)

with the volume change elastic (3K eps_kk' = sigma_kk'):

    (2.2.10) PerzynaLinearOverstress    (sqrt(J2) - k)/sqrt(J2)      Phi = 1 - (1 + x)^(-1/2)
    (2.2.11) PerzynaQuadraticOverstress (J2 - k^2)/k^2               Phi = x
    (2.2.12) RelativeOverstress         (J2 - k^2)/J2                Phi = x/(1 + x)
    (2.2.13) Craggs                     (J2 - k^2)^(1/2)/J2^(1/2)     Phi = (x/(1 + x))^(1/2)
    (2.2.9)  Perzyna                    any non-decreasing Phi with Phi(0) = 0

Departures from the printed text:
- (2.2.9) is (*) with f = J2 (n = 2, df/dsigma_ij = s_ij). As printed it lacks the 1/(2G)
  that makes Phi dimensionless and that (2.2.10)-(2.2.13) carry, and its elastic term reads
  (1 - nu)/E where it is (1 + nu)/E.
- The "dynamic yield condition" derived after (2.2.12) follows from (2.2.10), not (2.2.9), and
  Craggs' condition is J2 = k^2 + (2G tau)^2 (1/2 e_p' e_p'), squared: the printed
  2G tau (1/2 e_p' e_p') is not dimensionally consistent and does not give (2.2.13).
- Under uniaxial stress (2.2.10) reduces to (2.2.3) with f = sigma_0 and the time constant
  tau' = 3 G tau / E = 3 tau / (2 (1 + nu)), which is tau only for nu = 1/2.
- For small overstress (2.2.11) and (2.2.12) agree with (2.2.10) only with tau halved
  (Phi ~ x against x/2); (2.2.13) has Phi ~ x^(1/2) and is not linear there at all.

Integration: backward Euler over a time step dt. The implicit equation for s is
s = s_trial - (dt/tau) Phi(x) s, so s = s_trial/(1 + r Phi), r = dt/tau: the return is radial,
and the effective stress q = J2^(1/2) solves the scalar equation

    q (1 + r Phi((q^2 - k^2)/k^2)) = q_trial,     k <= q <= q_trial,

whose left side increases with q, so the root is unique for every r; as r -> infinity
(dt -> infinity or tau -> 0) q -> k, the rate-independent radial return. (2.2.10), (2.2.12) and
(2.2.13) have closed-form roots; the others are found by safeguarded Newton under
`stop_gradient`, followed by one Newton step with gradients, which gives the derivatives of
the implicit function theorem at the converged root.
"""

import abc
from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .. import _checks
from .._custom_types import Batchable, Scalar
from .elastic import IsotropicElastic
from .j2 import (
    Tangent,
    Tensor,
    checked_poisson,
    deviator,
    identity_tensors,
    safe_norm,
    symmetric_part,
)


class AbstractViscoplastic(IsotropicElastic):
    """Elastic constants, static yield stress and time constant shared by all the forms."""

    yield_stress: eqx.AbstractVar[Batchable]
    relaxation_time: eqx.AbstractVar[Batchable]

    @abc.abstractmethod
    def overstress_function(self, x):
        """Phi(x) for x >= 0."""

    def effective_stress(self, trial, k, ratio):
        """Root q of q (1 + r Phi) = q_trial, for q_trial > k (safeguarded Newton)."""
        return _implicit_root(self.overstress_function, trial, k, ratio)


def _checked_fields(cls_name, young, poisson, yield_stress, relaxation_time):
    return (
        _checks.positive(f"{cls_name}.young", young),
        checked_poisson(f"{cls_name}.poisson", poisson),
        _checks.positive(f"{cls_name}.yield_stress", yield_stress),
        _checks.positive(f"{cls_name}.relaxation_time", relaxation_time),
    )


class _Printed(AbstractViscoplastic):
    young: Batchable
    poisson: Batchable
    yield_stress: Batchable
    relaxation_time: Batchable

    def __init__(self, young, poisson, yield_stress, relaxation_time):
        self.young, self.poisson, self.yield_stress, self.relaxation_time = _checked_fields(
            type(self).__name__, young, poisson, yield_stress, relaxation_time
        )


class PerzynaLinearOverstress(_Printed):
    """(2.2.10): 2G e' = s' + (1/tau) (J2^(1/2) - k)/J2^(1/2) s; linear in the overstress."""

    def overstress_function(self, x):
        return 1.0 - 1.0 / jnp.sqrt(1.0 + x)

    def effective_stress(self, trial, k, ratio):
        # q + r (q - k) = q_trial
        return k + (trial - k) / (1.0 + ratio)


class PerzynaQuadraticOverstress(_Printed):
    """(2.2.11): 2G e' = s' + (1/tau) (J2 - k^2)/k^2 s (a cubic in q: Newton)."""

    def overstress_function(self, x):
        return x


class RelativeOverstress(_Printed):
    """(2.2.12): 2G e' = s' + (1/tau) (J2 - k^2)/J2 s."""

    def overstress_function(self, x):
        return x / (1.0 + x)

    def effective_stress(self, trial, k, ratio):
        # (1 + r) q^2 - q_trial q - r k^2 = 0, positive root
        half = trial / (2.0 * (1.0 + ratio))
        return half + jnp.sqrt(half**2 + ratio * k**2 / (1.0 + ratio))


class Craggs(_Printed):
    """(2.2.13), from Craggs' dynamic yield condition:
    2G e' = s' + (1/tau) (J2 - k^2)^(1/2)/J2^(1/2) s."""

    def overstress_function(self, x):
        return jnp.sqrt(x / (1.0 + x))

    def effective_stress(self, trial, k, ratio):
        # q + r (q^2 - k^2)^(1/2) = q_trial: a quadratic, written without the cancellation at
        # r = 1 of its textbook root
        root = jnp.sqrt(trial**2 + (ratio**2 - 1.0) * k**2)
        return (trial**2 + ratio**2 * k**2) / (trial + ratio * root)


class Perzyna(AbstractViscoplastic):
    """(2.2.9) with the Mises function f = J2: 2G eps_p' = (1/tau) Phi((J2 - k^2)/k^2) s.

    `overstress` is Phi: a JAX function, non-decreasing on x >= 0 with Phi(0) = 0 (static).
    """

    young: Batchable
    poisson: Batchable
    yield_stress: Batchable
    relaxation_time: Batchable
    overstress: Callable = eqx.field(static=True)

    def __init__(self, young, poisson, yield_stress, relaxation_time, overstress):
        self.young, self.poisson, self.yield_stress, self.relaxation_time = _checked_fields(
            "Perzyna", young, poisson, yield_stress, relaxation_time
        )
        self.overstress = overstress

    def overstress_function(self, x):
        return self.overstress(x)


def _implicit_root(phi, trial, k, ratio, iterations=64):
    def residual(q, trial, k, ratio):
        return q * (1.0 + ratio * phi((q**2 - k**2) / k**2)) - trial

    slope = jax.grad(residual)
    fixed = jax.lax.stop_gradient((trial, k, ratio))

    # A fixed count (not a tolerance) keeps the cost uniform across a vmapped batch; a Newton
    # step leaving the bracket [low, high] is replaced by bisection, 64 of which exhaust float64.
    def step(_, carry):
        q, low, high = carry
        value = residual(q, *fixed)
        low = jnp.where(value < 0.0, q, low)
        high = jnp.where(value > 0.0, q, high)
        newton = q - value / slope(q, *fixed)
        inside = (newton >= low) & (newton <= high)
        q = jnp.where(value == 0.0, q, jnp.where(inside, newton, 0.5 * (low + high)))
        return q, low, high

    q = jax.lax.fori_loop(0, iterations, step, (fixed[0], fixed[1], fixed[0]))[0]
    # One Newton step with gradients: its value is the root, its derivatives those of the
    # implicit function theorem, -(d residual/d p)/(d residual/d q).
    return q - residual(q, trial, k, ratio) / slope(q, trial, k, ratio)


class ViscoplasticState(eqx.Module):
    """E_p of (2.1.12), integrated for output (the laws themselves carry no hardening)."""

    equivalent_plastic_strain: Scalar


def initial_state(dtype=None) -> ViscoplasticState:
    dtype = jnp.result_type(float) if dtype is None else dtype
    return ViscoplasticState(jnp.zeros((), dtype))


def _return_map(law: AbstractViscoplastic, stress, strain_increment, dt):
    """Trial deviator, its effective stress, the root q and dq/dq_trial."""
    dt = _checks.positive("dt", dt)
    g, bulk = law.shear_modulus, law.bulk_modulus
    increment = symmetric_part(strain_increment)
    eye = jnp.eye(3, dtype=stress.dtype)
    pressure = jnp.trace(stress) / 3.0 + bulk * jnp.trace(increment)
    trial = deviator(stress) + 2.0 * g * deviator(increment)
    q_trial = safe_norm(trial) / np.sqrt(2.0)
    k = law.yield_stress / np.sqrt(3.0)
    plastic = q_trial > k
    # the unselected branch is solved at a harmless point (double `where`)
    q_safe = jnp.where(plastic, q_trial, 2.0 * k)
    ratio = dt / law.relaxation_time
    q, dq = jax.jvp(
        lambda t: law.effective_stress(t, k, ratio), (q_safe,), (jnp.ones_like(q_safe),)
    )
    scale = jnp.where(plastic, q / q_safe, 1.0)
    slope = jnp.where(plastic, dq, 1.0)
    return pressure * eye, trial, q_trial, scale, slope


def update(
    law: AbstractViscoplastic,
    stress: Tensor,
    state: ViscoplasticState,
    strain_increment: Tensor,
    dt,
) -> tuple[Tensor, ViscoplasticState]:
    """Stress and state after `strain_increment` applied over the time step `dt` (backward
    Euler; stable for every dt, and the rate-independent J2 return as dt/tau -> infinity)."""
    spherical, trial, q_trial, scale, _ = _return_map(law, stress, strain_increment, dt)
    # |delta eps_p| = |s_trial - s| / 2G = sqrt(2) (q_trial - q) / 2G
    plastic_increment = (1.0 - scale) * q_trial * np.sqrt(2.0) / (2.0 * law.shear_modulus)
    return spherical + scale * trial, ViscoplasticState(
        state.equivalent_plastic_strain + plastic_increment
    )


def consistent_tangent(
    law: AbstractViscoplastic,
    stress: Tensor,
    state: ViscoplasticState,
    strain_increment: Tensor,
    dt,
) -> Tangent:
    """d(new stress)/d(strain increment) of `update`: with s = beta s_trial, beta = q/q_trial,

    K 1(x)1 + 2G beta I_dev + 2G (dq/dq_trial - beta) n(x)n,   n = s_trial/|s_trial|.
    """
    del state
    g = law.shear_modulus
    _, trial, q_trial, scale, slope = _return_map(law, stress, strain_increment, dt)
    symmetric, volumetric = identity_tensors(stress.dtype)
    normal = trial / jnp.where(q_trial > 0.0, np.sqrt(2.0) * q_trial, 1.0)
    return (
        law.bulk_modulus * volumetric
        + 2.0 * g * scale * (symmetric - volumetric / 3.0)
        + 2.0 * g * (slope - scale) * jnp.einsum("ij,kl->ijkl", normal, normal)
    )
