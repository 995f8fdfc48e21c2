"""Contact between the vehicle's periphery and the barrier, after BARRIER VII.

The barrier's face is a polyline (the rail's deformed nodes, or a wall's two ends) running
in +x. A periphery point P of the vehicle lies past it by delta = (P - R) . n, R the
polyline's point at P's abscissa and n its unit normal towards +y (the field side). The
point's crush spring (`vehicle.py`) keeps a plastic crush c: it pushes with
F = k (delta - c) where delta > c, at most its strength F_y (past which c grows to
delta - F_y / k), and not at all where delta <= c (unloaded or separated: c stays). The
vehicle point takes -F n and Coulomb friction mu F against its sliding along the face
(smoothed below `slip_speed`); the barrier takes the opposite, shared between the two
nodes of the segment in proportion to the point's place on it. Points beyond the
polyline's ends touch nothing.
"""

import jax.numpy as jnp


def face_contact(points, velocities, crush, stiffness, strength, nodes, node_velocities,
                 friction, slip_speed=0.05):  # fmt: skip
    """Contact forces of the periphery points (n, 2) moving at `velocities` (n, 2), with
    plastic crush `crush` (n,) and spring `stiffness`, `strength` (n,), on the polyline
    `nodes` (m, 2) moving at `node_velocities` (m, 2).

    Returns (force on each point (n, 2), force on each node (m, 2), new crush (n,), the
    friction's power (<= 0))."""
    xs = nodes[:, 0]
    segment = jnp.clip(jnp.searchsorted(xs, points[:, 0]) - 1, 0, xs.shape[0] - 2)
    a, b = nodes[segment], nodes[segment + 1]
    chord = b - a
    length = jnp.sqrt(jnp.sum(chord**2, -1))
    tangent = chord / length[:, None]
    normal = jnp.stack([-tangent[:, 1], tangent[:, 0]], -1)
    s = (points[:, 0] - a[:, 0]) / chord[:, 0]
    inside = (s >= 0.0) & (s <= 1.0)
    face = a + s[:, None] * chord
    delta = jnp.sum((points - face) * normal, -1)
    trial = stiffness * (delta - crush)
    force = jnp.where(inside & (trial > 0.0), jnp.minimum(trial, strength), 0.0)
    crush = jnp.where(inside & (trial > strength), delta - strength / stiffness, crush)
    weights = jnp.stack([1.0 - s, s], -1)
    face_velocity = (
        weights[:, :1] * node_velocities[segment] + weights[:, 1:] * node_velocities[segment + 1]
    )
    sliding = jnp.sum((velocities - face_velocity) * tangent, -1)
    drag = -friction * force * sliding / jnp.sqrt(sliding**2 + slip_speed**2)
    on_points = -force[:, None] * normal + drag[:, None] * tangent
    on_nodes = jnp.zeros_like(nodes)
    on_nodes = on_nodes.at[segment].add(-weights[:, :1] * on_points)
    on_nodes = on_nodes.at[segment + 1].add(-weights[:, 1:] * on_points)
    return on_points, on_nodes, crush, jnp.sum(drag * sliding)
