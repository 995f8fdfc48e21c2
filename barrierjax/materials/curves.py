"""Static stress-strain curves of report 2.2 (the curve f(eps) of (2.2.3)).

A curve is stored as the static yield stress k(kappa) against the accumulated plastic strain
kappa >= 0, the form a plastic-strain-based overstress law needs. The report's total-strain
curve f(eps) of monotonic loading follows from it: on the curve eps = kappa + k(kappa)/E, which
`StaticCurve.__call__` inverts. With the elastic-perfectly plastic curve k = sigma0 the two
forms coincide for monotonic loading; under reversed loading the total-strain form makes the
band f-(eps) < sigma < f+(eps) wander with the elastic strain, so the laws use k(kappa)
(isotropic hardening; see `barrierjax.materials.overstress`).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from .._checks import check, non_negative, positive


class StaticCurve(eqx.Module):
    """Static yield stress k(kappa) against accumulated plastic strain kappa >= 0."""

    def yield_stress(self, kappa):
        raise NotImplementedError

    def slope(self, kappa):
        """Plastic hardening modulus dk/dkappa."""
        raise NotImplementedError

    def __call__(self, strain, E):
        """The total-strain static curve f(eps) of monotonic loading (odd in eps)."""
        raise NotImplementedError


class ElasticPerfectlyPlastic(StaticCurve):
    """f(eps) = E eps for |eps| < sigma0/E, else sigma0 sign(eps): k(kappa) = sigma0."""

    sigma0: jnp.ndarray

    def __init__(self, sigma0):
        self.sigma0 = positive("sigma0", sigma0)

    def yield_stress(self, kappa):
        return jnp.broadcast_to(self.sigma0, jnp.shape(kappa))

    def slope(self, kappa):
        return jnp.zeros_like(kappa)

    def __call__(self, strain, E):
        return jnp.clip(E * strain, -self.sigma0, self.sigma0)


class Bilinear(StaticCurve):
    """k(kappa) = sigma0 + H kappa; in total strain, slope E to sigma0 then E H / (E + H).

    `Bilinear.from_tangent(E, sigma0, Et)` takes the report's total-strain tangent modulus Et of
    the static curve instead: H = E Et / (E - Et).
    """

    sigma0: jnp.ndarray
    H: jnp.ndarray

    def __init__(self, sigma0, H):
        self.sigma0 = positive("sigma0", sigma0)
        self.H = non_negative("H", H)

    @classmethod
    def from_tangent(cls, E, sigma0, Et):
        E = positive("E", E)
        Et = check("Et", Et, lambda x: (x >= 0) & (x < E), "in [0, E)")
        return cls(sigma0, E * Et / (E - Et))

    def yield_stress(self, kappa):
        return self.sigma0 + self.H * kappa

    def slope(self, kappa):
        return jnp.broadcast_to(self.H, jnp.shape(kappa))

    def __call__(self, strain, E):
        magnitude = jnp.abs(E * strain)
        kappa = jnp.maximum(magnitude - self.sigma0, 0) / (E + self.H)
        return jnp.sign(strain) * jnp.minimum(magnitude, self.sigma0 + self.H * kappa)


class Tabulated(StaticCurve):
    """Piecewise-linear k(kappa) through (plastic_strain[i], stress[i]), extended beyond the
    last point with the last segment's slope.

    `plastic_strain` starts at 0 and increases strictly; `stress` is positive and
    non-decreasing (a softening curve has no unique backward-Euler update). A curve tabulated
    in total strain converts with `plastic_strain = strain - stress / E`.
    """

    plastic_strain: jnp.ndarray
    stress: jnp.ndarray

    def __init__(self, plastic_strain, stress):
        if np.ndim(plastic_strain) != 1 or np.shape(plastic_strain) != np.shape(stress):
            raise ValueError(
                "plastic_strain and stress must be 1-d of equal length; got shapes "
                f"{np.shape(plastic_strain)} and {np.shape(stress)}"
            )
        if np.shape(stress)[0] < 2:
            raise ValueError("plastic_strain must have at least 2 points")
        self.plastic_strain = check(
            "plastic_strain",
            plastic_strain,
            lambda x: (x[0] == 0) & (x[1:] > x[:-1]),
            "strictly increasing from 0",
        )
        self.stress = check(
            "stress",
            stress,
            lambda x: (x[0] > 0) & (x[1:] >= x[:-1]),
            "positive and non-decreasing",
        )

    def _segment(self, kappa):
        last = self.plastic_strain.shape[0] - 2
        i = jnp.clip(jnp.searchsorted(self.plastic_strain, kappa, side="right") - 1, 0, last)
        k0, k1 = self.plastic_strain[i], self.plastic_strain[i + 1]
        s0, s1 = self.stress[i], self.stress[i + 1]
        return k0, s0, (s1 - s0) / (k1 - k0)

    def yield_stress(self, kappa):
        k0, s0, slope = self._segment(kappa)
        return s0 + slope * (kappa - k0)

    def slope(self, kappa):
        return self._segment(kappa)[2]

    def __call__(self, strain, E):
        # On the curve eps = kappa + k(kappa)/E is piecewise linear and increasing in kappa:
        # its knots map the total strain back to kappa.
        magnitude = jnp.abs(strain)
        knots = self.plastic_strain + self.stress / E
        last = knots.shape[0] - 2
        i = jnp.clip(jnp.searchsorted(knots, magnitude, side="right") - 1, 0, last)
        fraction = (magnitude - knots[i]) / (knots[i + 1] - knots[i])
        plastic = self.stress[i] + fraction * (self.stress[i + 1] - self.stress[i])
        return jnp.sign(strain) * jnp.where(magnitude < knots[0], E * magnitude, plastic)
