"""The results of an oblique impact: the state at rest, the run-out to it, and the
histories.

`max_deflection` integrates the velocity field over the recorded steps by the trapezoidal
rule (error O(step^2): about 2e-3 relative at rtol 1e-6) between the load's first and last
positions, where the peak lies, on grids zooming in on it (`max_deflection`: within 4e-6
of the peak on 16385 points over every plastic zone; a single grid of 129 points over
every plastic zone was up to 1.5e-2 off).
"""

import equinox as eqx
import jax
import jax.numpy as jnp

from ..._custom_types import Scalar
from ..._solve.recorded_rk import Recording, Solution
from .mechanism import Params, State, beam_kinetic_energy, velocity_field
from .phases import MOTION
from .transitions import Outcome, outcome_of


class ObliqueImpactHistory(eqx.Module):
    """One sample per accepted solver step, `n_saved` of them; the rest of each array
    repeats the final state. `displacement[k, j]` is W(x[j], time[k])."""

    time: Scalar
    s1: Scalar
    s2: Scalar
    v0: Scalar
    vehicle_normal_velocity: Scalar
    vehicle_tangential_velocity: Scalar
    contact_position: Scalar
    contact_force: Scalar
    slope: Scalar
    crush: Scalar
    contact_displacement: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar
    beam_kinetic_energy: Scalar
    vehicle_kinetic_energy: Scalar
    x: Scalar
    displacement: Scalar
    n_saved: Scalar


class ObliqueImpact(eqx.Module):
    """Dimensionless response to an oblique impact (report 3.3)."""

    t_star: Scalar
    t_final: Scalar
    s1_final: Scalar
    s2_final: Scalar
    w_final: Scalar
    max_deflection: Scalar
    damage: Scalar
    exit_normal_speed: Scalar
    exit_tangential_speed: Scalar
    # The angle of the exit velocity to the barrier; 0 (with zero derivatives) for a vehicle
    # that ends at rest against it, friction having stopped its slide before the barrier
    # stopped, where the angle is undefined (arctan2(0, 0) would give NaN derivatives).
    exit_angle_deg: Scalar
    separated: Scalar
    crush_work: Scalar
    backing_work: Scalar
    hinge_work: Scalar
    friction_work: Scalar
    slope_work: Scalar
    history: ObliqueImpactHistory | None


class MovingLoad(eqx.Module):
    s1: Scalar
    s2: Scalar
    v0: Scalar
    history: ObliqueImpactHistory | None


def run_out_to_rest(y: State, f: State, in_contact):
    """Add the motion from V0_end = V0* rtol e^-3 to rest, with the hinges frozen and the
    deceleration constant (its error is far below rtol): (time, extra displacement under
    the load)."""
    v0 = jnp.exp(y.speed)
    remaining = v0 / jnp.abs(f.speed)
    sliding = jnp.where(in_contact, y.vehicle_normal, 0.0)  # theta V_H (`transition`)
    return remaining, (0.5 * v0 + sliding) * remaining


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


def build_history(samples, count, p: Params, x, displacement):
    vn, vh = samples["vehicle_normal"], samples["vehicle_tangential"]
    vehicle_energy = 0.0 if p.moving_load else 0.5 * p.mu * (vn**2 + vh**2)
    return ObliqueImpactHistory(
        time=samples["time"],
        s1=samples["s1"],
        s2=samples["s2"],
        v0=samples["v0"],
        vehicle_normal_velocity=vn,
        vehicle_tangential_velocity=vh,
        contact_position=samples["position"],
        contact_force=samples["force"],
        slope=samples["slope"],
        crush=samples["crush"],
        contact_displacement=samples["contact_displacement"],
        backing_work=samples["backing_work"],
        hinge_work=samples["hinge_work"],
        friction_work=samples["friction_work"],
        slope_work=samples["slope_work"],
        beam_kinetic_energy=beam_kinetic_energy(samples["v0"], samples["s1"], samples["s2"]),
        vehicle_kinetic_energy=jnp.zeros_like(vn) + vehicle_energy,
        x=x,
        displacement=displacement,
        n_saved=count,
    )


def _exit_angle_deg(normal, tangential):
    """The exit velocity's angle to the barrier, 0 for a vehicle at rest (the inner `where`
    keeps arctan2's derivative at (0, 0), NaN, out of the gradient)."""
    at_rest = (normal == 0.0) & (tangential == 0.0)
    angle = jnp.arctan2(-normal, jnp.where(at_rest, 1.0, tangential))
    return jnp.where(at_rest, 0.0, jnp.degrees(angle))


def finish(solution: Solution, *, history, n_x) -> tuple[ObliqueImpact, Outcome]:
    """The results of a solve, and how it ended."""
    y, f, stage, p = solution.y, solution.derivative, solution.stage, solution.args
    remaining, extra = run_out_to_rest(y, f, ~stage.separated)
    recording = solution.recording
    hist = None
    if history:
        x = plastic_zone_grid(recording.samples, recording.count, n_x)
        samples = padded(recording.samples, recording.count)
        displacement = displacement_field(samples, recording.count, x)
        hist = build_history(samples, recording.count, p, x, displacement)
    w_final = y.contact_displacement + extra
    t_final = y.time + remaining
    exit_tangential = y.vehicle_tangential
    return ObliqueImpact(
        t_star=stage.t_star,
        t_final=t_final,
        s1_final=y.s1,
        s2_final=y.s2,
        w_final=w_final,
        max_deflection=_max_deflection(recording, y.position, w_final),
        damage=y.crush,
        exit_normal_speed=y.vehicle_normal,
        exit_tangential_speed=exit_tangential,
        exit_angle_deg=_exit_angle_deg(y.vehicle_normal, exit_tangential),
        separated=stage.separated.astype(t_final.dtype),
        crush_work=p.phi * y.crush,
        backing_work=y.backing_work,
        hinge_work=y.hinge_work,
        friction_work=y.friction_work,
        slope_work=y.slope_work,
        history=hist,
    ), outcome_of(solution)
