"""Isotropic linear elasticity of the 3-D laws (`j2`, `perzyna`): the shear and bulk moduli
of Young's modulus E and Poisson's ratio nu."""

import equinox as eqx

from .._custom_types import Batchable


class IsotropicElastic(eqx.Module):
    """Base of the laws with isotropic elasticity: a subclass has the fields `young` (E) and
    `poisson` (nu) and gets the moduli G and K derived from them."""

    young: eqx.AbstractVar[Batchable]
    poisson: eqx.AbstractVar[Batchable]

    @property
    def shear_modulus(self):
        """G = E / (2 (1 + nu))."""
        return self.young / (2.0 * (1.0 + self.poisson))

    @property
    def bulk_modulus(self):
        """K = E / (3 (1 - 2 nu))."""
        return self.young / (3.0 * (1.0 - 2.0 * self.poisson))
