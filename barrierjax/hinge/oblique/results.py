"""The results of an oblique impact: the state at rest, the run-out to it, and the
histories.

`max_deflection` integrates the velocity field over the recorded steps by the trapezoidal
rule (error O(step^2): about 2e-3 relative at rtol 1e-6) between the load's first and last
positions, where the peak lies, on grids zooming in on it (`max_deflection`: within 4e-6
of the peak on 16385 points over every plastic zone; a single grid of 129 points over
every plastic zone was up to 1.5e-2 off). That W is piecewise linear in x, its peak at one
of the load's recorded positions, where both grids read it low: by up to 2.3e-4 of it on
4,096 scenarios of benchmarks/oblique_impact.py's box, inside the rule's own error.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from ..._custom_types import Scalar
from ..._solve.recorded_rk import Recording, Solution
from ..response import ImpactHistory, ImpactResult, exit_angle_deg
from .mechanism import Params, State, beam_kinetic_energy, velocity_field
from .memory import read_past
from .phases import MOTION, Stage, at_rest, record, vector_field
from .transitions import Outcome, outcome_of


class ObliqueImpactHistory(ImpactHistory):
    """Time histories of an oblique impact, dimensionless, under the names of
    `barrierjax.hinge.response.HISTORY_UNITS`: `n_history` samples equally spaced in
    time from contact to the last step (linear between the solver's accepted steps, so a
    sum of terms that balances at every step balances at every sample), with
    `contact_position` (the load's position F along the barrier) and `slope` (the
    barrier's slope under it). `hinge_position` is the distance from the load to the
    hinge ahead of it (S1), `rear_hinge_position` to the one behind (S2);
    `deflected_shape[k, j]` is W(x[j], time[k]), x along the barrier from the impact
    point on `N_X` points spanning every plastic zone."""

    contact_position: Scalar
    slope: Scalar


class ObliqueImpact(ImpactResult):
    """Dimensionless response to an oblique impact (report 3.3), under the names of
    `barrierjax.hinge.response.RESULT_UNITS`; `string_work` is zero (no axial force).
    Its own: `t_star` (end of the crushing phase), `exit_normal_speed` and
    `exit_tangential_speed` (the exit velocity's components; the angle is 0, with zero
    derivatives, for a vehicle that ends at rest against the barrier, friction having
    stopped its slide before the barrier stopped), `separated` (1 where the vehicle left
    the barrier before it came to rest) and `steps` (the solver's accepted steps)."""

    t_star: Scalar
    exit_normal_speed: Scalar
    exit_tangential_speed: Scalar
    separated: Scalar
    steps: Scalar
    history: ObliqueImpactHistory | None


class MovingLoad(eqx.Module):
    """The moving load's state at `t_end` (S1, S2, V0), the solver's accepted steps, and
    its history (as `ObliqueImpactHistory`, without a vehicle)."""

    s1: Scalar
    s2: Scalar
    v0: Scalar
    steps: Scalar
    history: ObliqueImpactHistory


# At rest, ln V0 is this far below the solve's end: V0 e^-60, 1e-26 of it, stands for 0
# (a V0 of 0 itself would put 1/0 into the field's unused branches and their derivatives).
_FAR_BELOW = 60.0


def run_out_to_rest(y: State, f: State, stage: Stage, recording: Recording, p: Params):
    """The state at rest (V0 = 0, `_FAR_BELOW`) and the memory's window there, from the
    solve's last state `y` and its rate `f`, at V0_end = V0* rtol^1/2 e^-1
    (`transitions.REST_SPEED`, `REST_MARGIN`): the deceleration held at its last value, V0
    falls linearly to zero over tau = V0_end / |V0'|. Every quantity moves at its rate in
    T at the end (f over V0_end): those proportional to V0 (the rotation, the backing and
    hinge work) at half of it, the beam's displacement under the load at V0/2 + theta V_H;
    the slide, if friction stops it within tau, until it stops, the friction taking the
    vehicle's tangential energy. Error O(V0_end^2), relative O(rtol e^-2). The hinges go to where
    they rest, and the exit velocity in contact, theta V_H (`transition`), is read again
    there (`phases.at_rest`)."""
    v0 = jnp.exp(y.speed)
    tau = v0 / jnp.abs(f.speed)
    rate = jax.tree.map(lambda r: r / v0, f)  # in T: the phase's variable has dT = V0 of it
    # (Only friction slows the slide; `f`, interpolated, need not hold its zeros exactly.)
    slowing = stage.sliding & (p.friction > 0.0) & (rate.vehicle_tangential < 0.0)
    deceleration = jnp.where(slowing, -rate.vehicle_tangential, 0.0)
    stop = y.vehicle_tangential / jnp.where(slowing, deceleration, 1.0)
    slide = jnp.where(slowing, jnp.minimum(tau, stop), tau)
    vh = y.vehicle_tangential - deceleration * slide
    moved = eqx.tree_at(
        lambda s: (
            s.speed,
            s.time,
            s.position,
            s.rotation,
            s.vehicle_tangential,
            s.contact_displacement,
            s.backing_work,
            s.hinge_work,
            s.friction_work,
            s.slope_work,
        ),
        y,
        (
            y.speed - _FAR_BELOW,
            y.time + tau,
            y.position + 0.5 * (y.vehicle_tangential + vh) * slide,
            y.rotation + 0.5 * rate.rotation * tau,
            vh,
            y.contact_displacement + (rate.contact_displacement - 0.5 * v0) * tau,
            y.backing_work + 0.5 * rate.backing_work * tau,
            y.hinge_work + 0.5 * rate.hinge_work * tau,
            y.friction_work
            + 0.5 * p.mu * (y.vehicle_tangential - vh) * (y.vehicle_tangential + vh),
            y.slope_work + rate.slope_work * slide,
        ),
    )
    past = read_past(moved, None, 0.0, stage, recording)
    s1, s2, theta = at_rest(moved, stage, past, p)
    exit_normal = jnp.where(stage.separated, y.vehicle_normal, theta * vh)
    rest = eqx.tree_at(lambda s: (s.s1, s.s2, s.vehicle_normal), moved, (s1, s2, exit_normal))
    return rest, past


def _ending_at_rest(recording: Recording, y: State, stage: Stage, past, p: Params):
    """The recorded samples, and after them `y`, the state at rest, as a sample of its
    own: the histories end where the results are. (The field stands in for its own
    derivative, which only the hinge's trace reads, and nothing reads it past the end.)"""
    f = vector_field(y, stage, past, p)
    sample = record(y, f, f, stage, past, p)
    count = recording.count
    samples = {name: v.at[count].set(sample[name]) for name, v in recording.samples.items()}
    return samples, count + 1


def _motion(samples, k):
    return tuple(samples[name][k] for name in ("v0", "s1", "s2", "position"))


def displacement_field(samples, count, x):
    """W(x, T_k) for every recorded T_k: the velocity field integrated over the recorded
    steps by the trapezoidal rule (error O(step^2) where a hinge crosses x)."""
    v = velocity_field(*(m[:, None] for m in _motion(samples, slice(None))), x[None, :])
    recorded = jnp.arange(1, v.shape[0], dtype=count.dtype)[:, None] < count
    dt = jnp.where(recorded, jnp.diff(samples["time"])[:, None], 0.0)
    increments = 0.5 * (v[1:] + v[:-1]) * dt
    return jnp.concatenate([jnp.zeros_like(v[:1]), jnp.cumsum(increments, axis=0)])


def _final_displacement(recording: Recording, x):
    """W(x) at the last recorded time, as `displacement_field` but over the recorded
    steps alone (a few dozen, where the buffer holds thousands), `_BLOCK` steps per read:
    under `vmap`, a loop of one step per iteration cost more than the solve's steps."""

    def block(b, w):
        first = b * _BLOCK
        rows = recording.rows(first, _BLOCK + 1, MOTION)
        t = rows.pop("time")
        v = velocity_field(**{k: r[:, None] for k, r in rows.items()}, x=x[None, :])
        step = first + jnp.arange(_BLOCK, dtype=first.dtype)
        # (Rows past the recorded ones may hold a rejected step's sample, even a NaN.)
        increments = 0.5 * (v[1:] + v[:-1]) * jnp.diff(t)[:, None]
        recorded = (step + 1 < recording.count)[:, None]
        return w + jnp.sum(jnp.where(recorded, increments, 0.0), axis=0)

    blocks = (recording.count - 1 + _BLOCK - 1) // _BLOCK
    return jax.lax.fori_loop(0, blocks, block, jnp.zeros_like(x))


_BLOCK = 16


def _max_deflection(recording: Recording, final_position, w_final):
    """max over x of W(x) at rest. It lies between the load's first and last positions, 0
    and F_end: ahead of F_end every point has been ahead of the load throughout, where the
    velocity falls with x at every time, and behind 0 behind it, where it rises with x.
    The best of `_N_MAX` points of [0, F_end], then of as many between the best one's
    neighbours, `_ZOOMS` times; at least w_final, W(F_end), which the solve integrated
    exactly. (No parabola through the last three: W may have a kink at its peak, where a
    hinge stood, and the parabola overshoots it.)"""
    lo, hi = jnp.zeros_like(final_position), final_position
    for _ in range(_ZOOMS):
        x = jnp.linspace(lo, hi, _N_MAX)
        w = _final_displacement(recording, x)
        k = jnp.argmax(w)
        lo, hi = x[jnp.maximum(k - 1, 0)], x[jnp.minimum(k + 1, _N_MAX - 1)]
    return jnp.maximum(jnp.max(w), w_final)


# `max_deflection`'s grids: each of this many points spans two intervals of the last.
_N_MAX, _ZOOMS = 17, 3


def padded(samples, count):
    """Repeat the last recorded sample over the unfilled tail."""
    index = jnp.minimum(
        jnp.arange(jax.tree.leaves(samples)[0].shape[0], dtype=count.dtype), count - 1
    )
    return jax.tree.map(lambda a: a[index], samples)


def plastic_zone_grid(samples, count, n_x):
    """`n_x` points spanning every plastic zone of the first `count` samples."""
    filled = jnp.arange(samples["position"].shape[0], dtype=count.dtype) < count
    return jnp.linspace(
        jnp.min(jnp.where(filled, samples["position"] - samples["s2"], jnp.inf)),
        jnp.max(jnp.where(filled, samples["position"] + samples["s1"], -jnp.inf)),
        n_x,
    )


def vehicle_path(time, contact_force, contact_position, normal, tangential, sunk):
    """The vehicle's path in plan, `(along, normal)` at each recorded step: along the
    barrier from the impact point and normal to it (towards the barrier) from the point
    of contact.

    While in contact (crushing and contact phases) the vehicle is at the contact point
    F(T), and its body has moved `sunk` = W(F(T), T) + D(T) towards the barrier, the
    barrier's displacement under it plus its crush: the integral of its normal velocity
    (3.3.3). From the first step of the free phase on (where the contact force is zero:
    after a separation, or the final state at rest) it moves on in a straight line at
    its exit velocity."""
    n = time.shape[-1]
    free = contact_force == 0.0
    first = jnp.where(jnp.any(free), jnp.argmax(free), n)
    k = jnp.minimum(first, n - 1)
    in_contact = jnp.arange(n) < first
    elapsed = time - time[k]
    return (
        jnp.where(in_contact, contact_position, contact_position[k] + tangential * elapsed),
        jnp.where(in_contact, sunk, sunk[k] + normal * elapsed),
    )


def build_history(samples, count, p: Params, n_x, n_history) -> ObliqueImpactHistory:
    """The history at `n_history` equal steps of time from the first recorded step to the
    last, interpolated linearly between the `count` recorded ones."""
    samples = padded(samples, count)
    x = plastic_zone_grid(samples, count, n_x)
    time, vn, vh = samples["time"], samples["vehicle_normal"], samples["vehicle_tangential"]
    sunk = samples["contact_displacement"] + samples["crush"]
    along, normal = vehicle_path(time, samples["force"], samples["position"], vn, vh, sunk)
    vehicle_energy = 0.0 if p.moving_load else 0.5 * p.mu * (vn**2 + vh**2)
    steps = dict(
        vehicle_velocity=vn,
        vehicle_tangential_velocity=vh,
        vehicle_position=along,
        vehicle_displacement=normal,
        barrier_velocity=samples["v0"],
        barrier_displacement=samples["contact_displacement"],
        contact_force=samples["force"],
        crush=samples["crush"],
        hinge_position=samples["s1"],
        rear_hinge_position=samples["s2"],
        backing_work=samples["backing_work"],
        hinge_work=samples["hinge_work"],
        friction_work=samples["friction_work"],
        slope_work=samples["slope_work"],
        string_work=jnp.zeros_like(vn),
        beam_kinetic_energy=beam_kinetic_energy(samples["v0"], samples["s1"], samples["s2"]),
        vehicle_kinetic_energy=jnp.zeros_like(vn) + vehicle_energy,
        contact_position=samples["position"],
        slope=samples["slope"],
        deflected_shape=displacement_field(samples, count, x),
    )
    t = jnp.linspace(time[0], time[count - 1], n_history)
    # Every quantity in one interpolation, side by side: the sample times are searched once
    # (a search each: 3.5 % more instructions in the forward program, to compile and load).
    columns = [values.reshape(values.shape[0], -1) for values in steps.values()]
    at_t = jax.vmap(jnp.interp, in_axes=(None, None, 1), out_axes=1)
    resampled = jnp.split(
        at_t(t, time, jnp.concatenate(columns, axis=1)),
        np.cumsum([c.shape[1] for c in columns[:-1]]),
        axis=1,
    )
    return ObliqueImpactHistory(
        time=t,
        x=x,
        **{
            name: r if values.ndim == 2 else r[:, 0]
            for (name, values), r in zip(steps.items(), resampled)
        },
    )


def _speed(normal, tangential):
    """|(normal, tangential)|, 0 with zero derivatives for a vehicle at rest (hypot's
    derivative there is NaN)."""
    at_rest = (normal == 0.0) & (tangential == 0.0)
    return jnp.where(at_rest, 0.0, jnp.hypot(normal, jnp.where(at_rest, 1.0, tangential)))


def finish(solution: Solution, *, n_history, n_x) -> tuple[ObliqueImpact, Outcome]:
    """The results of a solve, and how it ended."""
    y, f, stage, p = solution.y, solution.derivative, solution.stage, solution.args
    recording = solution.recording
    y, past = run_out_to_rest(y, f, stage, recording, p)
    history = None
    if n_history:
        samples, count = _ending_at_rest(recording, y, stage, past, p)
        history = build_history(samples, count, p, n_x, n_history)
    w_final = y.contact_displacement
    duration = y.time
    vn, vh = y.vehicle_normal, y.vehicle_tangential
    return ObliqueImpact(
        damage=y.crush,
        duration=duration,
        max_deflection=_max_deflection(recording, y.position, w_final),
        barrier_displacement=w_final,
        hinge_position=y.s1,
        rear_hinge_position=y.s2,
        exit_speed=_speed(vn, vh),
        exit_angle_deg=exit_angle_deg(vn, vh),
        crush_work=p.phi * y.crush,
        backing_work=y.backing_work,
        hinge_work=y.hinge_work,
        friction_work=y.friction_work,
        slope_work=y.slope_work,
        string_work=jnp.zeros_like(duration),
        t_star=stage.t_star,
        exit_normal_speed=vn,
        exit_tangential_speed=vh,
        separated=stage.separated.astype(duration.dtype),
        steps=recording.count,
        history=history,
    ), outcome_of(solution)


def rigid_barrier(mu, phi, vn, vh, friction, *, n_history, n_x) -> ObliqueImpact:
    """phi <= 1 (report 3.2's force ratio P0 / P_b, P_b = 4 (M0 q0)^1/2 the beam's static
    collapse load): the barrier never yields, and the vehicle crushes against it as against a
    rigid wall, at P0 (phi) until its normal speed is spent, at T* = mu V_N / phi, sliding
    meanwhile under the friction force friction phi (its slide stopped where V_H runs
    out first); then it moves on along the barrier at what is left of V_H, with no force
    between them (exit angle 0). D = mu V_N^2 / (2 phi); the friction takes the rest of
    the tangential kinetic energy lost. Histories from contact to T*; the barrier's are
    zero."""
    t_star = mu * vn / phi
    slide = friction * phi / mu  # the tangential deceleration while sliding
    vh_end = jnp.maximum(vh - slide * t_star, 0.0)
    zero = jnp.zeros_like(t_star)
    history = None
    if n_history:
        t = t_star[..., None] * jnp.linspace(0.0, 1.0, n_history)
        vn_, vh_, sl = vn[..., None], vh[..., None], slide[..., None]
        t_slide = jnp.where(sl > 0.0, vh_ / jnp.where(sl > 0.0, sl, 1.0), jnp.inf)
        sliding = jnp.minimum(t, t_slide)
        along = vh_ * sliding - 0.5 * sl * sliding**2
        normal = vn_ * t - 0.5 * (phi / mu)[..., None] * t**2
        v_normal, v_along = vn_ - (phi / mu)[..., None] * t, jnp.maximum(vh_ - sl * t, 0.0)
        zeros = jnp.zeros_like(t)
        history = ObliqueImpactHistory(
            time=t,
            vehicle_velocity=v_normal,
            vehicle_tangential_velocity=v_along,
            vehicle_position=along,
            vehicle_displacement=normal,
            barrier_velocity=zeros,
            barrier_displacement=zeros,
            contact_force=jnp.zeros_like(t) + phi[..., None],
            crush=normal,
            hinge_position=zeros,
            rear_hinge_position=zeros,
            backing_work=zeros,
            hinge_work=zeros,
            friction_work=0.5 * mu[..., None] * (vh_**2 - v_along**2),
            slope_work=zeros,
            string_work=zeros,
            beam_kinetic_energy=zeros,
            vehicle_kinetic_energy=0.5 * mu[..., None] * (v_normal**2 + v_along**2),
            contact_position=along,
            slope=zeros,
            x=along[..., -1:] * jnp.linspace(0.0, 1.0, n_x),
            deflected_shape=jnp.zeros(t.shape + (n_x,), t.dtype),
        )
    return ObliqueImpact(
        damage=0.5 * mu * vn**2 / phi,
        duration=t_star,
        max_deflection=zero,
        barrier_displacement=zero,
        hinge_position=zero,
        rear_hinge_position=zero,
        exit_speed=vh_end,
        exit_angle_deg=zero,
        crush_work=0.5 * mu * vn**2,
        backing_work=zero,
        hinge_work=zero,
        friction_work=0.5 * mu * (vh**2 - vh_end**2),
        slope_work=zero,
        string_work=zero,
        t_star=t_star,
        exit_normal_speed=zero,
        exit_tangential_speed=vh_end,
        separated=jnp.ones_like(t_star),
        steps=jnp.zeros(t_star.shape, int),
        history=history,
    )
