"""The flail-space model of MASH 2016 and NCHRP Report 350 (after Michie, 1981): occupant
impact velocity (OIV) and ridedown acceleration (ORA).

The occupant is a point free in the ground, at rest relative to the vehicle at first. It
moves relative to the vehicle with the opposite of the vehicle's acceleration, integrated on
the vehicle's x (forward) and y (left) axes separately (the vehicle's yaw is not used: the
model behind NCHRP Report 350's Table 5.1 criteria H and I, which MASH 2016 keeps). It strikes the
interior when it has moved 0.6 m (2 ft) along x or 0.3 m (1 ft) along y, whichever first:
the occupant impact. The OIV is its velocity relative to the vehicle then, component by
component; the ORA the largest 10 ms average of each of the vehicle's acceleration
components after it (the occupant then rides down with the vehicle).

Between samples the acceleration is linear (`barrierjax.assess.signals`): the impact time is
a root of the exact cubic displacement, found by Newton's method with its derivative by the
implicit function theorem, so OIV and ORA are differentiable in the record wherever the
crossing and the largest window are unique. After the record the vehicle moves on
unaccelerated, so a record (or a model's history) that ends at rest before the occupant has
crossed the flail space still has an impact, at the speed it had: `in_record` says which.
"""

import jax.numpy as jnp

from . import signals

__all__ = ["FLAIL_X", "FLAIL_Y", "RIDEDOWN_WINDOW", "flail_space", "ridedown"]

FLAIL_X = 0.6  # m: 2 ft, longitudinal flail distance (NCHRP 350, MASH 2016)
FLAIL_Y = 0.3  # m: 1 ft, lateral
RIDEDOWN_WINDOW = 0.010  # s: ORA averages over 10 ms


def occupant_motion(ax, ay, dt):
    """The occupant's displacement and velocity relative to the vehicle at each sample,
    (n, 2) each, on the vehicle's (x, y) axes."""
    vx, dx = signals.cumulative_integrals(ax, dt)
    vy, dy = signals.cumulative_integrals(ay, dt)
    return -jnp.stack([dx, dy], -1), -jnp.stack([vx, vy], -1)


def flail_space(ax, ay, dt, flail_x=FLAIL_X, flail_y=FLAIL_Y, n_real=None):
    """Occupant impact of one record sampled at `dt` (s from its first sample; of its
    samples the first `n_real` are the record's, default all, the rest padding): (t_impact,
    oiv (2,), in_record). Without an impact (the occupant at rest relative to the vehicle
    at the record's end) t_impact is +inf and oiv zero."""
    position, velocity = occupant_motion(ax, ay, dt)
    if n_real is not None:
        position, velocity = signals.continued(position, velocity, n_real, dt)
    limits = jnp.stack([jnp.asarray(flail_x), jnp.asarray(flail_y)])
    return signals.first_impact(position, velocity, limits, dt, n_real)


def ridedown(ax, ay, dt, t_impact, window=RIDEDOWN_WINDOW, end=None):
    """ORA: the largest |10 ms average| of each acceleration component after `t_impact`
    (windows starting at it or at a later sample; the record ends at `end`, default its
    last sample): (ora_x, ora_y), zero without impact."""
    return (
        signals.max_window_mean(ax, dt, window, t_impact, end),
        signals.max_window_mean(ay, dt, window, t_impact, end),
    )
