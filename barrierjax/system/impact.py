"""`system_impact`: a vehicle (`vehicle.py`) striking a guardrail on posts or a rigid wall
(`barrier.py`), integrated by explicit central differences in one `lax.scan`.

The vehicle's c.g. starts at `impact_point` along the rail, moving at `speed` and `angle` to
it, placed so that its left front corner touches the face. Positions are at the steps,
velocities at the half steps (leapfrog): the rail's nodes and the vehicle's c.g. and yaw
alike. At each step the rail's internal forces (the chapter 4 element, its sections stepped
from the last step), the posts' and anchors', the contact's (`contact.py`) and the tyres'
give the accelerations; friction (contact and tyres) reads the last half step's
velocities.

The energy audit: the vehicle's initial kinetic energy against the kinetic energies of
vehicle and rail (at the steps, from the mean of the half steps' velocities), the rail's
internal work and the posts' and anchors' (each the trapezoidal integral of its force over
its displacement), the contact's work (crush and friction: the power of the contact
forces on both bodies) and the tyres'. What it leaves is the scheme's error.
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import in_range, positive
from ..beam.model import init_sections, internal_forces
from .barrier import Guardrail, RigidWall, anchor_forces, lumped_mass, post_forces, stable_step
from .contact import face_contact
from .vehicle import Vehicle, periphery, rotation, tyre_forces


class SystemHistory(eqx.Module):
    """Saved every `save_every` steps (the initial state first)."""

    time: jnp.ndarray  # (n,)
    position: jnp.ndarray  # (n, 2) the vehicle's c.g.
    yaw: jnp.ndarray  # (n,)
    velocity: jnp.ndarray  # (n, 2)
    yaw_rate: jnp.ndarray  # (n,)
    acceleration: jnp.ndarray  # (n, 2) the c.g.'s, in the vehicle's axes (x forward, y left)
    rail_deflection: jnp.ndarray  # (n, n_nodes) lateral displacement (towards the field side)
    post_force: jnp.ndarray  # (n, n_posts) lateral
    contact_force: jnp.ndarray  # (n,) total normal force between vehicle and barrier
    energy_error: jnp.ndarray  # (n,) the audit's remainder over the initial kinetic energy


class SystemResult(eqx.Module):
    history: SystemHistory
    kinetic_energy: jnp.ndarray  # initial, J
    energies: dict  # final works (J): rail, posts, anchors, contact (crush and its friction,
    # contact_friction), tyres, and the final kinetic energy
    exit_speed: jnp.ndarray  # m/s, at the end
    exit_angle_deg: jnp.ndarray  # of the c.g.'s velocity to the rail, towards the road < 0
    dynamic_deflection: jnp.ndarray  # m, the rail's largest lateral displacement
    working_width: jnp.ndarray  # m, from the rail's face: rail, or vehicle, whichever is further
    failed_posts: jnp.ndarray  # (n_posts,) bool


def _initial_pose(v: Vehicle, impact_point, angle):
    """The c.g. and yaw at which the left front corner touches the face y = 0 at x =
    impact_point, heading at `angle` towards it."""
    corner = jnp.stack([v.front_to_cg, 0.5 * v.width])
    cg = jnp.stack([impact_point, 0.0]) - rotation(angle) @ corner
    return cg, angle


def system_impact(
    vehicle: Vehicle,
    barrier: Guardrail | RigidWall,
    *,
    speed,
    angle_deg,
    impact_point,
    duration,
    dt=None,
    save_every: int = 20,
    friction=0.3,
) -> SystemResult:
    """The vehicle at `speed` (m/s) and `angle_deg` to the barrier, its left front corner on
    the face at `impact_point` (m along it), for `duration` (s) in steps of `dt` (default:
    the guardrail's stable step, `barrier.stable_step`, or 1e-4 s for a wall)."""
    speed = positive("speed", speed)
    angle = jnp.radians(in_range("angle_deg", angle_deg, 0.0, 90.0))
    duration = positive("duration", duration)
    if dt is None:
        dt = 1e-4 if isinstance(barrier, RigidWall) else stable_step(barrier, _bound(vehicle))
    dt = float(dt)
    if isinstance(barrier, Guardrail):
        length = float(barrier.rail.coords[-1, 0])
        if not isinstance(impact_point, jax.core.Tracer) and not 0 < float(impact_point) < length:
            raise ValueError(
                f"impact_point must lie on the rail, in (0, {length:g}) m; got {impact_point!r}"
            )
    n_steps = int(np.ceil(float(duration) / dt))
    save_every = int(save_every)
    n_saved = n_steps // save_every
    return _integrate(vehicle, barrier, speed, angle, impact_point, jnp.asarray(friction),
                      dt=dt, n_saved=n_saved, save_every=save_every)  # fmt: skip


def _bound(v: Vehicle):
    """A bound on the crush springs' stiffness on one rail node (for the stable step)."""
    return float(v.crush_stiffness) * float(v.length)


@functools.partial(jax.jit, static_argnames=("dt", "n_saved", "save_every"))
def _integrate(vehicle, barrier, speed, angle, impact_point, friction, *, dt, n_saved, save_every):
    body_points, share = periphery(vehicle)
    stiffness = vehicle.crush_stiffness * share
    strength = vehicle.crush_strength * share
    rail = barrier if isinstance(barrier, Guardrail) else None
    cg, psi = _initial_pose(vehicle, impact_point, angle)
    velocity = speed * jnp.stack([jnp.cos(angle), jnp.sin(angle)])
    kinetic0 = 0.5 * vehicle.mass * speed**2

    if rail is not None:
        mass = lumped_mass(rail)
        stress, state = init_sections(rail.rail)
        n_dofs, n_posts = mass.shape[0], len(rail.post_nodes)
        rail_nodes = rail.rail.coords
    else:
        mass = jnp.ones(6)
        stress = state = None
        n_dofs, n_posts = 6, 0
        rail_nodes = jnp.stack([jnp.stack([barrier.start, 0.0]), jnp.stack([barrier.end, 0.0])])
    zero_dofs = jnp.zeros(n_dofs)
    zero = jnp.zeros(())

    def forces(carry):
        """Everything that acts at the current step, and the rail's stepped sections."""
        (X, psi, V, w, u, u_old, v_rail, stress, state, crush, plastic, failed) = carry[:12]
        R = rotation(psi)
        r = body_points @ R.T
        points = X + r
        point_velocity = V + w * jnp.stack([-r[:, 1], r[:, 0]], -1)
        if rail is not None:
            f_int, (stress, state, *_) = internal_forces(rail.rail, u, u_old, stress, state, dt)
            f_post, plastic, failed = post_forces(rail, u, plastic, failed)
            f_anchor = anchor_forces(rail, u)
            nodes = rail_nodes + u.reshape(-1, 3)[:, :2]
            node_velocity = v_rail.reshape(-1, 3)[:, :2]
        else:
            f_int = f_post = f_anchor = zero_dofs
            nodes, node_velocity = rail_nodes, jnp.zeros_like(rail_nodes)
        on_points, on_nodes, crush, friction_power, _ = face_contact(
            points, point_velocity, crush, stiffness, strength, nodes, node_velocity, friction
        )
        f_contact = jnp.concatenate([on_nodes, jnp.zeros((on_nodes.shape[0], 1))], -1).ravel()
        if rail is None:
            f_contact = zero_dofs
        tyre_force, tyre_moment, _ = tyre_forces(vehicle, psi, V, w)
        force = jnp.sum(on_points, 0) + tyre_force
        moment = jnp.sum(r[:, 0] * on_points[:, 1] - r[:, 1] * on_points[:, 0]) + tyre_moment
        parts = (f_int, f_post, f_anchor, f_contact, on_points, friction_power, tyre_force,
                 tyre_moment)  # fmt: skip
        return force, moment, parts, (stress, state, crush, plastic, failed)

    def step(carry, _):
        X, psi, V, w, u, u_old, v_rail = carry[:4] + carry[4:7]
        works, last = carry[12], carry[13]
        force, moment, parts, (stress, state, crush, plastic, failed) = forces(carry)
        f_int, f_post, f_anchor, f_contact, on_points, friction_power, tyre_f, tyre_m = parts
        a_rail = (f_contact - f_int - f_post - f_anchor) / mass
        a_vehicle, alpha = force / vehicle.mass, moment / vehicle.yaw_inertia
        V_next, w_next = V + dt * a_vehicle, w + dt * alpha
        v_rail_next = v_rail + dt * a_rail
        # Velocities at this step: the mean of the half steps around it.
        V_mid, w_mid, v_mid = 0.5 * (V + V_next), 0.5 * (w + w_next), 0.5 * (v_rail + v_rail_next)
        R = rotation(psi)
        r = body_points @ R.T
        points_mid = V_mid + w_mid * jnp.stack([-r[:, 1], r[:, 0]], -1)
        contact_power = jnp.sum(on_points * points_mid) + jnp.dot(f_contact, v_mid)
        tyre_power = jnp.dot(tyre_f, V_mid) + tyre_m * w_mid
        du = u - u_old
        f_last = last
        trapezoid = lambda new, old: 0.5 * jnp.dot(new + old, du)
        works = works + jnp.stack([
            trapezoid(f_int, f_last[0]), trapezoid(f_post, f_last[1]),
            trapezoid(f_anchor, f_last[2]), -dt * contact_power, -dt * tyre_power,
            -dt * friction_power,
        ])  # fmt: skip
        kinetic = 0.5 * vehicle.mass * jnp.sum(V_mid**2) + 0.5 * vehicle.yaw_inertia * w_mid**2
        if rail is not None:
            kinetic = kinetic + 0.5 * jnp.sum(mass * v_mid**2)
        error = (kinetic0 - kinetic - jnp.sum(works[:5])) / kinetic0  # (friction: in contact)
        out = (X, psi, V_mid, w_mid, R.T @ a_vehicle, u[1::3], _lateral(f_post, rail),
               -jnp.sum(on_points @ jnp.asarray([0.0, 1.0])), error, kinetic)  # fmt: skip
        carry = (
            X + dt * V_next, psi + dt * w_next, V_next, w_next,
            u + dt * v_rail_next, u, v_rail_next, stress, state, crush, plastic, failed,
            works, (f_int, f_post, f_anchor),
        )  # fmt: skip
        return carry, out

    def saved(carry, _):
        carry, outs = jax.lax.scan(step, carry, None, length=save_every)
        return carry, jax.tree.map(lambda x: x[0], outs)

    crush0 = jnp.zeros(body_points.shape[0])
    plastic0 = jnp.zeros((n_posts, 2))
    failed0 = jnp.zeros(n_posts, bool)
    init = (cg, psi, velocity, zero, zero_dofs, zero_dofs, zero_dofs, stress, state, crush0,
            plastic0, failed0, jnp.zeros(6), (zero_dofs, zero_dofs, zero_dofs))  # fmt: skip
    final, outs = jax.lax.scan(saved, init, None, length=n_saved)
    X, psi, V, w, acc, deflection, post_f, contact_f, error, kinetic = outs
    times = jnp.arange(n_saved) * (save_every * dt)
    history = SystemHistory(times, X, psi, V, w, acc, deflection, post_f, contact_f, error)
    works = final[12]
    names = ("rail", "posts", "anchors", "contact", "tyres", "contact_friction")
    energies = {name: works[k] for k, name in enumerate(names)} | {"kinetic": kinetic[-1]}
    V_end = V[-1]
    exit_speed = jnp.sqrt(jnp.sum(V_end**2))
    exit_angle = jnp.degrees(jnp.arctan2(V_end[1], V_end[0]))
    dynamic = jnp.max(deflection) if rail is not None else zero
    body_points_y = jax.vmap(lambda x, p: (x + body_points @ rotation(p).T)[:, 1])(X, psi)
    working = jnp.maximum(dynamic, jnp.max(body_points_y))
    return SystemResult(history, kinetic0, energies, exit_speed, exit_angle, dynamic, working,
                        final[11])  # fmt: skip


def _lateral(f_post, rail):
    """The posts' lateral forces from the assembled post forces."""
    if rail is None:
        return jnp.zeros(0)
    return f_post[3 * np.asarray(rail.post_nodes) + 1]
