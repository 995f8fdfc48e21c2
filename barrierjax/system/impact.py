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
from ..compilation_cache import stored_program
from .barrier import Guardrail, RigidWall, anchor_forces, lumped_mass, post_forces, stable_step
from .contact import face_contact
from .vehicle import Vehicle, contact_stiffness_bound, periphery, rotation, tyre_forces


class SystemHistory(eqx.Module):
    """Saved every `save_every` steps (the initial state first)."""

    time: jnp.ndarray  # (n,)
    position: jnp.ndarray  # (n, 2) the vehicle's c.g.
    yaw: jnp.ndarray  # (n,)
    velocity: jnp.ndarray  # (n, 2)
    yaw_rate: jnp.ndarray  # (n,)
    acceleration: jnp.ndarray  # (n, 2) the c.g.'s in the vehicle's axes (x forward, y left),
    # the mean over the interval that starts at the sample
    contact_on_rail: jnp.ndarray  # (n, n_nodes, 2) the contact's force on each rail node (x,
    # y; the mean over the interval that starts at the sample: its impulse kept)
    rail_deflection: jnp.ndarray  # (n, n_nodes) lateral displacement (towards the field side)
    rail_tension: jnp.ndarray  # (n, n_elements) each element's axial force (N; tension > 0)
    post_force: jnp.ndarray  # (n, n_posts) lateral
    contact_force: jnp.ndarray  # (n,) total normal force between vehicle and barrier
    energy_error: jnp.ndarray  # (n,) the audit's remainder over the initial kinetic energy


class SystemResult(eqx.Module):
    history: SystemHistory
    kinetic_energy: jnp.ndarray  # initial, J
    energies: dict  # final works (J): rail, posts, anchors, contact (crush and its friction,
    # contact_friction), tyres, and the final kinetic energy
    exit_speed: jnp.ndarray  # m/s, at the loss of contact (or the end, still in contact)
    exit_angle_deg: jnp.ndarray  # of the c.g.'s velocity to the rail there; towards the road < 0
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
    the guardrail's stable step, `barrier.stable_step`, or 1e-4 s for a wall). The history
    keeps a sample every `save_every` steps (the vehicle's acceleration and the contact's
    forces on the rail averaged over them); a reverse-mode gradient keeps the state there
    and computes the steps between again, so that its memory falls as `save_every` grows."""
    speed = positive("speed", speed)
    angle = jnp.radians(in_range("angle_deg", angle_deg, 0.0, 90.0))
    if _concrete_guardrail(vehicle, barrier):
        length = float(np.asarray(barrier.rail.coords)[-1, 0])
        if not isinstance(impact_point, jax.core.Tracer) and not 0 < float(impact_point) < length:
            raise ValueError(
                f"impact_point must lie on the rail, in (0, {length:g}) m; got {impact_point!r}"
            )
    dt, times = time_grid(vehicle, barrier, duration, dt, save_every)
    arrays = (speed, angle, *map(jnp.asarray, (impact_point, friction, dt)))
    return _integrate(vehicle, barrier, *arrays, n_saved=len(times), save_every=int(save_every))


def _concrete_guardrail(vehicle, barrier) -> bool:
    """A guardrail whose data (and the vehicle's) are concrete: the checks that need numbers
    can run."""
    return isinstance(barrier, Guardrail) and not any(
        isinstance(leaf, jax.core.Tracer) for leaf in jax.tree.leaves((barrier, vehicle))
    )


def time_grid(vehicle: Vehicle, barrier, duration, dt=None, save_every: int = 20):
    """The step of `system_impact` (checked against the stable step where the guardrail is
    concrete) and the times of its saved samples (numpy: concrete, for
    `barrierjax.assess` under a caller's jit or vmap)."""
    if not (isinstance(duration, int | float) and 0 < duration < np.inf):
        raise ValueError(f"duration must be a positive number of seconds; got {duration!r}")
    if dt is None:
        dt = (
            1e-4
            if isinstance(barrier, RigidWall)
            else stable_step(barrier, contact_stiffness_bound(vehicle))
        )
    elif _concrete_guardrail(vehicle, barrier) and float(dt) > (
        largest := stable_step(barrier, contact_stiffness_bound(vehicle), 1.0)
    ):
        raise ValueError(
            f"dt must be at most the central differences' stable step, {largest:.3g} s for "
            f"this rail; got {dt!r}"
        )
    dt, save_every = float(dt), int(save_every)
    n_saved = int(np.ceil(float(duration) / dt)) // save_every
    return dt, np.arange(n_saved) * (save_every * dt)


class _Loads(eqx.Module):
    """What acts at a step: on the rail's dofs, and the vehicle's resultants."""

    internal: jnp.ndarray
    posts: jnp.ndarray
    anchors: jnp.ndarray
    contact: jnp.ndarray  # the contact's forces on the rail's dofs
    contact_force: jnp.ndarray  # ... and their resultant on the vehicle (2,)
    contact_moment: jnp.ndarray
    tyre_force: jnp.ndarray
    tyre_moment: jnp.ndarray


class _State(eqx.Module):
    """Positions at the step and the one before, velocities at the half step before."""

    X: jnp.ndarray
    psi: jnp.ndarray
    V: jnp.ndarray
    w: jnp.ndarray
    X_old: jnp.ndarray
    psi_old: jnp.ndarray
    u: jnp.ndarray
    u_old: jnp.ndarray
    v: jnp.ndarray
    sections: tuple
    crush: jnp.ndarray
    plastic: jnp.ndarray
    failed: jnp.ndarray
    works: jnp.ndarray  # rail, posts, anchors, contact, tyres, contact friction (J)
    last: _Loads


# The step is an argument, not a compile-time constant: barriers of one mesh whose stable
# steps differ (another section, other posts) run one program where their saved samples
# are as many.
@stored_program
@functools.partial(jax.jit, static_argnames=("n_saved", "save_every"))
def _integrate(vehicle, barrier, speed, angle, impact_point, friction, dt, *, n_saved, save_every):
    body_points, share = periphery(vehicle)
    stiffness = vehicle.crush_stiffness * share
    strength = vehicle.crush_strength * share
    rail = barrier if isinstance(barrier, Guardrail) else None
    kinetic0 = 0.5 * vehicle.mass * speed**2
    if rail is not None:
        mass = lumped_mass(rail)
        sections = init_sections(rail.rail)
        n_posts = len(rail.post_nodes)
        rail_nodes = rail.rail.coords
    else:  # a wall: a rail of two immovable nodes
        mass, sections, n_posts = jnp.full(6, jnp.inf), (), 0
        rail_nodes = jnp.stack([jnp.stack([barrier.start, 0.0]), jnp.stack([barrier.end, 0.0])])
    zero_dofs = jnp.zeros(mass.shape[0])

    def loads(s: _State):
        """Everything that acts at the step, and the stepped state of rail, posts and crush."""
        r = body_points @ rotation(s.psi).T
        point_velocity = s.V + s.w * jnp.stack([-r[:, 1], r[:, 0]], -1)
        if rail is not None:
            f_int, (stress, state, axial, *_) = internal_forces(
                rail.rail, s.u, s.u_old, *s.sections, dt
            )
            tension = jnp.mean(axial, -1)
            sections = (stress, state)
            f_post, plastic, failed = post_forces(rail, s.u, s.plastic, s.failed)
            f_anchor = anchor_forces(rail, s.u)
        else:
            f_int = f_post = f_anchor = zero_dofs
            tension = jnp.zeros(0)
            sections, plastic, failed = s.sections, s.plastic, s.failed
        nodes = rail_nodes + s.u.reshape(-1, 3)[:, :2]
        on_points, on_nodes, crush, friction_power = face_contact(
            s.X + r, point_velocity, s.crush, stiffness, strength, nodes,
            s.v.reshape(-1, 3)[:, :2], friction,
        )  # fmt: skip
        on_rail = jnp.concatenate([on_nodes, jnp.zeros((on_nodes.shape[0], 1))], -1).ravel()
        tyre_force, tyre_moment, _ = tyre_forces(vehicle, s.psi, s.V, s.w)
        contact_moment = jnp.sum(r[:, 0] * on_points[:, 1] - r[:, 1] * on_points[:, 0])
        acting = _Loads(f_int, f_post, f_anchor, on_rail, jnp.sum(on_points, 0),
                        contact_moment, tyre_force, tyre_moment)  # fmt: skip
        return (
            acting,
            sections,
            crush,
            plastic,
            failed,
            friction_power,
            on_points,
            on_nodes,
            tension,
        )

    def step(s: _State, _):
        now, sections, crush, plastic, failed, friction_power, on_points, on_nodes, tension = loads(
            s
        )
        a_rail = (now.contact - now.internal - now.posts - now.anchors) / mass
        force = now.contact_force + now.tyre_force
        moment = now.contact_moment + now.tyre_moment
        V = s.V + dt * force / vehicle.mass
        w = s.w + dt * moment / vehicle.yaw_inertia
        v = s.v + dt * a_rail
        # The works of the step before to this one: trapezoids over the displacements.
        du, dX, dpsi = s.u - s.u_old, s.X - s.X_old, s.psi - s.psi_old
        on_rail = lambda f, f0: 0.5 * jnp.dot(f + f0, du)
        on_vehicle = lambda F, F0, M, M0: 0.5 * (jnp.dot(F + F0, dX) + (M + M0) * dpsi)
        last = s.last
        works = s.works + jnp.stack([
            on_rail(now.internal, last.internal),
            on_rail(now.posts, last.posts),
            on_rail(now.anchors, last.anchors),
            -on_rail(now.contact, last.contact) - on_vehicle(
                now.contact_force, last.contact_force, now.contact_moment, last.contact_moment),
            -on_vehicle(now.tyre_force, last.tyre_force, now.tyre_moment, last.tyre_moment),
            -dt * friction_power,
        ])  # fmt: skip
        # The kinetic energies at the step, from the mean of the half steps' velocities.
        V_mid, w_mid, v_mid = 0.5 * (s.V + V), 0.5 * (s.w + w), 0.5 * (s.v + v)
        kinetic = 0.5 * vehicle.mass * jnp.sum(V_mid**2) + 0.5 * vehicle.yaw_inertia * w_mid**2
        if rail is not None:
            kinetic = kinetic + 0.5 * jnp.sum(mass * v_mid**2)
        error = (kinetic0 - kinetic - jnp.sum(works[:5])) / kinetic0
        acceleration = rotation(s.psi).T @ (force / vehicle.mass)
        out = (s.X, s.psi, V_mid, w_mid, acceleration, on_nodes, s.u[1::3], tension,
               _lateral(now.posts, rail),
               -jnp.sum(on_points[:, 1]), error, kinetic)  # fmt: skip
        u_next = s.u + dt * v if rail is not None else s.u
        s = _State(s.X + dt * V, s.psi + dt * w, V, w, s.X, s.psi, u_next, s.u, v, sections,
                   crush, plastic, failed, works, now)  # fmt: skip
        return s, out

    # Reverse mode keeps the state at each saved sample and computes each interval's steps
    # again, where it kept every step's intermediates: a gradient of MASH 3-11 (0.6 s,
    # 15,899 steps) held 2.5 GB, now 0.4 GB, and runs faster (benchmarks/README.md, "The
    # first answer"). The forward pass is the same.
    @functools.partial(jax.checkpoint, prevent_cse=False)
    def saved(s, _):
        s, outs = jax.lax.scan(step, s, None, length=save_every)
        first = jax.tree.map(lambda x: x[0], outs)
        # The acceleration as its mean over the interval (a box filter: no aliasing of the
        # contact's chatter into the occupant-risk metrics).
        return s, (*first[:4], jnp.mean(outs[4], 0), jnp.mean(outs[5], 0), *first[6:])

    cg, psi = _initial_pose(vehicle, impact_point, angle)
    velocity = speed * jnp.stack([jnp.cos(angle), jnp.sin(angle)])
    zero, zero2 = jnp.zeros(()), jnp.zeros(2)
    nothing = _Loads(zero_dofs, zero_dofs, zero_dofs, zero_dofs, zero2, zero, zero2, zero)
    start = _State(cg, psi, velocity, zero, cg, psi, zero_dofs, zero_dofs, zero_dofs, sections,
                   jnp.zeros(body_points.shape[0]), jnp.zeros((n_posts, 2)),
                   jnp.zeros(n_posts, bool), jnp.zeros(6), nothing)  # fmt: skip
    final, outs = jax.lax.scan(saved, start, None, length=n_saved)
    X, psi, V, w, acc, on_rail, deflection, tension, post_f, contact_f, error, kinetic = outs
    times = jnp.arange(n_saved, dtype=kinetic0.dtype) * (save_every * dt)
    history = SystemHistory(times, X, psi, V, w, acc, on_rail, deflection, tension, post_f, contact_f,
                            error)  # fmt: skip
    names = ("rail", "posts", "anchors", "contact", "tyres", "contact_friction")
    energies = {name: final.works[k] for k, name in enumerate(names)} | {"kinetic": kinetic[-1]}
    # At the loss of contact: the first sample after the last one in contact (the last
    # sample where the vehicle is still in contact at the end).
    index = jnp.arange(n_saved)
    lost = jnp.minimum(jnp.max(jnp.where(contact_f > 0.0, index, -1)) + 1, n_saved - 1)
    exit_speed = jnp.sqrt(jnp.sum(V[lost] ** 2))
    exit_angle = jnp.degrees(jnp.arctan2(V[lost, 1], V[lost, 0]))
    dynamic = jnp.max(deflection) if rail is not None else zero
    outline_y = jax.vmap(lambda x, p: (x + body_points @ rotation(p).T)[:, 1])(X, psi)
    working = jnp.maximum(dynamic, jnp.max(outline_y))
    return SystemResult(history, kinetic0, energies, exit_speed, exit_angle, dynamic, working,
                        final.failed)  # fmt: skip


def _lateral(f_post, rail):
    """The posts' lateral forces from the assembled post forces."""
    if rail is None:
        return jnp.zeros(0)
    return f_post[3 * np.asarray(rail.post_nodes) + 1]
