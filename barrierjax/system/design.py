"""Design parameters of a barrier system as numbers that `jax.vmap` and `jax.grad` see: a
vehicle and a guardrail changed by the vehicle's mass, the post spacing, the rail's wall
thickness and the posts' strength (`redesign`), and the crash-test numbers a design is
judged by as one differentiable function of them (`crash_numbers`).

What each change keeps: the vehicle's shape, crush springs and tyres (its yaw inertia in
proportion to its mass: the same body, heavier); the guardrail's spans and elements (a new
spacing stretches every element and moves the rail's downstream end; the nodes' masses and
rotary inertias follow their elements' lengths), its posts' stiffness and failure, its
anchors. A thicker wall scales the thin-walled rail's area, second moment of area and mass
in proportion (the flanges stay where they are). The stable step of central differences
falls with a shorter spacing or a stiffer rail: a batch of designs needs the `dt` of its
stiffest member (`barrier.stable_step`).
"""

import equinox as eqx
import jax.numpy as jnp

from .assessment import summary, system_occupant_risk
from .barrier import Guardrail
from .impact import system_impact, time_grid
from .vehicle import Vehicle


def redesign(
    vehicle: Vehicle,
    guardrail: Guardrail,
    *,
    vehicle_mass=None,
    post_spacing=None,
    rail_thickness_ratio=None,
    post_strength=None,
) -> tuple[Vehicle, Guardrail]:
    """`vehicle` and `guardrail` with the given design parameters (SI; `None` keeps the
    value): `vehicle_mass` (kg), `post_spacing` (m), `rail_thickness_ratio` (the new wall
    thickness over the present one), `post_strength` (N, every post's lateral strength).
    Any of them may be a tracer."""
    if vehicle_mass is not None:
        vehicle_mass = jnp.asarray(vehicle_mass, vehicle.mass.dtype)
        scale = vehicle_mass / vehicle.mass
        vehicle = eqx.tree_at(lambda v: (v.mass, v.yaw_inertia), vehicle,
                              (vehicle_mass, vehicle.yaw_inertia * scale))  # fmt: skip
    rail = guardrail.rail
    mass, inertia = guardrail.node_mass, rail.point_inertia
    coords, areas = rail.coords, rail.section.area
    if post_spacing is not None:
        stretch = post_spacing / (coords[guardrail.post_nodes[1], 0] - coords[0, 0])
        coords = coords.at[:, 0].multiply(stretch)
        mass, inertia = mass * stretch, inertia * stretch**3
    if rail_thickness_ratio is not None:
        areas = areas * rail_thickness_ratio
        mass, inertia = mass * rail_thickness_ratio, inertia * rail_thickness_ratio
    rail = eqx.tree_at(lambda r: (r.coords, r.section.area, r.point_inertia), rail,
                       (coords, areas, inertia))  # fmt: skip
    guardrail = eqx.tree_at(lambda g: (g.rail, g.node_mass), guardrail, (rail, mass))
    if post_strength is not None:
        strength = jnp.broadcast_to(post_strength, guardrail.posts.strength.shape)
        guardrail = eqx.tree_at(lambda g: g.posts.strength, guardrail, strength.astype(mass.dtype))
    return vehicle, guardrail


def crash_numbers(vehicle: Vehicle, barrier, **impact) -> dict:
    """The crash-test numbers a design is judged by (`assessment.summary`: containment,
    exit speed and angle, dynamic deflection, working width, OIV, ORA, ASI, THIV, PHD; SI,
    degrees), each a differentiable scalar but the containment flag, under a caller's jit
    or vmap as well. `impact`: `system_impact`'s keywords."""
    result = system_impact(vehicle, barrier, **impact)
    options = {k: impact[k] for k in ("dt", "save_every") if k in impact}
    _, times = time_grid(vehicle, barrier, impact["duration"], **options)
    return summary(result, system_occupant_risk(result, times))
