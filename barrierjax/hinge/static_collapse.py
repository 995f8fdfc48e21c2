"""Static collapse of an axially restrained rigid-plastic beam under a central load, with
the interaction of bending and axial force (report 3.4, (3.4.8)-(3.4.22)).

A beam of span l, held against axial motion at both ends, carries a load P at mid-span.
At collapse it turns into two rigid halves about a central hinge (and, clamped, two end
hinges); a central deflection delta stretches it by u = 2 delta^2 / l (small slopes), so
an axial force N develops. Every hinge sits on the yield curve (3.4.17)

    |m| + |n|^a = 1,   m = M/M0, n = N/N0, a >= 1,

and N is uniform. In units of M0/N0 for the deflection, Delta = delta N0/M0, and with k
the number of hinge rotations per central one (k = 1 pinned, 2 clamped: the end hinges
turn half as fast as the central one, which turns at 4 delta'/l):

- compatibility with the flow rule (3.4.8), extension rate over rotation rate equal to
  (df/dN)/(df/dM) = a n^(a-1) M0/N0 at every hinge, summed over the hinges:
  a n^(a-1) = Delta / k;
- virtual work, P delta' = M0 m (sum of hinge rotation rates) + N u', in units of the
  collapse load without axial force (4 M0/l pinned, 8 M0/l clamped):
  p = m + n Delta / k.

Eliminating n: p = 1 + (a - 1) (Delta / (a k))^(a/(a-1)) while n < 1, that is Delta < a k.
From Delta = a k on, n = 1 and m = 0: the beam is a plastic string, P = 4 N0 delta / l,
p = Delta / k. The two branches meet at p = a. For a rectangle (a = 2, M0/N0 = h/4) this
is (3.4.12), (3.4.15), (3.4.16) pinned and (3.4.21) clamped. The printed (3.4.22) reads
1 + (Delta/2)^2 for the clamped beam; the derivation above gives 1 + (Delta/4)^2, which
alone meets the string branch p = Delta/2 at n = 1 (Delta = 4); (3.4.22) as printed would
jump there from 5 to 2. (3.4.18)-(3.4.19) are the pinned forms above, garbled in the scan.

a = 1 (the ideal I section): the yield curve is straight, its normal fixed, and the
stress point sits at a corner: n = 0, p = 1 up to Delta = k, then the string. This is the
limit a -> 1 of the formulas above; a = inf (a square yield curve, both corners at once)
gives n = 1, m = 1: p = 1 + Delta / k.
"""

import equinox as eqx
import jax
import jax.numpy as jnp

from .. import _checks
from .._custom_types import Scalar

_HINGE_ROTATIONS = {"pinned": 1.0, "clamped": 2.0}


class StaticLoadDeflection(eqx.Module):
    """The collapse state at each central deflection: `load` over the collapse load
    without axial force, `axial_force` n = N/N0 and `moment` m = M/M0 at the hinges, and
    `string`, true where the beam has become a plastic string (n = 1)."""

    load: Scalar
    axial_force: Scalar
    moment: Scalar
    string: Scalar


def static_load_deflection(
    delta, support: str = "pinned", interaction_exponent=2.0
) -> StaticLoadDeflection:
    """Collapse load against central deflection of an axially restrained beam under a
    central load, for the yield condition |M/M0| + |N/N0|^a = 1 (3.4.17).

    **Arguments:**

    - `delta`: central deflection over M0/N0 (h/4 for a rectangle), non-negative.
    - `support`: `"pinned"` or `"clamped"` (both ends held against axial motion).
    - `interaction_exponent`: a >= 1 (1: ideal I section, 2: rectangle; `inf`: a square
      yield curve, no interaction).

    Figures 3.4.3 and 3.4.5; differentiable in `delta` and `interaction_exponent`.
    """
    if support not in _HINGE_ROTATIONS:
        raise ValueError(f"support must be one of {sorted(_HINGE_ROTATIONS)}; got {support!r}")
    delta = _checks.check(
        "delta", delta, lambda x: (x >= 0) & (x < jnp.inf), "non-negative and finite"
    )
    a = _checks.check("interaction_exponent", interaction_exponent, lambda x: x >= 1, "at least 1")
    return _collapse(delta, a, _HINGE_ROTATIONS[support])


@jax.jit
def _collapse(delta, a, k):
    delta, a = jnp.broadcast_arrays(delta, a)
    ratio = delta / k  # the hinges' extension per unit of central rotation, in M0/N0
    interacting = (a > 1.0) & jnp.isfinite(a)
    string = (ratio >= a) & jnp.isfinite(a)
    # The beam branch, its inputs guarded where `where` discards it, so that neither its
    # values nor its derivatives are NaN there (n has an infinite slope at 0 for a > 2).
    a_safe = jnp.where(interacting, a, 2.0)
    base = jnp.where(interacting & ~string, ratio / a_safe, 0.5)
    positive = base > 0.0
    n_beam = jnp.where(positive, jnp.where(positive, base, 1.0) ** (1.0 / (a_safe - 1.0)), 0.0)
    load_beam = 1.0 + (a_safe - 1.0) * base ** (a_safe / (a_safe - 1.0))
    # a = 1: the corner n = 0 until the string; a = inf: the corner m = n = 1.
    n = jnp.where(string | ~jnp.isfinite(a), 1.0, jnp.where(interacting, n_beam, 0.0))
    m = jnp.where(string, 0.0, jnp.where(interacting, 1.0 - n_beam**a_safe, 1.0))
    load = jnp.where(
        string, ratio, jnp.where(interacting, load_beam, jnp.where(a > 1.0, 1.0 + ratio, 1.0))
    )
    return StaticLoadDeflection(load=load, axial_force=n, moment=m, string=string)
