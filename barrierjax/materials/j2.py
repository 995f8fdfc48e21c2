"""Rate-independent J2 (Mises, Prandtl-Reuss) plasticity for 3-D small strain (report 2.1).

The report gives the laws in rate form: the Prandtl-Reuss equations (2.1.6)-(2.1.9) with the
Mises condition (1/2 s_ij s_ij)^(1/2) = k, kinematic hardening (2.1.15) with Prager's rule
alpha' = C eps_p', and isotropic hardening (2.1.16) k = k(q) with q the equivalent plastic
strain (2.1.12). Here they are integrated over a strain increment by backward Euler, the radial
return (the elastic trial stress is pulled back to the yield surface along the normal of the
trial point), which is what an element of an incremental solution needs (report 2.1, "a form
particularly suitable for incorporation into incremental numerical approaches").

Conventions:
- Stress and strain are 3x3 symmetric tensors, strain as the tensor eps_ij (shear components
  are half the engineering shear strains). An increment is symmetrised before use, so the
  displacement-gradient increment may be passed as well.
- `yield_stress` is the uniaxial yield stress sigma_y = sqrt(3) k.
- `isotropic_modulus` H_i and `kinematic_modulus` H_k are slopes of the uniaxial stress against
  the uniaxial plastic strain, so that a monotone tension test is bilinear with plastic slope
  H_i + H_k and tangent E (H_i + H_k) / (E + H_i + H_k). In the report's variables: Prager's
  C = 2 H_k / 3, and k(E_p) = (sigma_y + H_i sqrt(2/3) E_p) / sqrt(3), with E_p the
  equivalent plastic strain exactly as defined by (2.1.12), int |eps_p'| dt (no factor 2/3;
  the uniaxial plastic strain is sqrt(2/3) E_p).

In deviatoric tensor norm |x| = (x_ij x_ij)^(1/2) the yield condition (2.1.15)-(2.1.16) is
|s - alpha| = R(E_p) = sqrt(2/3) sigma_y + (2/3) H_i E_p; plastic flow is eps_p' = lambda n
with n = (s - alpha)/|s - alpha| (2.1.2), so E_p' = lambda.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import _checks
from .._custom_types import Batchable, Scalar
from .elastic import IsotropicElastic

Tensor = Float[Array, "3 3"]
Tangent = Float[Array, "3 3 3 3"]


def checked_poisson(name: str, value):
    """Poisson's ratio, checked to lie in (-1, 0.5) (a stable isotropic solid)."""
    return _checks.check(name, value, lambda x: (x > -1.0) & (x < 0.5), "in (-1, 0.5)")


class J2Plasticity(IsotropicElastic):
    """Isotropic elasticity (E, nu) with the Mises yield condition and linear hardening.

    Perfectly plastic with both moduli zero (the default), isotropic (2.1.16), kinematic
    (2.1.15, Prager) or both combined. See the module docstring for the units of the moduli.
    """

    young: Batchable
    poisson: Batchable
    yield_stress: Batchable
    isotropic_modulus: Batchable
    kinematic_modulus: Batchable

    def __init__(self, young, poisson, yield_stress, isotropic_modulus=0.0, kinematic_modulus=0.0):
        self.young = _checks.positive("J2Plasticity.young", young)
        self.poisson = checked_poisson("J2Plasticity.poisson", poisson)
        self.yield_stress = _checks.positive("J2Plasticity.yield_stress", yield_stress)
        self.isotropic_modulus = _checks.non_negative(
            "J2Plasticity.isotropic_modulus", isotropic_modulus
        )
        self.kinematic_modulus = _checks.non_negative(
            "J2Plasticity.kinematic_modulus", kinematic_modulus
        )


class J2State(eqx.Module):
    """Internal variables: the back stress alpha (2.1.15) and E_p (2.1.12)."""

    back_stress: Tensor
    equivalent_plastic_strain: Scalar


def initial_state(dtype=None) -> J2State:
    """The virgin state: no back stress, no plastic strain."""
    dtype = jnp.result_type(float) if dtype is None else dtype
    return J2State(jnp.zeros((3, 3), dtype), jnp.zeros((), dtype))


def deviator(tensor: Tensor) -> Tensor:
    """x - tr(x)/3 I, as in (2.1.7)-(2.1.8)."""
    return tensor - jnp.trace(tensor) / 3.0 * jnp.eye(3, dtype=tensor.dtype)


def safe_norm(tensor: Tensor) -> Scalar:
    """(x_ij x_ij)^(1/2), with a zero (not NaN) gradient at x = 0 (double `where`)."""
    squared = jnp.sum(tensor**2)
    positive = squared > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 0.0)


def symmetric_part(tensor: Tensor) -> Tensor:
    """(A + A^T) / 2: the strain of a displacement gradient."""
    return 0.5 * (tensor + tensor.T)


def _elastic(law: J2Plasticity, strain: Tensor) -> Tensor:
    eye = jnp.eye(3, dtype=strain.dtype)
    return law.bulk_modulus * jnp.trace(strain) * eye + 2.0 * law.shear_modulus * deviator(strain)


def _radius(law: J2Plasticity, equivalent_plastic_strain) -> Scalar:
    return (
        np.sqrt(2.0 / 3.0) * law.yield_stress
        + (2.0 / 3.0) * law.isotropic_modulus * equivalent_plastic_strain
    )


def yield_function(law: J2Plasticity, stress: Tensor, state: J2State) -> Scalar:
    """f = |s - alpha| - R(E_p): negative inside the elastic range, zero on the surface."""
    relative = deviator(stress) - state.back_stress
    return safe_norm(relative) - _radius(law, state.equivalent_plastic_strain)


def _return_map(law: J2Plasticity, stress, state, strain_increment):
    """Trial stress, then the closed-form radial return (linear hardening makes the
    consistency condition linear in the multiplier increment)."""
    g = law.shear_modulus
    trial = stress + _elastic(law, symmetric_part(strain_increment))
    relative = deviator(trial) - state.back_stress
    size = safe_norm(relative)
    overshoot = size - _radius(law, state.equivalent_plastic_strain)
    plastic = overshoot > 0.0
    stiffness = 2.0 * g + (2.0 / 3.0) * (law.isotropic_modulus + law.kinematic_modulus)
    multiplier = jnp.where(plastic, overshoot, 0.0) / stiffness
    normal = relative / jnp.where(size > 0.0, size, 1.0)
    return trial, normal, size, multiplier, plastic


def update(
    law: J2Plasticity, stress: Tensor, state: J2State, strain_increment: Tensor
) -> tuple[Tensor, J2State]:
    """Stress and state at the end of a strain increment (radial return; backward Euler of
    (2.1.2), (2.1.6), (2.1.12), (2.1.15), (2.1.16)). First order along non-proportional paths;
    exact for proportional ones with perfect plasticity."""
    trial, normal, _, multiplier, _ = _return_map(law, stress, state, strain_increment)
    new_stress = trial - 2.0 * law.shear_modulus * multiplier * normal
    new_state = J2State(
        state.back_stress + (2.0 / 3.0) * law.kinematic_modulus * multiplier * normal,
        state.equivalent_plastic_strain + multiplier,
    )
    return new_stress, new_state


def identity_tensors(dtype):
    """The fourth-order symmetric identity I_ijkl and the volumetric delta_ij delta_kl."""
    eye = jnp.eye(3, dtype=dtype)
    symmetric = 0.5 * (jnp.einsum("ik,jl->ijkl", eye, eye) + jnp.einsum("il,jk->ijkl", eye, eye))
    volumetric = jnp.einsum("ij,kl->ijkl", eye, eye)
    return symmetric, volumetric


def consistent_tangent(
    law: J2Plasticity, stress: Tensor, state: J2State, strain_increment: Tensor
) -> Tangent:
    """d(new stress)_ij / d(strain increment)_kl of `update`, in closed form:

        K 1(x)1 + 2G theta I_dev - 2G theta_bar n(x)n,
        theta = 1 - 2G dgamma/|xi_trial|,  theta_bar = 1/(1 + (H_i + H_k)/(3G)) - (1 - theta)

    (the algorithmic tangent of the radial return; the elastic tensor when the step is
    elastic). Symmetric in (ij), (kl) and (ij)<->(kl).
    """
    g = law.shear_modulus
    _, normal, size, multiplier, plastic = _return_map(law, stress, state, strain_increment)
    symmetric, volumetric = identity_tensors(stress.dtype)
    theta = 1.0 - 2.0 * g * multiplier / jnp.where(plastic, size, 1.0)
    hardening = 1.0 / (1.0 + (law.isotropic_modulus + law.kinematic_modulus) / (3.0 * g))
    theta_bar = jnp.where(plastic, hardening - (1.0 - theta), 0.0)
    return (
        law.bulk_modulus * volumetric
        + 2.0 * g * theta * (symmetric - volumetric / 3.0)
        - 2.0 * g * theta_bar * jnp.einsum("ij,kl->ijkl", normal, normal)
    )
