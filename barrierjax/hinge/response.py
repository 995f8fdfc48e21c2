"""The one vocabulary of every impact model's result: the quantities that the normal
(report 3.2), axial-force (3.4) and oblique (3.3) impacts all define, each under one
name (`ImpactResult`, `ImpactHistory`), with the scale that gives it units (a field of
`barrierjax.Scales`; `None` where it has none). `barrierjax.simulate` returns them under
the same names, in the scene's units.

A model's result is an `ImpactResult` with fields of its own (the normal impact's end of the
accelerative phase, the oblique impact's exit velocity components); a quantity that a
model does not produce is zero in it (a normal impact's friction work, a vehicle's exit
speed from a normal impact, where it comes to rest with the barrier).
"""

import dataclasses

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .._custom_types import Batchable


def _scaled_by(unit: str | None):
    """A field in units of `unit`, a field of `barrierjax.Scales` (None: dimensionless)."""
    return eqx.field(metadata={"unit": unit})


class ImpactResult(eqx.Module):
    """The fields every impact model's result holds, dimensionless in a model's result and
    in the scene's units in `barrierjax.Result` (each field's scale in `RESULT_UNITS`).
    A model's result adds its own fields and its `history` (an `ImpactHistory`)."""

    damage: Batchable = _scaled_by("length")  # the vehicle's crush D
    duration: Batchable = _scaled_by("time")  # from contact to rest
    max_deflection: Batchable = _scaled_by("length")  # the barrier's largest, at rest
    # At rest: the barrier's displacement under the vehicle's last contact point, and the
    # distance from that point to the hinge ahead and to the one behind.
    barrier_displacement: Batchable = _scaled_by("length")
    hinge_position: Batchable = _scaled_by("length")
    rear_hinge_position: Batchable = _scaled_by("length")
    # The vehicle's speed as it leaves the barrier, and the angle of its velocity to the
    # barrier in degrees, positive away from it.
    exit_speed: Batchable = _scaled_by("velocity")
    exit_angle_deg: Batchable = _scaled_by(None)
    # Where the vehicle's initial kinetic energy went (the vehicle keeps the rest).
    crush_work: Batchable = _scaled_by("energy")
    backing_work: Batchable = _scaled_by("energy")
    hinge_work: Batchable = _scaled_by("energy")
    friction_work: Batchable = _scaled_by("energy")
    slope_work: Batchable = _scaled_by("energy")
    string_work: Batchable = _scaled_by("energy")


Series = Float[Array, "*batch n"]


class ImpactHistory(eqx.Module):
    """The time histories every impact model's history holds, one sample per entry of
    `time` (each field's scale in `HISTORY_UNITS`)."""

    time: Series = _scaled_by("time")
    # The vehicle's velocity normal to the barrier (towards it) and along it; its path in
    # plan, along the barrier from the impact point and normal to it since contact.
    vehicle_velocity: Series = _scaled_by("velocity")
    vehicle_tangential_velocity: Series = _scaled_by("velocity")
    vehicle_position: Series = _scaled_by("length")
    vehicle_displacement: Series = _scaled_by("length")
    # The barrier's under the contact point.
    barrier_velocity: Series = _scaled_by("velocity")
    barrier_displacement: Series = _scaled_by("length")
    contact_force: Series = _scaled_by("force")
    crush: Series = _scaled_by("length")
    hinge_position: Series = _scaled_by("length")
    rear_hinge_position: Series = _scaled_by("length")
    backing_work: Series = _scaled_by("energy")
    hinge_work: Series = _scaled_by("energy")
    friction_work: Series = _scaled_by("energy")
    slope_work: Series = _scaled_by("energy")
    string_work: Series = _scaled_by("energy")
    beam_kinetic_energy: Series = _scaled_by("energy")
    vehicle_kinetic_energy: Series = _scaled_by("energy")
    # deflected_shape[..., k, j]: the barrier's displacement at time[k] and x[j].
    x: Float[Array, "*batch nx"] = _scaled_by("length")
    deflected_shape: Float[Array, "*batch n nx"] = _scaled_by("length")


def _units(module) -> dict[str, str | None]:
    return {field.name: field.metadata["unit"] for field in dataclasses.fields(module)}


RESULT_UNITS = _units(ImpactResult)
"""The result fields every impact model defines, and their scales."""

HISTORY_UNITS = _units(ImpactHistory)
"""The history fields every impact model defines, and their scales."""


def exit_angle_deg(normal, tangential):
    """The exit velocity's angle to the barrier in degrees, positive away from it (its
    normal component is positive towards the barrier); 0 for a vehicle at rest, where
    the angle is undefined (the inner `where` keeps arctan2's NaN derivative at (0, 0)
    out of the gradient)."""
    at_rest = (normal == 0.0) & (tangential == 0.0)
    angle = jnp.arctan2(-normal, jnp.where(at_rest, 1.0, tangential))
    return jnp.where(at_rest, 0.0, jnp.degrees(angle))


def kinetic_energy_balance(result, mass_ratio, normal_speed, tangential_speed=0.0):
    """The vehicle's initial kinetic energy mu (V_N^2 + V_H^2) / 2 less what the result
    says it went into (every work term, and the kinetic energy it leaves with): zero to
    the model's accuracy. Dimensionless for a model's result; for `barrierjax.Result`,
    pass the vehicle's mass and impact speed and it is in the scene's units. The barrier
    is at rest at the end."""
    initial = 0.5 * mass_ratio * (normal_speed**2 + tangential_speed**2)
    spent = sum(getattr(result, name) for name in RESULT_UNITS if name.endswith("_work"))
    return initial - spent - 0.5 * mass_ratio * result.exit_speed**2
