r"""A rectangular hollow steel section (a tube rail) as a pure function of its wall
thickness t and depth d.

The rail bends about the axis along its face: `d` is the depth in the direction of the
impact (horizontal, perpendicular to the barrier's face) and `width` b is the face height,
held fixed. A fixed face height is the usual design situation: it is set by the bumper
heights the rail has to engage and by the post and blockout details, while the depth and
the wall thickness are what a designer varies to buy bending strength. Default b = 152 mm
(6 in, the common HSS rail size).

Sharp-cornered plastic properties (corner radii neglected, which overestimates Z by a few
per cent for cold-formed tubes; t is the design wall thickness, which AISC takes as 0.93
times the nominal one for electric-resistance-welded HSS):

    Z = b d^2 / 4 - (b - 2t)(d - 2t)^2 / 4          plastic section modulus
    A = b d - (b - 2t)(d - 2t)                       cross-sectional area
    M0 = Fy Z,   m = rho A                           plastic moment, mass per length

The plastic moment is attainable only if the walls are compact (no local buckling before
the section is fully plastic); `SteelTube.compactness` gives the AISC 360-16 Table B4.1b
ratios for flexure of rectangular HSS, flange (b - 3t)/t <= 1.12 (E/Fy)^(1/2) and web
(d - 3t)/t <= 2.42 (E/Fy)^(1/2), as fractions of their limits (<= 1: compact). The sizing
problem's default bounds keep every design compact; the optimiser does not check it.

Bad input raises `ValueError` naming the field (eagerly for concrete values; through
`equinox.error_if` at run time for traced ones).
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import _checks

Scalar = Float[Array, "..."]


def plastic_modulus(t, d, b):
    """Z = b d^2/4 - (b - 2t)(d - 2t)^2/4 of a sharp-cornered rectangular tube bent
    about the axis parallel to its width b (depth d in the plane of bending)."""
    return 0.25 * (b * d**2 - (b - 2.0 * t) * (d - 2.0 * t) ** 2)


def area(t, d, b):
    """A = b d - (b - 2t)(d - 2t) of a sharp-cornered rectangular tube."""
    return b * d - (b - 2.0 * t) * (d - 2.0 * t)


class SteelTube(eqx.Module):
    """A rectangular hollow steel section of fixed `width` (face height b, m); the wall
    thickness t and the depth d (m) are the design variables passed to the methods.

    Defaults: ASTM A500 Grade C, `yield_strength` Fy = 345 MPa (50 ksi),
    `density` rho = 7850 kg/m^3, `elastic_modulus` E = 200 GPa (for the compactness
    limits only); `width` 0.152 m. SI units throughout (Pa, kg/m^3, m); any consistent
    set works.
    """

    width: float = 0.152
    yield_strength: float = 345e6
    density: float = 7850.0
    elastic_modulus: float = 200e9

    def __check_init__(self):
        for name in ("width", "yield_strength", "density", "elastic_modulus"):
            _checks.positive(f"SteelTube.{name}", getattr(self, name))

    def _checked(self, t, d):
        b = self.width
        t = _checks.positive("t (wall thickness)", t)
        t = _checks.check(
            "t (wall thickness)", t, lambda x: 2.0 * x < b, "less than half the width"
        )
        d = _checks.positive("d (depth)", d)
        d = _checks.check("d (depth)", d, lambda x: x > 2.0 * t, "greater than 2 t (two walls)")
        return t, d

    def plastic_modulus(self, t, d) -> Scalar:
        """Z (length^3)."""
        t, d = self._checked(t, d)
        return plastic_modulus(t, d, self.width)

    def area(self, t, d) -> Scalar:
        """A (length^2)."""
        t, d = self._checked(t, d)
        return area(t, d, self.width)

    def plastic_moment(self, t, d) -> Scalar:
        """M0 = Fy Z (force x length)."""
        return self.yield_strength * self.plastic_modulus(t, d)

    def mass_per_length(self, t, d) -> Scalar:
        """m = rho A (mass / length)."""
        return self.density * self.area(t, d)

    def properties(self, t, d) -> tuple[Scalar, Scalar]:
        """(M0, m): the two numbers a `barrierjax.Barrier` needs from the rail."""
        return self.plastic_moment(t, d), self.mass_per_length(t, d)

    def compactness(self, t, d) -> tuple[Scalar, Scalar]:
        """(flange, web) slenderness as fractions of the AISC 360-16 compact limits for
        flexure of rectangular HSS (Table B4.1b, cases 17 and 19, flat widths b - 3t and
        d - 3t); both <= 1 means the section reaches its plastic moment."""
        t, d = self._checked(t, d)
        root = jnp.sqrt(self.elastic_modulus / self.yield_strength)
        flange = (self.width - 3.0 * t) / t / (1.12 * root)
        web = (d - 3.0 * t) / t / (2.42 * root)
        return flange, web
