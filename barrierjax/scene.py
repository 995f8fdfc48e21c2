"""Scenes: a barrier, a vehicle and an impact, in any consistent unit system.

Physical inputs enter here and are reduced once to the report's dimensionless groups
(section 3.2, after (3.2.8); docs/errata.md, 3.3.14 for the scales):

    length   L   = 2 (M0/q0)^(1/2)        force    P_b = 4 (M0 q0)^(1/2)
    time     t0  = m^(1/2) M0^(1/4) / q0^(3/4)
    velocity L/t0 = 2 M0^(1/4) q0^(1/4) / m^(1/2)      acceleration L/t0^2 = 2 q0/m
    energy   P_b L = 8 M0

    mass ratio  mu   = M / (m L)          force ratio phi = P0 / P_b
    axial ratio eta0 = N0 / P_b  (3.4, after 3.4.33)

Every class is an `equinox.Module`, so scenes are PyTrees: `jax.vmap` over a scene
whose leaves are arrays solves a batch, and `jax.grad` differentiates through any leaf.
Concrete invalid values raise `ValueError` naming the field; traced ones fail at run
time with the same message (`equinox.error_if`).
"""

import equinox as eqx
import jax
import jax.numpy as jnp

from . import _checks
from ._custom_types import Batchable
from .compilation_cache import stored_program


class Barrier(eqx.Module):
    """A rigid-plastic beam on a rigid-plastic backing.

    - `plastic_moment`: M0, the beam's fully plastic bending moment (force x length).
    - `mass_per_length`: m, the beam's mass per unit length.
    - `backing_strength`: q0, the force per unit length at which the backing crushes.
    - `axial_capacity`: N0, the beam's plastic axial force where its ends are held
      (report 3.4), or None for a beam that carries no axial force.
    """

    plastic_moment: Batchable
    mass_per_length: Batchable
    backing_strength: Batchable
    axial_capacity: Batchable | None

    def __init__(self, plastic_moment, mass_per_length, backing_strength, axial_capacity=None):
        self.plastic_moment = _checks.positive("Barrier.plastic_moment", plastic_moment)
        self.mass_per_length = _checks.positive("Barrier.mass_per_length", mass_per_length)
        self.backing_strength = _checks.positive("Barrier.backing_strength", backing_strength)
        self.axial_capacity = (
            None
            if axial_capacity is None
            else _checks.positive("Barrier.axial_capacity", axial_capacity)
        )


class Vehicle(eqx.Module):
    """A rigid-perfectly-plastic vehicle: `mass` M, crushing at the constant `crush_force` P0."""

    mass: Batchable
    crush_force: Batchable

    def __init__(self, mass, crush_force):
        self.mass = _checks.positive("Vehicle.mass", mass)
        self.crush_force = _checks.positive("Vehicle.crush_force", crush_force)


class Impact(eqx.Module):
    """The vehicle's `speed`, its `angle_deg` to the barrier's axis in (0, 90] (90 is a
    normal impact), and the Coulomb `friction` coefficient between vehicle and barrier."""

    speed: Batchable
    angle_deg: Batchable
    friction: Batchable

    def __init__(self, speed, angle_deg=90.0, friction=0.0):
        self.speed = _checks.positive("Impact.speed", speed)
        self.angle_deg = _checks.in_range("Impact.angle_deg", angle_deg, 0.0, 90.0)
        self.friction = _checks.non_negative("Impact.friction", friction)


class Scene(eqx.Module):
    """What happens: a `barrier`, a `vehicle`, and an `impact`."""

    barrier: Barrier
    vehicle: Vehicle
    impact: Impact

    def __check_init__(self):
        for name, kind in (("barrier", Barrier), ("vehicle", Vehicle), ("impact", Impact)):
            if not isinstance(getattr(self, name), kind):
                raise ValueError(f"Scene.{name} must be a barrierjax.{kind.__name__}")


class Scales(eqx.Module):
    """The report's characteristic scales, in the scene's units."""

    length: Batchable
    force: Batchable
    time: Batchable
    velocity: Batchable
    acceleration: Batchable
    energy: Batchable


class Dimensionless(eqx.Module):
    """The report's dimensionless groups of a scene, and the scales that restore units."""

    mass_ratio: Batchable
    force_ratio: Batchable
    normal_speed: Batchable
    tangential_speed: Batchable
    axial_ratio: Batchable | None
    friction: Batchable
    scales: Scales


def scales(barrier: Barrier) -> Scales:
    """Characteristic length, force, time, velocity, acceleration and energy (3.2)."""
    moment, m, q0 = barrier.plastic_moment, barrier.mass_per_length, barrier.backing_strength
    length = 2.0 * jnp.sqrt(moment / q0)
    force = 4.0 * jnp.sqrt(moment * q0)
    time = jnp.sqrt(m) * moment**0.25 / q0**0.75
    return Scales(
        length=length,
        force=force,
        time=time,
        velocity=length / time,
        acceleration=2.0 * q0 / m,
        energy=force * length,
    )


@stored_program
@eqx.filter_jit
def dimensionless(scene: Scene) -> Dimensionless:
    """The report's groups of `scene`: mass ratio mu = M/(m L), force ratio phi = P0/P_b,
    the normal and tangential impact speeds over L/t0, the axial ratio eta0 = N0/P_b
    (None without axial capacity), and the scales."""
    s = scales(scene.barrier)
    barrier, vehicle, impact = scene.barrier, scene.vehicle, scene.impact
    # The angle is to the barrier's axis: the tangential part through the complement, so
    # that 90 degrees gives exactly zero, and the normal one through the angle, so that a
    # small angle gives a small positive one (in float32 the complement of 1e-6 degrees
    # rounds to 90, and its cosine to -4e-8).
    complement = jnp.deg2rad(90.0 - impact.angle_deg)
    return Dimensionless(
        mass_ratio=vehicle.mass / (barrier.mass_per_length * s.length),
        force_ratio=vehicle.crush_force / s.force,
        normal_speed=impact.speed * jnp.sin(jnp.deg2rad(impact.angle_deg)) / s.velocity,
        tangential_speed=impact.speed * jnp.sin(complement) / s.velocity,
        axial_ratio=None if barrier.axial_capacity is None else barrier.axial_capacity / s.force,
        friction=impact.friction,
        scales=s,
    )


def broadcast_scene(scene: Scene) -> Scene:
    """`scene` with every leaf broadcast to the leaves' common shape, so that a plain
    `jax.vmap` maps over all of them (a sweep over speed alone, say)."""
    leaves, treedef = jax.tree.flatten(scene)
    return jax.tree.unflatten(treedef, jnp.broadcast_arrays(*leaves))
