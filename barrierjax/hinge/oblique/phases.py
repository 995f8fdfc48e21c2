"""The stages of the step loop (crushing, contact, free), their vector field, and what
each accepted step records: the right hinge's trace for the memory, and the quantities
of the histories.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from ..._custom_types import Scalar
from ..._solve.recorded_rk import Recording
from .mechanism import Params, State, beam_acceleration, beam_powers, hinge_terms
from .memory import MEMORY, Past, slope_memory

CRUSHING, CONTACT, FREE = 1, 2, 3


class Breakpoints(eqx.Module):
    """Points of the right hinge's trace where Psi' jumps or has a kink, not yet reached
    by the load, in the order the load meets them: `position` and the indices of the
    recorded samples holding the left and right limits there. Two slots suffice (see
    `transition`); an empty slot is at +inf."""

    position: Float[Array, "2"]
    left: Int[Array, "2"]
    right: Int[Array, "2"]

    @classmethod
    def at_contact(cls, y: State, s_star, left):
        """Those pending when the contact starts: H(T*), where the right hinge stands (the
        crushing phase's last sample, recorded at `left`, is the left limit there, the
        contact's first the right one), and before it S*, where the trace starts (a
        kink of Psi'), if the load has not reached it."""
        hinge, zero = y.position + y.s1, 0 * left
        ahead = y.position < s_star
        return cls(
            jnp.where(ahead, jnp.stack([s_star, hinge]), jnp.stack([hinge, jnp.inf])),
            jnp.where(ahead, jnp.stack([zero, left]), jnp.stack([left, zero])),
            jnp.where(ahead, jnp.stack([zero, left + 1]), jnp.stack([left + 1, zero])),
        )

    def pop_and_push(self, position, left):
        """Drop the head and append a breakpoint created now: ahead of every other, since
        the hinge only advances."""
        filled = jnp.isfinite(self.position[1])
        pick = lambda old, new, empty: jnp.where(
            filled, jnp.stack([old[1], new]), jnp.stack([new, empty])
        )
        return Breakpoints(
            pick(self.position, position, jnp.inf),
            pick(self.left, left, 0),
            pick(self.right, left + 1, 0),
        )


class Stage(eqx.Module):
    """Where the solve is: the phase, the recorded samples the memory may read in this
    segment of it (`slope_memory`), the breakpoints ahead, and what the phases that
    follow need from those before."""

    phase: Int[Array, ""]
    first: Int[Array, ""]
    last: Int[Array, ""]
    breakpoints: Breakpoints
    log_rest: Scalar  # ln V0 where the decelerative phases hand over to `run_out_to_rest`
    t_star: Scalar
    separated: Bool[Array, ""]
    overtaken: Bool[Array, ""]
    sliding: Bool[Array, ""]  # the vehicle slides along the barrier (V_H > 0)


def _sliding_friction(stage: Stage, p: Params):
    """The friction coefficient acting on the vehicle: Coulomb's f while it slides; once it
    has stopped sliding (an event, `transition`), static friction holds it (the barrier
    takes no axial motion), with no tangential deceleration and no work."""
    return jnp.where(stage.sliding, p.friction, 0.0)


def beam_speed(y: State, stage: Stage):
    return jnp.where(stage.phase == CRUSHING, y.speed, jnp.exp(y.speed))


def _contact_force(y: State, v0, curvature, theta, stage: Stage, p: Params):
    """The force ratio in contact: (3.3.20)-(3.3.22) solved for it."""
    vh = y.vehicle_tangential
    s1, s2 = y.s1, y.s2
    numerator = (
        p.mu * (s1 * s2 + 3.0) / (2.0 * s1 * s2) + p.mu * vh * v0 / s1 - p.mu * vh**2 * curvature
    )
    # The friction term: the tangential deceleration f g / mu changes theta V_H.
    return numerator / (1.0 - _sliding_friction(stage, p) * theta + 4.0 * p.mu / (s1 + s2))


def force_from_rates(y: State, f: State):
    """The force ratio that gives the field f, from the first line of (3.3.16)."""
    return (f.speed + 1.5 / (y.s1 * y.s2) + 0.5) * (y.s1 + y.s2) / 4.0


def vector_field(y: State, stage: Stage, past: Past, p: Params) -> State:
    """The state's rate, (3.3.16), with the force of the phase: phi while the vehicle
    crushes, (3.3.22)'s in contact, none once it has left (the load then stands still
    and the memory is not read)."""
    vehicle = 0.0 if p.moving_load else 1.0
    crushing, free = stage.phase == CRUSHING, stage.phase == FREE
    v0 = beam_speed(y, stage)
    per_time = jnp.where(crushing, 1.0, v0)  # dT per unit of the phase's variable
    # (Unclamped: past the slide's stop, within the step that locates it, the field goes
    # on smoothly.)
    vh = y.vehicle_tangential
    psi, curvature = slope_memory(past, y.position, p.s_star)
    theta = jnp.where(free, 0.0, psi - y.rotation)
    force = jnp.where(
        crushing, p.phi, jnp.where(free, 0.0, _contact_force(y, v0, curvature, theta, stage, p))
    )
    load_speed = jnp.where(free, 0.0, vh)
    contact_velocity = v0 + theta * load_speed
    g1, g2 = hinge_terms(y.s1, y.s2, force)
    backing, hinge = beam_powers(v0, y.s1, y.s2)
    # V0 S' = g_i, against T or s.
    per_v0 = jnp.where(crushing, 1.0 / v0, 1.0)
    rates_in_time = State(
        speed=jnp.zeros_like(v0),
        s1=-1.5 * load_speed,
        s2=1.5 * load_speed,
        time=jnp.ones_like(v0),
        position=load_speed,
        rotation=v0 / y.s1,
        vehicle_normal=jnp.where(crushing, -vehicle * force / p.mu, 0.0),
        vehicle_tangential=-vehicle * _sliding_friction(stage, p) * force / p.mu,
        crush=jnp.where(crushing, vehicle * (y.vehicle_normal - contact_velocity), 0.0),
        contact_displacement=contact_velocity,
        backing_work=backing,
        hinge_work=hinge,
        friction_work=p.friction * force * vh,
        slope_work=force * theta * load_speed,
    )
    rates = jax.tree.map(lambda r: per_time * r, rates_in_time)
    return eqx.tree_at(
        lambda r: (r.speed, r.s1, r.s2),
        rates,
        (beam_acceleration(y.s1, y.s2, force), rates.s1 + per_v0 * g1, rates.s2 + per_v0 * g2),
    )


def at_rest(y: State, stage: Stage, past: Past, p: Params):
    """Where the hinges come to rest from `y` (the run-out's end, V0 = 0), and the slope
    under the load there: (S1, S2, theta), S1 = S2. In the decelerative phases the hinges
    move as dS_i/ds = g_i - 3/2 c V0 ((3.3.16) against s, dT/ds = V0), so that they settle
    where g1 = g2 = 0 at V0 = 0, some V0_end from where the solve left them. There g1 - g2
    = -(S1 - S2)(1/2 + 2 g / (S1 + S2)) vanishes only where they meet, and g1 = 0 with
    the contact's force at V0 = 0 ((3.3.22): A = 1 - f theta, B = mu V_H^2 Psi'(F)) is
    the cubic A S^3 + (3 mu - 2 B) S^2 - 3 A S - 3 mu = 0; in the free phase (g = 0),
    S = sqrt 3. Newton's method on the cubic from the mean of the two."""
    free = stage.phase == FREE
    psi, curvature = slope_memory(past, y.position, p.s_star)
    theta = jnp.where(free, 0.0, psi - y.rotation)
    a = 1.0 - _sliding_friction(stage, p) * theta
    b = p.mu * y.vehicle_tangential**2 * curvature
    s = 0.5 * (y.s1 + y.s2)
    for _ in range(3):
        cubic = ((a * s + 3.0 * p.mu - 2.0 * b) * s - 3.0 * a) * s - 3.0 * p.mu
        slope = (3.0 * a * s + 2.0 * (3.0 * p.mu - 2.0 * b)) * s - 3.0 * a
        s = s - cubic / slope
    s = jnp.where(free, jnp.sqrt(3.0), s)
    return s, s, theta


def trace_sample(phase, v0, f, rate, y, **extra):
    """One recorded step. The trace of the right hinge H = F + S1 carries Psi's data at H:
    Phi, dPhi/dH = Phi'/H' and d2Phi/dH2 = (Phi'' H' - Phi' H'')/H'^3 (primes: d/ds or
    d/dT; the ratios do not depend on which); zero while the hinge stands."""
    hinge_speed, hinge_acceleration = f.position + f.s1, rate.position + rate.s1
    moving = hinge_speed > 0.0
    speed = jnp.where(moving, hinge_speed, 1.0)
    curvature = jnp.where(moving, f.rotation / speed, 0.0)
    curvature_rate = jnp.where(
        moving, (rate.rotation * speed - f.rotation * hinge_acceleration) / speed**3, 0.0
    )
    return dict(
        hinge=y.position + y.s1,
        rotation=y.rotation,
        curvature=curvature,
        curvature_rate=curvature_rate,
        phase=phase,
        time=y.time,
        v0=v0,
        s1=y.s1,
        s2=y.s2,
        position=y.position,
        vehicle_tangential=y.vehicle_tangential,
        crush=y.crush,
        contact_displacement=y.contact_displacement,
        backing_work=y.backing_work,
        hinge_work=y.hinge_work,
        friction_work=y.friction_work,
        slope_work=y.slope_work,
        **extra,
    )


def slope_under_load(y: State, p: Params, past: Past):
    """theta, the slope under the load (3.3.4)-(3.3.6), read from the memory: where V0 is
    small, the field's V0 (V0 + theta V_H) over V0 would amplify any error in it."""
    return slope_memory(past, y.position, p.s_star)[0] - y.rotation


def record(y: State, f: State, rate: State, stage: Stage, past: Past, p: Params):
    """The sample recorded after a step: `trace_sample`'s, with the phase's vehicle velocity,
    force and slope."""
    v0 = beam_speed(y, stage)
    crushing, contact = stage.phase == CRUSHING, stage.phase == CONTACT
    force = jnp.where(crushing, p.phi, jnp.where(contact, force_from_rates(y, f), 0.0))
    theta = jnp.where(crushing | contact, slope_under_load(y, p, past), 0.0)
    # In contact the vehicle moves with the load point: V0 + theta V_H.
    vehicle_normal = jnp.where(contact, v0 + theta * y.vehicle_tangential, y.vehicle_normal)
    return trace_sample(
        jnp.asarray(stage.phase, v0.dtype),
        v0,
        f,
        rate,
        y,
        vehicle_normal=vehicle_normal,
        force=force,
        slope=theta,
    )


# What the recording keeps besides the right hinge's trace (`memory.MEMORY`): the motion
# for the displacement field (max_deflection), and with `history` the rest of each sample.
MOTION = ("time", "v0", "s1", "s2", "position")
_HISTORY = (
    "phase",
    "vehicle_normal",
    "vehicle_tangential",
    "force",
    "slope",
    "crush",
    "contact_displacement",
    "backing_work",
    "hinge_work",
    "friction_work",
    "slope_work",
)


def empty_recording(capacity, dtype, history):
    names = MEMORY + MOTION + (_HISTORY if history else ())
    return Recording.empty(names, capacity, dtype)
