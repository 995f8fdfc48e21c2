"""`simulate(scene)`: the response of a scene in the scene's own units.

The scene is reduced to the report's groups once (`scene.dimensionless`), the model that
the scene's physics calls for is run in dimensionless form, and the result is scaled
back once. Dispatch is static: a normal impact without axial force compiles only the
model of report 3.2.
"""

from typing import Literal

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer
from jaxtyping import Array, Float

from ._custom_types import Batchable
from .hinge.normal import NormalImpact, normal_impact
from .scene import Dimensionless, Scene, dimensionless


class History(eqx.Module):
    """Time histories in the scene's units (one sample per row of `time`).

    `deflected_shape[k, j]` is the barrier's displacement at `time[k]` and distance `x[j]`
    from the impact point (the shape is symmetric about it)."""

    time: Float[Array, " n"]
    vehicle_velocity: Float[Array, " n"]
    barrier_velocity: Float[Array, " n"]
    contact_force: Float[Array, " n"]
    hinge_position: Float[Array, " n"]
    displacement: Float[Array, " n"]
    x: Float[Array, " nx"]
    deflected_shape: Float[Array, "n nx"]


class Result(eqx.Module):
    """The response of a scene, in the scene's units.

    - `damage`: the vehicle's crush (length);
    - `max_deflection`: the barrier's largest displacement under the impact point;
    - `duration`: time from contact to rest;
    - `peak_force`, `peak_deceleration`: largest contact force and vehicle deceleration;
    - `hinge_extent`: distance from the impact point to the travelling hinges at rest;
    - `kinetic_energy`, `crush_work`, `backing_work`, `hinge_work`: the vehicle's
      initial kinetic energy and where it went;
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
    groups: Dimensionless
    model: NormalImpact
    history: History | None


def _require_normal_impact(scene: Scene) -> Scene:
    if scene.barrier.axial_capacity is not None:
        raise NotImplementedError(
            "Barrier.axial_capacity is set, but the axial-force model (report 3.4) is not "
            "implemented yet; leave axial_capacity=None"
        )
    message = (
        "Impact.angle_deg < 90: the oblique-impact model (report 3.3) is not "
        "implemented yet; use angle_deg=90"
    )
    angle = scene.impact.angle_deg
    if isinstance(angle, Tracer):
        return eqx.tree_at(lambda s: s.impact.angle_deg, scene, eqx.error_if(angle, angle != 90.0, message))
    if not np.all(np.asarray(angle) == 90.0):
        raise NotImplementedError(message)
    return scene


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


def simulate(
    scene: Scene,
    *,
    method: Literal["closed_form", "ode"] = "closed_form",
    rtol: float = 1e-8,
    n_history: int = 200,
    n_shape: int = 81,
) -> Result:
    """The response of `scene` in its own units; `n_history=0` skips the histories.

    Normal impact (angle 90 degrees, no axial capacity): report 3.2 by
    `barrierjax.hinge.normal_impact` with `method` and `rtol`. Friction plays no part in
    a normal impact (nothing slides). Other scenes raise `NotImplementedError` until
    their models land (inside `jit`, an oblique angle fails at run time).
    """
    scene = _require_normal_impact(scene)
    groups = dimensionless(scene)
    s = groups.scales
    model = normal_impact(
        groups.mass_ratio,
        groups.force_ratio,
        groups.normal_speed,
        method=method,
        rtol=rtol,
        n_history=n_history,
    )
    vehicle = scene.vehicle
    history = None
    if n_history:
        h = model.history
        x = jnp.linspace(0.0, 2.0, n_shape)
        # The first sample of the decelerative phase repeats the last of the accelerative
        # one, so S is non-decreasing as the interpolation needs.
        shape = deflected_shape(x, h.hinge, h.displacement, h.hinge_work)
        history = History(
            time=h.time * s.time,
            vehicle_velocity=h.vehicle_velocity * s.velocity,
            barrier_velocity=h.barrier_velocity * s.velocity,
            contact_force=h.contact_force * s.force,
            hinge_position=h.hinge * s.length,
            displacement=h.displacement * s.length,
            x=x * s.length,
            deflected_shape=shape * s.length,
        )
    return Result(
        damage=model.damage * s.length,
        max_deflection=model.w_final * s.length,
        duration=model.t_final * s.time,
        peak_force=vehicle.crush_force,
        peak_deceleration=vehicle.crush_force / vehicle.mass,
        hinge_extent=model.s_final * s.length,
        kinetic_energy=0.5 * vehicle.mass * scene.impact.speed**2,
        crush_work=model.crush_work * s.energy,
        backing_work=model.backing_work * s.energy,
        hinge_work=model.hinge_work * s.energy,
        groups=groups,
        model=model,
        history=history,
    )
