"""The vehicle of a barrier-system impact: a planar rigid body with a crushable periphery and
tyres, after BARRIER VII's vehicle (Powell 1973).

Body axes: x forward, y to the left, origin at the centre of gravity. The vehicle is a
rectangle `length` x `width` whose front is `front_to_cg` ahead of the c.g.; the periphery
that can meet a rail on the vehicle's left (the front edge and the left side) carries
contact points, each the end of a crush spring of its own (`contact.py`): elastic with
`crush_stiffness` per metre of periphery, yielding at `crush_strength` per metre, unloading
elastically, so that the crush a point keeps is its plastic part. The tyres resist sliding
sideways with Coulomb friction on their static loads (free rolling: no longitudinal force).
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer

from .._checks import non_negative, positive

G = 9.80665  # m/s^2, standard gravity


class Vehicle(eqx.Module):
    """A planar vehicle (SI units). Every field is a leaf: jit, vmap and grad see them all;
    `n_front` and `n_side` (the contact points on the front edge and on the left side) fix
    the shapes."""

    mass: jnp.ndarray
    yaw_inertia: jnp.ndarray
    length: jnp.ndarray
    width: jnp.ndarray
    front_to_cg: jnp.ndarray  # from the front bumper back to the c.g.
    cg_to_front_axle: jnp.ndarray  # from the c.g. forward to the front axle
    wheelbase: jnp.ndarray
    track: jnp.ndarray
    crush_stiffness: jnp.ndarray  # N/m per m of periphery
    crush_strength: jnp.ndarray  # N per m of periphery
    tyre_friction: jnp.ndarray
    n_front: int = eqx.field(static=True, default=5)
    n_side: int = eqx.field(static=True, default=16)


def vehicle(
    mass,
    yaw_inertia,
    length,
    width,
    front_to_cg,
    cg_to_front_axle,
    wheelbase,
    track,
    *,
    crush_stiffness,
    crush_strength,
    tyre_friction=0.5,
    n_front: int = 5,
    n_side: int = 16,
) -> Vehicle:
    """A checked `Vehicle`: every length and force positive, the c.g. within the outline and
    the axles within the wheelbase's reach; at least 2 contact points on each edge."""
    fields = {
        "mass": mass,
        "yaw_inertia": yaw_inertia,
        "length": length,
        "width": width,
        "front_to_cg": front_to_cg,
        "wheelbase": wheelbase,
        "track": track,
        "crush_stiffness": crush_stiffness,
        "crush_strength": crush_strength,
    }
    checked = {name: positive(name, value) for name, value in fields.items()}
    checked["cg_to_front_axle"] = non_negative("cg_to_front_axle", cg_to_front_axle)
    checked["tyre_friction"] = non_negative("tyre_friction", tyre_friction)
    concrete = not any(isinstance(x, Tracer) for x in (front_to_cg, length))
    if concrete and np.any(np.asarray(front_to_cg) >= np.asarray(length)):
        raise ValueError(
            f"front_to_cg must be less than length (the c.g. inside the outline); got "
            f"{front_to_cg!r} and {length!r}"
        )
    for name, count in (("n_front", n_front), ("n_side", n_side)):
        if int(count) != count or count < 2:
            raise ValueError(f"{name} must be an integer >= 2; got {count!r}")
    return Vehicle(**checked, n_front=int(n_front), n_side=int(n_side))


def periphery(v: Vehicle):
    """The contact points in body axes (n, 2) and the length of periphery each stands for
    (n,): `n_front` on the front edge from the right corner to the left one (both corners
    included, trapezoidal shares), then `n_side` at the middles of equal parts of the left
    side, front to rear. The front edge is symmetric: a head-on impact does not yaw."""
    u = jnp.linspace(0.0, 1.0, v.n_front, dtype=v.width.dtype)
    front_points = jnp.stack([jnp.full_like(u, 1.0) * v.front_to_cg, v.width * (u - 0.5)], -1)
    front_share = jnp.full_like(u, 1.0) * v.width / (v.n_front - 1)
    front_share = front_share.at[0].multiply(0.5).at[-1].multiply(0.5)
    s = (jnp.arange(v.n_side, dtype=v.length.dtype) + 0.5) / v.n_side
    side_points = jnp.stack([v.front_to_cg - v.length * s, jnp.full_like(s, 0.5) * v.width], -1)
    side_share = jnp.full_like(s, 1.0) * v.length / v.n_side
    return (
        jnp.concatenate([front_points, side_points]),
        jnp.concatenate([front_share, side_share]),
    )


def outline(v: Vehicle):
    """The rectangle's corners in body axes (4, 2): front right, front left, rear left,
    rear right."""
    front, back, half = v.front_to_cg, v.front_to_cg - v.length, 0.5 * v.width
    return jnp.stack([jnp.stack([front, -half]), jnp.stack([front, half]),
                      jnp.stack([back, half]), jnp.stack([back, -half])])  # fmt: skip


def contact_stiffness_bound(v: Vehicle) -> float:
    """A bound on what the crush springs add to one rail node's stiffness (every point at
    once), for the stable step (`barrier.stable_step`): concrete data only."""
    k, length, width = (float(np.asarray(x)) for x in (v.crush_stiffness, v.length, v.width))
    return k * (length + width)


def wheels(v: Vehicle):
    """The four wheels in body axes (4, 2) and their static loads (4,): the axle loads split
    by the c.g.'s place on the wheelbase, half to each side."""
    front, rear = v.cg_to_front_axle, v.cg_to_front_axle - v.wheelbase
    half = 0.5 * v.track
    positions = jnp.stack(
        [jnp.stack([front, -half]), jnp.stack([front, half]),
         jnp.stack([rear, -half]), jnp.stack([rear, half])]
    )  # fmt: skip
    front_share = -rear / v.wheelbase
    loads = (
        0.5 * v.mass * G * jnp.stack([front_share, front_share, 1 - front_share, 1 - front_share])
    )
    return positions, loads


def rotation(psi):
    """The matrix taking body axes to global ones at yaw psi."""
    c, s = jnp.cos(psi), jnp.sin(psi)
    return jnp.stack([jnp.stack([c, -s]), jnp.stack([s, c])])


def tyre_forces(v: Vehicle, psi, velocity, yaw_rate, slip_speed=0.05):
    """The tyres' side forces as a global force (2,), their yaw moment and their power (the
    rate of work on the vehicle, <= 0): Coulomb friction on each wheel's static load
    against its sideways velocity, smoothed below `slip_speed` (m/s) so that it is
    differentiable and does not chatter at rest."""
    positions, loads = wheels(v)
    R = rotation(psi)
    body_velocity = R.T @ velocity
    lateral = body_velocity[1] + yaw_rate * positions[:, 0]  # (4,) sideways speed of each wheel
    force_y = -v.tyre_friction * loads * lateral / jnp.sqrt(lateral**2 + slip_speed**2)
    force = R @ jnp.stack([jnp.zeros_like(psi), jnp.sum(force_y)])
    return force, jnp.sum(positions[:, 0] * force_y), jnp.sum(force_y * lateral)
