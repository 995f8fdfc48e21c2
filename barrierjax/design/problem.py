r"""The sizing problem: a tube rail on a crushable backing, sized for least vehicle damage.

The problem (report 3.2 physics, `barrierjax.simulate` with the closed form):

    minimise    f(t, d, q0) = mean over impact cases of the vehicle's crush D
    subject to  W_k(t, d, q0) <= W_max for every case k     (barrier's final deflection)
                (t, d, q0) in a box

with t, d the rail's wall thickness and depth (`SteelTube`: M0 = Fy Z, m = rho A) and q0
the backing's crush strength per unit length. The constraint is reported as
`max_k W_k - W_max` (<= 0: feasible), the same as one constraint per case
(`barrierjax.design.model`).

Default problem (`SizingProblem()`, SI units; every number is a choice, stated here):
- cases: a 1100 kg car crushing at P0 = 250 kN and a 2270 kg pickup crushing at 450 kN
  (the MASH 1100C and 2270P test masses), both at 40 km/h (11.1 m/s) and normal to the
  barrier (the closed form of report 3.2: `barrierjax.hinge.oblique_impact` has none,
  and its gradients cost milliseconds per scenario, see the README). Against
  a rigid wall they would crush M v^2 / (2 P0) = 272 mm and 311 mm;
- bounds: t in [5.2, 12.7] mm, d in [102, 305] mm with the face width b = 152 mm, so every
  section in the box is compact (AISC 360-16 Table B4.1b: the flange limit
  (b - 3t)/t <= 1.12 (E/Fy)^(1/2) needs t >= 5.07 mm, and the web limit holds for
  d <= 61 t) and M0 = Fy Z is attainable; q0 in [5, 300] kN/m;
- deflection limit W_max = 0.6 m, which is active at the optimum. The optimum is then the
  lightest, weakest rail of the box (t and d on their lower bounds) on the backing just
  strong enough to hold the pickup to 0.6 m: the car yields that barrier and crushes
  about 42 mm instead of 272 mm. With a tighter limit the optimum changes character: at
  0.5 m no feasible barrier lets the car crush much less than on a rigid wall (best mean
  crush about 131 mm, against 137.6 mm in the basin where the car sees a rigid barrier),
  and between about 0.5 and 0.58 m the landscape has many local minima near the car's
  phi = 1 kink (see `barrierjax.design.solve`).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import _checks
from .section import SteelTube

Vector = Float[Array, " n"]

KMH = 1.0 / 3.6


def bounds(name, value) -> Array:
    if np.asarray(value).size != 2:
        raise ValueError(f"{name} must be a pair (low, high); got {np.asarray(value).tolist()!r}")
    low, high = (float(v) for v in np.asarray(value, dtype=float).reshape(-1))
    if not (0.0 < low < high < np.inf):
        raise ValueError(f"{name} must satisfy 0 < low < high < inf; got {(low, high)!r}")
    return jnp.asarray([low, high], dtype=jnp.result_type(float))


class ImpactCases(eqx.Module):
    """Normal impacts the barrier must take: vehicle `mass` (kg), `crush_force` P0 (N)
    and `speed` (m/s), one entry per case, with static `names`."""

    mass: Vector
    crush_force: Vector
    speed: Vector
    names: tuple[str, ...] = eqx.field(static=True)

    def __init__(self, mass, crush_force, speed, names=None):
        arrays = [np.atleast_1d(np.asarray(v, dtype=float)) for v in (mass, crush_force, speed)]
        n = arrays[0].shape[0]
        for label, a in zip(("mass", "crush_force", "speed"), arrays):
            if a.ndim != 1 or a.shape[0] != n:
                raise ValueError(
                    f"ImpactCases.{label} must be a 1-D sequence of {n} values; got shape {a.shape}"
                )
        self.mass = _checks.positive("ImpactCases.mass", arrays[0])
        self.crush_force = _checks.positive("ImpactCases.crush_force", arrays[1])
        self.speed = _checks.positive("ImpactCases.speed", arrays[2])
        names = tuple(f"case {k}" for k in range(n)) if names is None else tuple(names)
        if len(names) != n:
            raise ValueError(f"ImpactCases.names must have {n} entries; got {len(names)}")
        self.names = names


def default_cases() -> ImpactCases:
    """A 1100 kg car (P0 = 250 kN) and a 2270 kg pickup (P0 = 450 kN), both at 40 km/h."""
    return ImpactCases(
        mass=(1100.0, 2270.0),
        crush_force=(250e3, 450e3),
        speed=(40.0 * KMH, 40.0 * KMH),
        names=("1100 kg car", "2270 kg pickup"),
    )


class SizingProblem(eqx.Module):
    """Choose the rail's wall thickness t (m), depth d (m) and the backing strength q0
    (N/m) in their bounds to minimise the mean vehicle crush over `cases`, keeping the
    barrier's deflection at most `deflection_limit` (m) in every case. See the module
    docstring for the defaults and why. `rtol` is the closed form's quadrature target."""

    section: SteelTube
    thickness_bounds: Float[Array, "2"]
    depth_bounds: Float[Array, "2"]
    backing_bounds: Float[Array, "2"]
    cases: ImpactCases
    deflection_limit: Float[Array, ""]
    rtol: float = eqx.field(static=True)

    def __init__(
        self,
        section: SteelTube | None = None,
        thickness_bounds=(5.2e-3, 12.7e-3),
        depth_bounds=(0.102, 0.305),
        backing_bounds=(5e3, 300e3),
        cases: ImpactCases | None = None,
        deflection_limit=0.6,
        rtol: float = 1e-8,
    ):
        self.section = SteelTube() if section is None else section
        if not isinstance(self.section, SteelTube):
            raise ValueError("SizingProblem.section must be a barrierjax.design.SteelTube")
        self.thickness_bounds = bounds("SizingProblem.thickness_bounds", thickness_bounds)
        self.depth_bounds = bounds("SizingProblem.depth_bounds", depth_bounds)
        self.backing_bounds = bounds("SizingProblem.backing_bounds", backing_bounds)
        t_high = float(self.thickness_bounds[1])
        if not 2.0 * t_high < float(self.section.width):
            raise ValueError(
                "SizingProblem.thickness_bounds: the upper thickness must be less than half "
                f"the section width {float(self.section.width):g}; got {t_high:g}"
            )
        if not float(self.depth_bounds[0]) > 2.0 * t_high:
            raise ValueError(
                "SizingProblem.depth_bounds: the lower depth must exceed twice the upper "
                f"thickness {2.0 * t_high:g}; got {float(self.depth_bounds[0]):g}"
            )
        self.cases = default_cases() if cases is None else cases
        if not isinstance(self.cases, ImpactCases):
            raise ValueError("SizingProblem.cases must be a barrierjax.design.ImpactCases")
        self.deflection_limit = _checks.positive("SizingProblem.deflection_limit", deflection_limit)
        self.rtol = _checks.tolerance("SizingProblem.rtol", rtol)

    @property
    def lower(self) -> Float[Array, "3"]:
        """Lower bounds of (t, d, q0)."""
        return jnp.stack([self.thickness_bounds[0], self.depth_bounds[0], self.backing_bounds[0]])

    @property
    def upper(self) -> Float[Array, "3"]:
        """Upper bounds of (t, d, q0)."""
        return jnp.stack([self.thickness_bounds[1], self.depth_bounds[1], self.backing_bounds[1]])
