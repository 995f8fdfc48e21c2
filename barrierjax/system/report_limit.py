"""Chapter 3's barrier in the system model: a rail on a continuous backing struck by a
narrow vehicle, for comparing `system_impact` with `barrierjax.hinge.oblique_impact` and
mapping where the report's rigid-plastic idealisation holds.

Report 3.2-3.3 take an infinite rigid-plastic beam (plastic moment M0, mass m per length)
on a rigid-plastic backing (resistance q0 per length) struck by a rigid-plastic vehicle
(mass M, crush force P0) at a point. Here the same beam is the chapter 4 element with a
two-flange section of plastic moment M0 (flanges `flange_offset` from the axis, the
area m / density: elastic-perfectly plastic, shape factor 1), on a post at every node whose
lateral spring yields at q0 times the node spacing after `backing_yield` of travel (no
longitudinal restraint to speak of, no end anchors: the report's beam carries no axial
force); the vehicle is a square `width` wide whose front crushes at P0 after
`crush_yield`, with no tyre friction and a yaw inertia large enough that it does not turn
(the report's vehicle translates). What is left between the two models is the elasticity of
rail, backing and crush, the finite rail and mesh, the vehicle's width and, in oblique
impacts, the tangential speed that the report holds fixed.

`energy_ratio` measures the first: the vehicle's kinetic energy normal to the barrier over
the elastic energy the barrier stores at its static collapse load P_b = 4 (M0 q0)^1/2 (report 3.2), that of an
elastic beam on an elastic foundation of the backing's modulus under P_b (Hetenyi):
P_b^2 beta / (4 k), beta = (k / 4 EI)^1/4. The rigid-plastic idealisation is commonly
taken to hold where such a ratio is above about 3.
"""

import numpy as np

from .. import scene as report
from ..materials.plasticity import RateIndependentPlasticity
from .barrier import Guardrail, guardrail, post_springs, rail_section
from .vehicle import Vehicle, vehicle


def backed_rail(
    barrier: report.Barrier,
    *,
    length,
    element_length,
    elastic_modulus=200e9,
    density=7850.0,
    flange_offset=0.1,
    backing_yield=0.005,
) -> Guardrail:
    """The report's `barrier` (SI) on its backing: `length` m of rail in elements of
    `element_length`, a backing spring at every node."""
    area = barrier.mass_per_length / density
    yield_stress = barrier.plastic_moment / (area * flange_offset)
    section = rail_section(
        area, area * flange_offset**2, RateIndependentPlasticity(elastic_modulus, yield_stress)
    )
    stiffness = barrier.backing_strength / backing_yield
    strength = barrier.backing_strength * element_length
    posts = post_springs(stiffness * element_length, strength, 1e3, 1.0, 1.0)
    return guardrail(length, element_length, section=section, density=density, posts=posts,
                     anchor_stiffness=0.0, elements_per_span=1)  # fmt: skip


def point_vehicle(v: report.Vehicle, *, width=0.3, crush_yield=0.002) -> Vehicle:
    """The report's vehicle `v` (SI): a `width` square crushing at its crush force."""
    strength = v.crush_force / width
    return vehicle(v.mass, 1e3 * v.mass, width, width, width / 2, 0.0, width / 2, width / 2,
                   crush_stiffness=strength / crush_yield, crush_strength=strength,
                   tyre_friction=0.0, n_front=5, n_side=2)  # fmt: skip


def energy_ratio(
    s: report.Scene, *, elastic_modulus=200e9, density=7850.0, flange_offset=0.1,
    backing_yield=0.005,
):  # fmt: skip
    """The vehicle's kinetic energy normal to the barrier over the barrier's elastic energy
    at its collapse load (module docstring), for `backed_rail`'s barrier of scene `s`."""
    b = s.barrier
    bending = elastic_modulus * b.mass_per_length / density * flange_offset**2
    modulus = b.backing_strength / backing_yield
    collapse = report.scales(b).force
    beta = (modulus / (4.0 * bending)) ** 0.25
    normal_speed = s.impact.speed * np.sin(np.radians(s.impact.angle_deg))
    kinetic = 0.5 * s.vehicle.mass * normal_speed**2
    return kinetic / (collapse**2 * beta / (4.0 * modulus))
