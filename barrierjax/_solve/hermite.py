"""Hermite interpolation on one interval, as polynomials in the fraction of it."""

import numpy as np

# The quintic on [0, 1] through (value, slope, second derivative) at both ends, in powers
# of u: row k gives u^k's coefficient from (p0, s0, k0, p1, s1, k1), the derivatives
# taken in u (the callers' derivatives in x times the width, and its square).
_POWERS = np.array(
    [
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.5, 0.0, 0.0, 0.0],
        [-10.0, -6.0, -1.5, 10.0, -4.0, 0.5],
        [15.0, 8.0, 1.5, -15.0, 7.0, -1.0],
        [-6.0, -3.0, -0.5, 6.0, -3.0, 0.5],
    ]
)


class Quintic:
    """The quintic Hermite interpolant on an interval of `width` through (value, slope,
    second derivative) at both ends, the derivatives in x = u width; the data may be
    arrays of one shape (one interpolant each). Its powers of u are formed once, so that
    evaluating it is Horner's rule: a few multiply-adds, where the ends' weights (15
    polynomials in u) would be formed at every evaluation."""

    def __init__(self, width, left, right):
        (p0, s0, k0), (p1, s1, k1) = left, right
        data = (p0, width * s0, width**2 * k0, p1, width * s1, width**2 * k1)
        self.width = width
        # (Written out term by term, not one product with a stacked array: under `vmap`
        # a stack puts each lane's six numbers side by side, and every later operation on
        # one of them then reads a strided column.)
        self.powers = tuple(
            sum(float(m) * d for m, d in zip(row, data) if m != 0.0) for row in _POWERS
        )

    def __call__(self, u, derivatives: int = 2):
        """Value, slope and second derivative in x at the fraction `u` of the interval;
        with `derivatives=1`, value and slope alone (the second is then not traced)."""
        return polynomial(self.powers, self.width, u, derivatives)


def polynomial(powers, width, u, derivatives: int = 2):
    """The polynomial sum_k powers[k] u^k on an interval of `width` (x = u width), by
    Horner's rule: its value, slope and (`derivatives=2`) second derivative in x at u."""
    value, slope, half_second = powers[-1], 0.0, 0.0
    for power in powers[-2::-1]:
        if derivatives == 2:
            half_second = half_second * u + slope
        slope = slope * u + value
        value = value * u + power
    if derivatives == 1:
        return value, slope / width
    return value, slope / width, 2.0 * half_second / width**2


def cubic_powers(width, left, right):
    """The powers of u of the cubic Hermite interpolant on an interval of `width` through
    (value, slope) at both ends, the slopes in x = u width (padded to six, as `Quintic`'s)."""
    (p0, s0), (p1, s1) = left, right
    s0, s1 = width * s0, width * s1
    zero = 0.0 * p0
    return (p0, s0, -3.0 * p0 - 2.0 * s0 + 3.0 * p1 - s1, 2.0 * p0 + s0 - 2.0 * p1 + s1, zero, zero)


def quintic_hermite(u, width, left, right, derivatives: int = 2):
    """The quintic on [0, 1] through (value, slope, second derivative) at both ends, the
    derivatives in x = u width: its value, slope and (`derivatives=2`) second derivative
    in x at u.

    Exact on quintics; error O(width^6) on smooth functions."""
    return Quintic(width, left, right)(u, derivatives)
