"""Quintic Hermite interpolation on one interval."""


def _left_weights(u):
    """The weights of the left end's value, slope and second derivative, and their first
    and second u-derivatives."""
    u2, u3, u4, u5 = u * u, u**3, u**4, u**5
    return (
        (
            1 - 10 * u3 + 15 * u4 - 6 * u5,
            u - 6 * u3 + 8 * u4 - 3 * u5,
            0.5 * (u2 - 3 * u3 + 3 * u4 - u5),
        ),
        (
            -30 * u2 + 60 * u3 - 30 * u4,
            1 - 18 * u2 + 32 * u3 - 15 * u4,
            0.5 * (2 * u - 9 * u2 + 12 * u3 - 5 * u4),
        ),
        (
            -60 * u + 180 * u2 - 120 * u3,
            -36 * u + 96 * u2 - 60 * u3,
            0.5 * (2 - 18 * u + 36 * u2 - 20 * u3),
        ),
    )


def quintic_hermite(u, width, left, right):
    """The quintic on [0, 1] through (value, slope, second derivative) at both ends, the
    derivatives in x = u width: its value, slope and second derivative in x at u.

    Exact on quintics; error O(width^6) on smooth functions."""
    # The right end's weights are the left end's at 1 - u, with the odd derivatives negated.
    weights, weights_right = _left_weights(u), _left_weights(1.0 - u)
    (p0, s0, k0), (p1, s1, k1) = left, right
    scale = (1.0, width, width * width)
    out = []
    for order, (b, c) in enumerate(zip(weights, weights_right)):
        sign = -1.0 if order % 2 else 1.0
        combined = sum(
            bi * d * si + sign * ci * e * si * (-1.0) ** i
            for i, (bi, ci, d, e, si) in enumerate(zip(b, c, (p0, s0, k0), (p1, s1, k1), scale))
        )
        out.append(combined / width**order)
    return tuple(out)
