"""The theoretical head of EN 1317-1 (the 1998 and 2010 editions): theoretical head
impact velocity (THIV) and post-impact head deceleration (PHD).

As the flail-space occupant, the head is a point free in the ground, starting at the
vehicle's centre of gravity with its velocity; unlike it, the vehicle turns under it with the
yaw rate. The head strikes the interior when its position in the vehicle's frame reaches
0.6 m along x or 0.3 m along y (Dx, Dy of EN 1317-1); the THIV is the magnitude of its
velocity relative to the vehicle then, in the vehicle's frame (the rate of change of its
vehicle-frame coordinates, rotation included). The PHD is the largest 10 ms average of the
resultant of the vehicle's x and y accelerations after the head's impact (the head then
moves with the vehicle). EN 1317-2:2010 judges by THIV alone; PHD is reported, informative
(`barrierjax.assess.matrices.OCCUPANT_LIMITS["en1317"]["PHD"]`).

The yaw angle is the trapezoidal integral of the yaw rate; the vehicle's acceleration is
rotated into the ground frame at each sample and integrated as in `barrierjax.assess.flail`,
and the head's ground-frame displacement rotated back. Between samples the path in the
vehicle's frame is the cubic Hermite interpolant of these samples and their exact slopes
(exact without yaw: then THIV is the flail-space OIV's magnitude); after the record it runs
on straight.
"""

import jax.numpy as jnp

from . import signals
from .flail import FLAIL_X, FLAIL_Y, RIDEDOWN_WINDOW

__all__ = ["head_impact", "post_impact_head_deceleration"]


def head_motion(ax, ay, yaw_rate, dt):
    """The head's position and velocity in the vehicle's frame at each sample, (n, 2)."""
    yaw, _ = signals.cumulative_integrals(yaw_rate, dt)
    cos, sin = jnp.cos(yaw), jnp.sin(yaw)
    vx, dx = signals.cumulative_integrals(cos * ax - sin * ay, dt)
    vy, dy = signals.cumulative_integrals(sin * ax + cos * ay, dt)
    x = -(cos * dx + sin * dy)
    y = -(-sin * dx + cos * dy)
    u = -(cos * vx + sin * vy) + yaw_rate * y
    w = -(-sin * vx + cos * vy) - yaw_rate * x
    return jnp.stack([x, y], -1), jnp.stack([u, w], -1)


def head_impact(ax, ay, yaw_rate, dt, flail_x=FLAIL_X, flail_y=FLAIL_Y, n_real=None):
    """(t_head, thiv, in_record) of one record (its first `n_real` samples, default all,
    the rest padding): when the theoretical head strikes and its speed relative to the
    vehicle then (m/s); +inf and zero without an impact."""
    position, velocity = head_motion(ax, ay, yaw_rate, dt)
    if n_real is not None:
        position, velocity = signals.continued(position, velocity, n_real, dt)
    limits = jnp.stack([jnp.asarray(flail_x), jnp.asarray(flail_y)])
    t_head, relative, in_record = signals.first_impact(position, velocity, limits, dt, n_real)
    return t_head, signals.safe_norm(relative), in_record


def post_impact_head_deceleration(ax, ay, dt, t_head, window=RIDEDOWN_WINDOW, end=None):
    """PHD: the largest 10 ms average of the resultant of (ax, ay) after `t_head` (the
    record ends at `end`, default its last sample)."""
    resultant = signals.safe_norm(jnp.stack([ax, ay], -1))
    return signals.max_window_mean(resultant, dt, window, t_head, end)
