"""`simulate(scene)`: the response of a scene in the scene's own units.

The scene is reduced to the report's groups once (`scene.dimensionless`), the model that
the scene's physics calls for is run in dimensionless form, and the result is scaled
back once. Dispatch is static: a normal impact without axial force compiles only the
model of report 3.2.
"""

from typing import Literal

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer
from jaxtyping import Array, Float

from ._custom_types import Batchable
from .hinge.axial import axial_impact
from .hinge.normal import NormalImpact, normal_impact
from .hinge.oblique import ObliqueImpact, ObliqueImpactHistory, oblique_impact
from .scene import Dimensionless, Scene, dimensionless


class History(eqx.Module):
    """Time histories in the scene's units (one sample per row of `time`).

    - `vehicle_velocity`: the vehicle's velocity normal to the barrier (towards it);
      `barrier_velocity`: the barrier's under the contact point; `contact_force`;
    - `hinge_position`, `rear_hinge_position`: distance from the contact point to the
      hinge ahead of the vehicle and to the one behind it (equal in a normal impact);
    - `displacement`: the barrier's displacement under the contact point;
    - `vehicle_position`, `vehicle_displacement`: the vehicle's path in plan, along the
      barrier from the impact point and normal to it (towards the barrier) since contact,
      the integral of its velocity: the barrier's displacement under it plus its crush
      while in contact, a straight line at its exit velocity after it has left (see
      `vehicle_path`); in a normal impact the position stays 0;
    - `vehicle_tangential_velocity`: along the barrier (0 in a normal impact);
    - `deflected_shape[k, j]`: the barrier's displacement at `time[k]` and `x[j]`. In a
      normal impact `x` is the distance from the impact point (the shape is symmetric
      about it); in an oblique one, the position along the barrier from the impact point,
      in the vehicle's direction of travel.

    The histories of an oblique impact are the solver's steps, padded with the final
    state (`result.model.history.n_saved` of them are distinct)."""

    time: Float[Array, " n"]
    vehicle_velocity: Float[Array, " n"]
    barrier_velocity: Float[Array, " n"]
    contact_force: Float[Array, " n"]
    hinge_position: Float[Array, " n"]
    displacement: Float[Array, " n"]
    x: Float[Array, " nx"]
    deflected_shape: Float[Array, "n nx"]
    rear_hinge_position: Float[Array, " n"]
    vehicle_position: Float[Array, " n"]
    vehicle_displacement: Float[Array, " n"]
    vehicle_tangential_velocity: Float[Array, " n"]


class Result(eqx.Module):
    """The response of a scene, in the scene's units.

    - `damage`: the vehicle's crush (length);
    - `max_deflection`: the barrier's largest displacement under the impact point;
    - `duration`: time from contact to rest;
    - `peak_force`, `peak_deceleration`: largest contact force and vehicle deceleration;
    - `hinge_extent`: distance from the impact point to the travelling hinges at rest;
    - `kinetic_energy`, `crush_work`, `backing_work`, `hinge_work`: the vehicle's
      initial kinetic energy and where it went;
    - `friction_work`, `slope_work`: oblique impacts only (zero otherwise): the work of
      friction, and that of the normal force through the barrier's slope under the
      vehicle (see `barrierjax.hinge.oblique`); the vehicle keeps the rest;
    - `string_work`: with `Barrier.axial_capacity`, the stretching work of the plastic
      string (report 3.4.45) once N reaches N0 (zero otherwise; the beam stage's
      stretching is in `hinge_work`);
    - `exit_speed`, `exit_angle_deg`: the vehicle's speed when it leaves the barrier and
      the angle of its velocity to the barrier (positive: away from it); zero for a
      normal impact, where the vehicle comes to rest with the barrier;
    - `groups`: the scene's dimensionless groups and scales;
    - `model`: the dimensionless model result;
    - `history`: a `History`, or None when `n_history=0`.
    """

    damage: Batchable
    max_deflection: Batchable
    duration: Batchable
    peak_force: Batchable
    peak_deceleration: Batchable
    hinge_extent: Batchable
    kinetic_energy: Batchable
    crush_work: Batchable
    backing_work: Batchable
    hinge_work: Batchable
    friction_work: Batchable
    slope_work: Batchable
    string_work: Batchable
    exit_speed: Batchable
    exit_angle_deg: Batchable
    groups: Dimensionless
    model: NormalImpact | ObliqueImpact
    history: History | None


def _is_normal(scene: Scene, oblique: bool | None) -> bool:
    """Static dispatch. With `oblique=None`, a concrete angle below 90 degrees takes the
    oblique model; a traced angle (under `jit` or `vmap`) takes the normal one and must
    be 90 degrees at run time, so that a normal sweep never pays for the oblique model.
    `oblique=True` forces the oblique model (which also covers 90 degrees)."""
    if oblique is not None:
        normal = not oblique
    else:
        angle = scene.impact.angle_deg
        normal = isinstance(angle, Tracer) or bool(np.all(np.asarray(angle) == 90.0))
    if scene.barrier.axial_capacity is not None and not normal:
        raise NotImplementedError(
            "Barrier.axial_capacity is set for an oblique impact: the axial-force model of "
            "report 3.4 is a normal impact's; leave axial_capacity=None or strike at 90 degrees"
        )
    return normal


def _require_normal_angle(scene: Scene) -> Scene:
    message = (
        "Impact.angle_deg must be 90 for the normal-impact model; under jit or vmap pass "
        "simulate(..., oblique=True) to sweep oblique angles"
    )
    angle = scene.impact.angle_deg
    if isinstance(angle, Tracer):
        checked = eqx.error_if(angle, jnp.any(angle != 90.0), message)
        return eqx.tree_at(lambda s: s.impact.angle_deg, scene, checked)
    if not np.all(np.asarray(angle) == 90.0):
        raise ValueError(message)
    return scene


def vehicle_path(history: ObliqueImpactHistory):
    """The vehicle's path in plan during an oblique impact, dimensionless: `(along,
    normal)` at each sample of `history` (`oblique_impact(..., history=True).history`),
    along the barrier from the impact point and normal to it (towards the barrier) from
    the point of contact, for one scenario (`jax.vmap` it over a batch).

    While in contact (crushing and contact phases) the vehicle is at the contact point
    F(T), and its body has moved W(F(T), T) + D(T) towards the barrier, the barrier's
    displacement under it plus its crush: the integral of its normal velocity (3.3.3).
    From the first sample of the free phase on (where the contact force is zero: after a
    separation, or the final state at rest) it moves on in a straight line at its exit
    velocity."""
    h = history
    n = h.time.shape[-1]
    free = h.contact_force == 0.0
    first = jnp.where(jnp.any(free), jnp.argmax(free), n)
    k = jnp.minimum(first, n - 1)
    in_contact = jnp.arange(n) < first
    elapsed = h.time - h.time[k]
    along = h.contact_position
    normal = h.contact_displacement + h.crush
    return (
        jnp.where(in_contact, along, along[k] + h.vehicle_tangential_velocity * elapsed),
        jnp.where(in_contact, normal, normal[k] + h.vehicle_normal_velocity * elapsed),
    )


def deflected_shape(x, hinge, displacement, hinge_work):
    """W(X, T) on the grid `x` from the histories of S, W and the hinge work (all
    dimensionless), for the velocity field V (1 - |X|/S) of (3.2.1).

    A point at X moves once the hinge has passed it (at T_X, with S(T_X) = X, or at T = 0
    if X <= S*), so W(X, T) = [W(T) - W(T_X)] - X [H(T) - H(T_X)] with H = integral V/S dT
    = 2 x hinge work."""
    h = 2.0 * hinge_work
    # S is non-decreasing, so W and H at hinge passage are interpolated against it.
    w_at_pass = jnp.interp(x, hinge, displacement, left=0.0)
    h_at_pass = jnp.interp(x, hinge, h, left=0.0)
    passed = x[None, :] <= hinge[:, None]
    shape = (displacement[:, None] - w_at_pass) - x * (h[:, None] - h_at_pass)
    return jnp.where(passed, jnp.maximum(shape, 0.0), 0.0)


def _with_string_profile(shape, x, profile, model: NormalImpact):
    """The deflected shape during the plastic-string stage, where the mechanism of (3.2.1)
    no longer holds: the string's own profile (`NormalImpactHistory.string_profile`, at
    nodes spread over the final half-span), for the string block of the history and the
    state at rest after it (its last `n + 1` rows, n = profile rows), where the string
    was reached."""
    n = profile.shape[0]
    nodes = model.s_final * jnp.linspace(0.0, 1.0, profile.shape[1])
    on_grid = jax.vmap(lambda row: jnp.interp(x, nodes, row, right=0.0))(profile)
    string_rows = jnp.concatenate([on_grid, on_grid[-1:]])
    reached = jnp.isfinite(model.t_string)
    return shape.at[-(n + 1) :].set(jnp.where(reached, string_rows, shape[-(n + 1) :]))


def simulate(
    scene: Scene,
    *,
    method: Literal["closed_form", "ode"] = "closed_form",
    rtol: float = 1e-8,
    n_history: int = 200,
    n_shape: int = 81,
    oblique: bool | None = None,
) -> Result:
    """The response of `scene` in its own units; `n_history=0` skips the histories.

    - Normal impact (angle 90 degrees, no axial capacity): report 3.2 by
      `barrierjax.hinge.normal_impact` with `method` and `rtol`. Friction plays no part
      in a normal impact (nothing slides).
    - Oblique impact (a concrete angle below 90 degrees, or `oblique=True`, which a
      `vmap` over angles needs): report 3.3 by `barrierjax.hinge.oblique_impact` with
      `rtol` (`method` does not apply; see that module for its current limits).
    - With `Barrier.axial_capacity` (a normal impact only): the beam stage of report 3.4,
      integrated in time whatever `method` (it has no closed form), and where N reaches
      N0 the plastic-string stage (3.4.45) to rest.
    """
    if _is_normal(scene, oblique):
        scene = _require_normal_angle(scene)
        return _normal(scene, dimensionless(scene), method, rtol, n_history, n_shape)
    return _oblique(scene, dimensionless(scene), rtol, n_history)


# The scale of each field of `History` and `Result` (a field of `Scales`); the adapters
# below give each model's quantities under these names, dimensionless, and `_in_units`
# scales them, once.
_HISTORY_UNITS = {
    "time": "time",
    "vehicle_velocity": "velocity",
    "barrier_velocity": "velocity",
    "contact_force": "force",
    "hinge_position": "length",
    "displacement": "length",
    "x": "length",
    "deflected_shape": "length",
    "rear_hinge_position": "length",
    "vehicle_position": "length",
    "vehicle_displacement": "length",
    "vehicle_tangential_velocity": "velocity",
}
_RESULT_UNITS = {
    "damage": "length",
    "max_deflection": "length",
    "duration": "time",
    "hinge_extent": "length",
    "crush_work": "energy",
    "backing_work": "energy",
    "hinge_work": "energy",
    "friction_work": "energy",
    "slope_work": "energy",
    "string_work": "energy",
    "exit_speed": "velocity",
}


def _in_units(units, scales, quantities):
    return {name: value * getattr(scales, units[name]) for name, value in quantities.items()}


# What every model's result calls by the `Result`'s own names.
_SHARED = ("damage", "crush_work", "backing_work", "hinge_work")


def _result(scene, groups, model, history, **quantities) -> Result:
    """The `Result` of a model: its fields named as `Result`'s (`_SHARED`), the other
    dimensionless `quantities` (the fields of `_RESULT_UNITS`, and `exit_angle_deg`) and
    `history` (those of `_HISTORY_UNITS`, or None)."""
    vehicle, scales = scene.vehicle, groups.scales
    quantities |= {name: getattr(model, name) for name in _SHARED}
    exit_angle_deg = quantities.pop("exit_angle_deg")
    if history is not None:
        history = History(**_in_units(_HISTORY_UNITS, scales, history))
    return Result(
        **_in_units(_RESULT_UNITS, scales, quantities),
        exit_angle_deg=exit_angle_deg,
        peak_force=vehicle.crush_force,
        peak_deceleration=vehicle.crush_force / vehicle.mass,
        kinetic_energy=0.5 * vehicle.mass * scene.impact.speed**2,
        groups=groups,
        model=model,
        history=history,
    )


def _normal(scene, groups, method, rtol, n_history, n_shape) -> Result:
    inputs = (groups.mass_ratio, groups.force_ratio, groups.normal_speed)
    if groups.axial_ratio is None:
        model = normal_impact(*inputs, method=method, rtol=rtol, n_history=n_history)
    else:
        model = axial_impact(*inputs, groups.axial_ratio, rtol=rtol, n_history=n_history)
    history = None
    if n_history:
        h = model.history
        x = jnp.linspace(0.0, 2.0, n_shape)
        # The first sample of the decelerative phase repeats the last of the accelerative
        # one, so S is non-decreasing as the interpolation needs.
        shape = deflected_shape(x, h.hinge, h.displacement, h.hinge_work)
        if h.string_profile is not None:
            shape = _with_string_profile(shape, x, h.string_profile, model)
        zeros = jnp.zeros_like(h.time)
        history = dict(
            time=h.time,
            vehicle_velocity=h.vehicle_velocity,
            barrier_velocity=h.barrier_velocity,
            contact_force=h.contact_force,
            hinge_position=h.hinge,
            displacement=h.displacement,
            x=x,
            deflected_shape=shape,
            rear_hinge_position=h.hinge,
            vehicle_position=zeros,
            vehicle_displacement=h.displacement + h.crush,
            vehicle_tangential_velocity=zeros,
        )
    zero = jnp.zeros_like(model.damage)
    return _result(
        scene,
        groups,
        model,
        history,
        max_deflection=model.w_final,
        duration=model.t_final,
        hinge_extent=model.s_final,
        friction_work=zero,
        slope_work=zero,
        string_work=model.string_work,
        exit_speed=zero,
        exit_angle_deg=zero,
    )


def _oblique(scene, groups, rtol, n_history) -> Result:
    """Report 3.3 by `barrierjax.hinge.oblique_impact`. Its histories are the solver's
    steps (padded with the final state); `hinge_position` is the distance to the hinge
    ahead of the vehicle, `rear_hinge_position` to the one behind it, and `x` runs along
    the barrier from the impact point."""
    model = oblique_impact(
        groups.mass_ratio,
        groups.force_ratio,
        groups.normal_speed,
        groups.tangential_speed,
        friction=groups.friction,
        rtol=rtol,
        history=bool(n_history),
        max_steps=4096,
    )
    history = None
    if n_history:
        h = model.history
        along, normal = vehicle_path(h)
        history = dict(
            time=h.time,
            vehicle_velocity=h.vehicle_normal_velocity,
            barrier_velocity=h.v0,
            contact_force=h.contact_force,
            hinge_position=h.s1,
            displacement=h.contact_displacement,
            x=h.x,
            deflected_shape=h.displacement,
            rear_hinge_position=h.s2,
            vehicle_position=along,
            vehicle_displacement=normal,
            vehicle_tangential_velocity=h.vehicle_tangential_velocity,
        )
    return _result(
        scene,
        groups,
        model,
        history,
        max_deflection=model.max_deflection,
        duration=model.t_final,
        hinge_extent=jnp.maximum(model.s1_final, model.s2_final),
        friction_work=model.friction_work,
        slope_work=model.slope_work,
        string_work=jnp.zeros_like(model.damage),
        exit_speed=jnp.hypot(model.exit_normal_speed, model.exit_tangential_speed),
        exit_angle_deg=model.exit_angle_deg,
    )
