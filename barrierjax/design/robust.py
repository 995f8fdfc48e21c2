r"""Robust sizing: a tube rail on a crushable backing sized for the least expected vehicle
damage over real-world impacts, under the criteria of every crash test of a test level.

The problem (`RobustSizing`; report 3.2 physics by `barrierjax.simulate`):

    minimise    E[D(t, q0; IS, M)]          expected crush over real-world impacts
    subject to  for every test k of the level (MASH TL-3: 3-10 and 3-11):
                W_k <= W_max,  OIV_k <= 12.2 m/s,  ORA_k <= 20.49 g
                t, q0 in a box

- Design: the rail's wall thickness t (a `SteelTube` of fixed depth and face, so M0 and
  m follow from t) and the backing's crush strength q0.
- Expectation: over the equally probable `real_world_impacts` (impact severity of NCHRP
  Report 665 by road class, vehicle mass of the US fleet; `barrierjax.design.impacts`),
  each a normal impact at the normal speed sqrt(2 IS / M), the quantity the severity
  measures. Every vehicle crushes at the scene vehicle's crush force per unit mass
  (the default scene: 450 kN for 2270 kg, 198 m/s^2; the barrier-system presets make the
  same assumption).
- Tests: the level's crash tests (`barrierjax.assess.matrices.test_level`), each vehicle
  at the test's mass, struck at the test's speed and angle, reduced to report 3.2 as
  the default scene is: the normal component v sin(theta) applied normally, the
  component along the barrier kept constant (frictionless). Not by the oblique impact of
  3.3: near phi = 1 (a test vehicle that barely yields the barrier, which the optimiser
  and the brute force pass through) its crushing phase takes steps in proportion to
  1 / (phi - 1), and under their jit the step budget cannot grow: tried, a budget of
  16384 steps was spent. The occupant risk is `barrierjax.assess.assess` of that motion
  on the vehicle's axes (the vehicle does not turn); the limits are MASH 2016's maxima (criteria H and I). The deflection limit
  W_max is the designer's (the site's), not MASH's: MASH reports the working width
  without limiting it. MASH's exit box and the vehicle's stability (criteria D, F) need
  a vehicle that yaws and rolls: not judged here (see `barrierjax.system`).

Why these criteria bind as they do: a rigid-plastic vehicle that crushes at a force
proportional to its mass decelerates at most at P0/M (20.2 g for the default scene's
198 m/s^2), so with the default scene's vehicles the ORA limit of 20.49 g holds for every
design, by 1.4 % at least; the lateral OIV cannot exceed the normal impact speed, 11.7 m/s at 100 km/h
and 25 degrees, below 12.2 m/s. The deflection of the heavier test vehicle is what
binds, as in the deterministic problem of `barrierjax.design.problem`.
"""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .. import _checks
from ..assess import assess, matrices
from ..scene import Barrier, Impact, Scene, Vehicle
from ..simulate import simulate
from .formulation import Formulation
from .impacts import Impacts, real_world_impacts
from .model import to_design
from .problem import bounds
from .section import SteelTube

Vector = Float[Array, " n"]

# The occupant risk of a test is read on a uniform 10 kHz grid up to `risk_window`; past
# the impact's end the vehicle moves on unaccelerated, so the window need only hold the
# impact: this much longer than the longest test against the softest barrier of the box
# (3-11 on the default box's softest corner lasts 0.32 s: a 0.5 s window), in steps of
# 0.1 s. A longer impact (a box where softer is not slower) is an error.
_WINDOW_MARGIN, _WINDOW_STEP = 1.25, 0.1
_RISK_SAMPLES = 200  # history samples of a test's impact
CRITERIA = ("deflection", "OIV", "ORA")


class RobustSizing(eqx.Module):
    """Choose the rail's wall thickness t (m) and the backing strength q0 (N/m) to
    minimise the expected crush over `impacts`, with every crash test of `level` meeting
    its criteria (module docstring).

    Fields: `section` (the tube's face width and steel) of fixed `depth` (m);
    `thickness_bounds`, `backing_bounds`; `crush_per_mass` (N/kg) of every vehicle;
    `impact_mass`, `impact_speed` (kg, m/s normal to the barrier) and the `impacts`'
    distributions (static); the tests' `test_mass`, `test_speed`, `test_angle_deg` and
    `test_names` (static); `deflection_limit` (m), `oiv_limit` (m/s) and `ora_limit`
    (m/s^2); `level`, `road_class`; `rtol` of the closed form; `risk_window` (s), how long
    a test's occupant risk is read (from the longest test against the box's softest
    barrier)."""

    section: SteelTube
    depth: Float[Array, ""]
    thickness_bounds: Float[Array, "2"]
    backing_bounds: Float[Array, "2"]
    crush_per_mass: Float[Array, ""]
    impact_mass: Vector
    impact_speed: Vector
    test_mass: Vector
    test_speed: Vector
    test_angle_deg: Vector
    deflection_limit: Float[Array, ""]
    oiv_limit: Float[Array, ""]
    ora_limit: Float[Array, ""]
    impacts: Impacts = eqx.field(static=True)
    test_names: tuple[str, ...] = eqx.field(static=True)
    level: str = eqx.field(static=True)
    road_class: str = eqx.field(static=True)
    rtol: float = eqx.field(static=True)
    risk_window: float = eqx.field(static=True)

    def __init__(
        self,
        level: str = "MASH TL-3",
        *,
        deflection_limit=0.6,
        crush_per_mass=450e3 / 2270.0,
        road_class: str = "Interstate",
        section: SteelTube | None = None,
        depth=0.2032,
        thickness_bounds=(5.2e-3, 12.7e-3),
        backing_bounds=(5e3, 300e3),
        n_severity: int = 32,
        n_mass: int = 8,
        rtol: float = 1e-8,
    ):
        tests = matrices.test_level(level)
        if any(test.standard != "mash" for test in tests):
            raise ValueError(
                f"RobustSizing.level must be a MASH test level (its occupant limits are "
                f"MASH's); got {level!r}"
            )
        self.section = SteelTube() if section is None else section
        self.depth = _checks.positive("RobustSizing.depth", depth)
        self.thickness_bounds = bounds("RobustSizing.thickness_bounds", thickness_bounds)
        self.backing_bounds = bounds("RobustSizing.backing_bounds", backing_bounds)
        t_high = float(self.thickness_bounds[1])
        if not (2.0 * t_high < self.section.width and 2.0 * t_high < float(self.depth)):
            raise ValueError(
                "RobustSizing.thickness_bounds: the upper thickness must be less than half "
                f"the tube's width and depth; got {t_high:g}"
            )
        self.crush_per_mass = _checks.positive("RobustSizing.crush_per_mass", crush_per_mass)
        self.impacts = real_world_impacts(road_class, n_severity, n_mass)
        self.road_class = road_class
        self.impact_mass = jnp.asarray(self.impacts.mass)
        self.impact_speed = jnp.asarray(self.impacts.normal_speed)
        self.test_mass = jnp.asarray([float(test.mass) for test in tests])
        self.test_speed = jnp.asarray([test.speed for test in tests])
        self.test_angle_deg = jnp.asarray([float(test.angle_deg) for test in tests])
        self.test_names = tuple(test.label for test in tests)
        self.deflection_limit = _checks.positive("RobustSizing.deflection_limit", deflection_limit)
        limits = matrices.occupant_limits("mash")
        self.oiv_limit = jnp.asarray(limits["OIV"].maximum)
        self.ora_limit = jnp.asarray(limits["ORA"].maximum)
        self.level = f"MASH {tests[0].level}"
        self.rtol = _checks.tolerance("RobustSizing.rtol", rtol)
        softest = rail_barrier(self, self.lower)
        longest = max(
            float(_normal_impact(self, softest, m, v * math.sin(math.radians(a)), 0).duration)
            for m, v, a in zip(
                np.asarray(self.test_mass),
                np.asarray(self.test_speed),
                np.asarray(self.test_angle_deg),
            )
        )
        self.risk_window = round(
            _WINDOW_STEP * math.ceil(_WINDOW_MARGIN * longest / _WINDOW_STEP), 6
        )

    @property
    def lower(self) -> Float[Array, "2"]:
        """Lower bounds of (t, q0)."""
        return jnp.stack([self.thickness_bounds[0], self.backing_bounds[0]])

    @property
    def upper(self) -> Float[Array, "2"]:
        """Upper bounds of (t, q0)."""
        return jnp.stack([self.thickness_bounds[1], self.backing_bounds[1]])


def rail_barrier(problem: RobustSizing, x) -> Barrier:
    """The `Barrier` of design x = (t, q0)."""
    moment, mass_per_length = problem.section.properties(x[..., 0], problem.depth)
    return Barrier(moment, mass_per_length, x[..., 1])


def _normal_impact(problem, barrier, mass, normal_speed, n_history):
    vehicle = Vehicle(mass, problem.crush_per_mass * mass)
    scene = Scene(barrier, vehicle, Impact(normal_speed))
    return simulate(scene, method="closed_form", rtol=problem.rtol, n_history=n_history)


def damages(problem: RobustSizing, barrier: Barrier) -> tuple[Vector, Vector]:
    """(crush, deflection) of `barrier` in each of the real-world impacts (m)."""
    result = jax.vmap(lambda m, v: _normal_impact(problem, barrier, m, v, 0))(
        problem.impact_mass, problem.impact_speed
    )
    return result.damage, result.max_deflection


def expected_damage(problem: RobustSizing, x):
    """E[D]: the mean crush of design x over the equally probable real-world impacts (m)."""
    return jnp.mean(damages(problem, rail_barrier(problem, x))[0])


def _test_impact(problem, barrier, mass, speed, angle_deg):
    """A crash test's impact with its history: report 3.2 on the normal component, the
    component along the barrier kept constant."""
    angle = jnp.deg2rad(angle_deg)
    result = _normal_impact(problem, barrier, mass, speed * jnp.sin(angle), _RISK_SAMPLES)
    along = jnp.full_like(result.history.time, speed * jnp.cos(angle))
    return eqx.tree_at(lambda r: r.history.vehicle_tangential_velocity, result, along)


def _test(problem, barrier, mass, speed, angle_deg):
    result = _test_impact(problem, barrier, mass, speed, angle_deg)
    result = eqx.error_if(
        result,
        result.duration > problem.risk_window,
        f"RobustSizing: a crash test's impact lasts longer than the {problem.risk_window:g} s "
        "window of its occupant risk (set by the softest barrier of the box)",
    )
    risk = assess(result, t_end=problem.risk_window)
    oiv = jnp.maximum(jnp.abs(risk.oiv_x), jnp.abs(risk.oiv_y))
    return jnp.stack([result.max_deflection, oiv, jnp.maximum(risk.ora_x, risk.ora_y)])


def crash_test_responses(problem: RobustSizing, barrier: Barrier) -> Float[Array, "tests 3"]:
    """Each crash test's deflection (m), OIV (m/s, the larger of its two components) and
    ORA (m/s^2, the larger) against `barrier`, in the order of `CRITERIA`."""
    return jax.vmap(lambda m, v, a: _test(problem, barrier, m, v, a))(
        problem.test_mass, problem.test_speed, problem.test_angle_deg
    )


def limits(problem: RobustSizing) -> Float[Array, "3"]:
    """The limits of `CRITERIA`: W_max (m), OIV (m/s), ORA (m/s^2)."""
    return jnp.stack([problem.deflection_limit, problem.oiv_limit, problem.ora_limit])


def margins(problem: RobustSizing, barrier: Barrier) -> Float[Array, "tests 3"]:
    """Each test's margin on each criterion against `barrier`, limit - value, in the
    criterion's units (>= 0: met)."""
    return limits(problem) - crash_test_responses(problem, barrier)


def _measure(problem: RobustSizing, u):
    x = to_design(problem, u)
    g = crash_test_responses(problem, rail_barrier(problem, x)) / limits(problem) - 1.0
    return expected_damage(problem, x), g.ravel()


def robust_formulation(problem: RobustSizing) -> Formulation:
    """The problem on the unit cube of (t, q0), log-uniform: expected crush over its
    rigid-wall value, the tests' criteria normalised by their limits; q0 stiffens."""
    severity = jnp.asarray(problem.impacts.severity)
    rigid_wall = jnp.mean(severity / (problem.crush_per_mass * problem.impact_mass))
    return Formulation(problem, rigid_wall, measure=_measure, design=to_design, stiffening=1)


__all__ = [
    "CRITERIA",
    "RobustSizing",
    "crash_test_responses",
    "damages",
    "expected_damage",
    "limits",
    "margins",
    "rail_barrier",
    "robust_formulation",
]
