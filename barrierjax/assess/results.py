"""`assess(result)`: the occupant risk of an impact model's result, through the one result
vocabulary (`barrierjax.hinge.response.ImpactHistory`).

The report's vehicle is a mass that does not turn: its forward axis is the direction of its
velocity at contact, at the impact angle to the barrier, which lies on its right. The
history gives its velocity normal to the barrier (towards it) and along it; `vehicle_record`
interpolates both linearly between the history's samples onto a uniform grid (10 kHz, a
crash test's sampling, unless told) and differentiates them there (central differences) for
the vehicle-fixed accelerations that `occupant_risk` reads. After the history (the vehicle
at rest, or leaving the barrier) the vehicle moves on unaccelerated. The metrics are as
accurate as the history is fine: the default 200 samples of `simulate` resolve the 10 ms
averages; the accelerations' peaks between samples are smoothed.
"""

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer

from ..compilation_cache import stored_program
from .occupant import OccupantRisk, occupant_risk

__all__ = ["ASSESS_STEP", "assess", "vehicle_record"]

ASSESS_STEP = 1e-4  # s: the uniform grid's step (10 kHz)


def _duration(history) -> float:
    if isinstance(history.time, Tracer):
        raise ValueError("assess: t_end must be given for a traced result (under jit or grad)")
    return float(np.max(np.asarray(history.time)))


def vehicle_record(history, *, dt: float = ASSESS_STEP, t_end: float | None = None):
    """(t, ax, ay) of one result's `history`: the vehicle's accelerations on its own axes
    (x forward, y left), m/s^2, at uniform times `t` (step `dt`) from contact to `t_end`
    (default: the history's end, which must then be concrete). Differentiable."""
    t = _grid(history, dt, t_end)
    velocities = history.time, history.vehicle_velocity, history.vehicle_tangential_velocity
    return (t, *_vehicle_axes(*velocities, t, dt))


# The coarsest grid step: the ridedown's 10 ms average then holds ten samples.
_COARSEST_STEP = 1e-3


def _grid(history, dt: float, t_end: float | None) -> np.ndarray:
    if not 0.0 < dt <= _COARSEST_STEP:
        raise ValueError(f"dt must be positive and at most {_COARSEST_STEP:g} s; got {dt!r}")
    if t_end is not None and not 0.0 < t_end < math.inf:
        raise ValueError(f"t_end must be positive and finite, s; got {t_end!r}")
    t_end = _duration(history) if t_end is None else float(t_end)
    return dt * np.arange(max(math.ceil(t_end / dt - 1e-9) + 1, 3))


@functools.partial(jax.jit, static_argnames="dt")
def _vehicle_axes(time, normal_velocity, tangential_velocity, t, dt):
    """The accelerations on the vehicle's forward and left axes at the uniform times `t`."""
    normal = jnp.interp(t, time, normal_velocity)
    along = jnp.interp(t, time, tangential_velocity)
    speed = jnp.hypot(normal_velocity[0], tangential_velocity[0])
    sin, cos = normal_velocity[0] / speed, tangential_velocity[0] / speed
    a_normal, a_along = jnp.gradient(normal, dt), jnp.gradient(along, dt)
    forward = sin * a_normal + cos * a_along
    left = -cos * a_normal + sin * a_along
    return forward, left


@stored_program
@functools.partial(jax.jit, static_argnames="dt")
def _vehicle_axes_rows(time, normal_velocity, tangential_velocity, t, *, dt):
    """`_vehicle_axes` of histories (on the last axis, any leading ones a batch) at the
    shared times `t`: one program, reshapes included, which the command line keeps between
    runs (each eager reshape would be a program of its own to find in a new process)."""
    rows = lambda history: history.reshape(-1, history.shape[-1])
    one = lambda *velocities: _vehicle_axes(*velocities, t, dt)
    axes = jax.vmap(one)(rows(time), rows(normal_velocity), rows(tangential_velocity))
    return tuple(a.reshape(*time.shape[:-1], t.size) for a in axes)


def assess(
    result, *, dt: float = ASSESS_STEP, t_end: float | None = None, asi_edition: str = "2010"
) -> OccupantRisk:
    """The occupant risk (`OccupantRisk`) of a `simulate` result with a history (a normal,
    oblique or axial impact), on a uniform grid of step `dt` to `t_end` (default: the
    history's end; a batch's longest). Under `jit` or `grad` give `t_end`."""
    history = result.history
    if history is None:
        raise ValueError("assess: the result has no history: simulate(scene, n_history>=2)")
    t = _grid(history, dt, t_end)
    velocities = history.time, history.vehicle_velocity, history.vehicle_tangential_velocity
    ax, ay = _vehicle_axes_rows(*velocities, jax.device_put(t), dt=dt)
    return occupant_risk(t, ax, ay, asi_edition=asi_edition)
