"""Where each stage ends and what follows it, the step loop built from them, and the
failures it reports.

Where the model stops with an error rather than an answer:
- The load catches up with the hinge ahead of it (S1 -> 0 in the contact phase; fast
  slides, small angles): V0 and the force then grow without bound, outside the
  three-hinge mechanism; the report does not meet this case.
- The step budget runs out (`max_steps`). Heavy vehicles (mu above about 50) crush for
  T* ~ mu V_N / phi with the hinges at their steady state, where the explicit steps are
  bounded by stability, not accuracy: they need a larger budget (an L-stable step in
  `barrierjax._solve.recorded_rk` would remove this).
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Int

from ..._custom_types import Scalar
from ..._solve.recorded_rk import Carry, RecordedRK, Recording, Solution
from .mechanism import Params, State, beam_acceleration, start_series
from .memory import Past, read_past
from .phases import (
    CONTACT,
    CRUSHING,
    FREE,
    Breakpoints,
    Stage,
    beam_speed,
    empty_recording,
    force_from_rates,
    record,
    slope_under_load,
    trace_sample,
    vector_field,
)

# The contact phase and each of its segments start with this fraction of the step the last
# stage would have taken next. The force jumps or kinks at a breakpoint and changes fast
# after it, and the right hinge records there the trace the load reads later: carried
# over whole, the step recorded it too coarsely (on the benchmark's worst scenario, t_final
# was 1.3e-4 off at rtol 1e-5; with a tenth, 2e-6, in as many steps as a fresh start).
_RESTART = 0.1

# The contact phase stops where S1 falls to this fraction of S*: there the load has caught
# up with the hinge ahead of it, V0 and the force grow without bound, and the mechanism of
# 3.3 no longer holds (the report does not meet this case).
_OVERTAKEN = 1e-3

# In s, ln V0 falls at the rate |V0'|, steadily once the hinges have settled, where the
# error estimate would let the step grow without bound: cap it at this many e-folds of V0.
_EFOLDS_PER_STEP = 2.0

# The decelerative phases end at V0 = V0* rtol^REST_SPEED e^-REST_MARGIN, and the run-out to
# rest is closed in form (`results.run_out_to_rest`): its error, O(V0^2), is then relative
# O(rtol e^-2). A heavy vehicle's contact takes some 8 steps an e-fold of V0 (its hinges
# relax some 30 times faster than V0 falls, and bound the explicit steps); a margin of 1
# e-fold instead of 3 saved 15 % of its steps and moved no result by more than 1.24 times
# its error (benchmarks/README.md, "Nineteenth pass").
REST_SPEED = 0.5
REST_MARGIN = 1.0


def _contact_end(y: State, f: State, stage: Stage, p: Params):
    """The terms positive while the contact lasts: it ends where the force would fall
    below zero (separation), at V0 = V0* rtol^1/2 e^-1 (`REST_SPEED`; the run-out to
    rest is closed in form, `results.run_out_to_rest`), or where the load catches up with
    the hinge ahead (an error)."""
    return (
        force_from_rates(y, f) / p.phi,
        y.speed - stage.log_rest,
        y.s1 / p.s_star - _OVERTAKEN,
    )


def _event(y: State, f: State, stage: Stage, p: Params):
    """The terms whose first zero ends the stage: the crushing phase's (the vehicle
    stops crushing where its velocity is the load point's; the moving load's at t_end),
    the contact's (`_contact_end`, and the next breakpoint) or the free phase's; and, the
    last, the slide's stop while the vehicle, crushing or in contact, slides against
    friction."""
    phase = stage.phase
    if p.moving_load:
        crushing = p.t_end - y.time
    else:
        crushing = y.vehicle_normal - f.contact_displacement
    free = y.speed - stage.log_rest
    contact = (*_contact_end(y, f, stage, p), stage.breakpoints.position[0] - y.position)
    first = jnp.where(phase == CRUSHING, crushing, jnp.where(phase == CONTACT, contact[0], free))
    rest = [jnp.where(phase == CONTACT, term, jnp.inf) for term in contact[1:]]
    slide = jnp.where(stage.sliding & (phase != FREE), y.vehicle_tangential, jnp.inf)
    return jnp.stack([first, *rest, slide])


def transition(y: State, f: State, stage: Stage, recording: Recording, past: Past, p: Params):
    """What follows the end of a stage.

    The contact phase runs in segments between the breakpoints of the deposited
    curvature. The force in contact reads Psi'(F), so its vector field jumps where Psi'
    jumps and has a kink where Psi' has one. Psi' jumps where the right hinge stood at T*
    (the force drops there, and with it S1'), and has a kink at S*, where the trace
    starts. When the load reaches such a point the force jumps (or kinks), and so does the
    curvature the right hinge deposits at that moment: a neutral delay equation propagates
    its breakpoints, x_new = H(T_k) where F(T_k) = x_k. A new breakpoint lies ahead of
    every pending one, so at most two are pending (S* and H(T*) at the start). Each
    segment ends exactly on the next one, so that no step straddles it (a straddling step
    misses the jump's contribution to the derivatives, O(1), or a kink's, O(step)), and
    reads the trace only between its two breakpoints. The end of a segment and the start
    of the next record the left and right limits at the new breakpoint.

    Friction may stop the slide in either phase: the field's friction terms switch off
    there, so the stop is an event of its own, after which the phase goes on with V_H = 0
    exactly. (The force jumps there, and so does the curvature the right hinge deposits;
    but the load no longer moves, and never reaches that point.)

    After the contact: the free phase if the vehicle separated, or the end. The state's
    `vehicle_normal` then holds the exit velocity: the load point's at separation, (3.3.3);
    in contact, theta V_H at the solve's end, which `results.run_out_to_rest` reads again
    at rest."""
    left = recording.count - 1  # this stage's last sample
    if p.moving_load:
        return y, stage, 1.0, jnp.asarray(True)
    terms = _event(y, f, stage, p)
    stops = jnp.argmin(terms) == terms.shape[0] - 1
    crushing = (stage.phase == CRUSHING) & ~stops
    in_contact = (stage.phase == CONTACT) & ~stops
    v0 = beam_speed(y, stage)
    # The crushing phase ends: the contact, against s, starts.
    breakpoints = Breakpoints.at_contact(y, p.s_star, left)
    contact = Stage(
        phase=jnp.asarray(CONTACT),
        first=jnp.zeros_like(left),
        last=breakpoints.left[0],
        breakpoints=breakpoints,
        log_rest=jnp.log(v0) + REST_SPEED * jnp.log(p.rtol) - REST_MARGIN,
        t_star=y.time,
        separated=stage.separated,
        overtaken=stage.overtaken,
        sliding=stage.sliding,
    )
    # A segment of the contact ends on a breakpoint: the next starts.
    ahead = stage.breakpoints
    # (In contact the event's terms are `_contact_end`'s, then the breakpoint's.)
    on_breakpoint = in_contact & (terms[3] < jnp.min(terms[:3]))
    pending = ahead.pop_and_push(y.position + y.s1, left)
    segment = eqx.tree_at(
        lambda s: (s.first, s.last, s.breakpoints),
        stage,
        (ahead.right[0], pending.left[0], pending),
    )
    # The contact ends: the free phase follows a separation.
    separated = terms[0] < terms[1]  # the force fell to zero before V0 to its rest value
    overtaken = y.s1 / p.s_star < 2.0 * _OVERTAKEN
    ended = eqx.tree_at(
        lambda s: (s.phase, s.separated, s.overtaken),
        stage,
        (jnp.where(separated, FREE, CONTACT), separated, overtaken),
    )
    contact_ends = in_contact & ~on_breakpoint
    exit_normal = (
        jnp.where(separated, v0, 0.0) + slope_under_load(y, p, past) * y.vehicle_tangential
    )
    y = eqx.tree_at(
        lambda y: (y.speed, y.vehicle_normal, y.vehicle_tangential),
        y,
        (
            jnp.where(crushing, jnp.log(v0), y.speed),
            jnp.where(contact_ends, exit_normal, y.vehicle_normal),
            jnp.where(stops, 0.0, y.vehicle_tangential),
        ),
    )
    pick = lambda when, a, b: jax.tree.map(lambda x, z: jnp.where(when, x, z), a, b)
    stopped = eqx.tree_at(lambda s: s.sliding, stage, jnp.asarray(False))
    stage_next = pick(stops, stopped, pick(crushing, contact, pick(on_breakpoint, segment, ended)))
    done = (contact_ends & (~separated | overtaken)) | (stage.phase == FREE)
    # A step of dT from the crushing phase is one of dT / V0 in s; a phase or a segment
    # starts with a fraction of the last step (`_RESTART`).
    restart = jnp.where(crushing | on_breakpoint | stops, _RESTART, 1.0)
    return y, stage_next, restart * jnp.where(crushing, 1.0 / v0, 1.0), done


def max_step(y: State, f: State, stage: Stage, past: Past, p: Params):
    """At most `_EFOLDS_PER_STEP` e-folds of V0; the load kept within the interval of the
    hinge's trace that the step reads (`Past.room`); and a step reaching the next
    breakpoint passes it by little: the stage ends on the step's interpolant, and past
    the breakpoint its stages read the segment's memory extrapolated."""
    efolds = jnp.where(stage.phase == CRUSHING, jnp.inf, _EFOLDS_PER_STEP / jnp.abs(f.speed))
    moving = f.position > 0.0
    per_distance = 1.0 / jnp.where(moving, f.position, 1.0)
    breakpoint = jnp.maximum(stage.breakpoints.position[0] - y.position, 0.0)
    bound = jnp.minimum(past.room, _PAST_BREAKPOINT * breakpoint) * per_distance
    return jnp.minimum(efolds, jnp.where(moving, bound, jnp.inf))


# How far (as a multiple of the distance to it at the step's start) a step may reach past
# the next breakpoint.
_PAST_BREAKPOINT = 1.01


def step_loop(rtol, max_steps, *, batched=False) -> RecordedRK:
    """The step loop; `batched` for one that runs many scenarios side by side (its steps
    written out: longer to compile, faster to run)."""
    return RecordedRK(
        field=vector_field,
        record=record,
        event=_event,
        transition=transition,
        view=read_past,
        max_step=max_step,
        rtol=rtol,
        atol=1e-3 * rtol,
        max_steps=max_steps,
        batched=batched,
    )


def initial_carry(loop: RecordedRK, mu, phi, vn, vh, friction, *, history, t_end=None) -> Carry:
    """The step loop's start, all phases in the speed-free dimensionless variables. With
    `t_end`, the moving load: phase 1 alone with no vehicle, to T = t_end."""
    dtype = jnp.result_type(mu)
    zero = jnp.zeros((), dtype)
    root = jnp.sqrt(phi**2 + 3.0)
    s_star = 3.0 / (root + phi)
    moving_load = t_end is not None
    rtol = zero + loop.rtol
    p = Params(mu, phi, friction, s_star, rtol, zero + (t_end if moving_load else 0.0), moving_load)
    # One row per iteration, and one at T = 0.
    capacity = loop.max_steps + 8
    recording = empty_recording(capacity, dtype, history)
    a = beam_acceleration(s_star, s_star, phi)
    time_scale = t_end if moving_load else 1.0 / (a + phi / mu)

    # The histories and the hinge trace start at T = 0 itself, with the expansion's rates
    # in T (the sample's ratios do not depend on the variable).
    # (ln V0 is -inf there: the series' V0 goes to the sample, in the place of ln V0.)
    series = lambda t: start_series(t, zero + vn, zero + vh, p)
    rate, acceleration = jax.jvp(
        lambda t: jax.jvp(series, (t,), (jnp.ones_like(t),)), (zero,), (jnp.ones_like(zero),)
    )[1]
    as_state = lambda d: State(speed=d["v0"], **{k: v for k, v in d.items() if k != "v0"})
    start = series(zero)
    recording = recording.append(
        trace_sample(
            jnp.asarray(CRUSHING, dtype),
            start["v0"],
            as_state(rate),
            as_state(acceleration),
            as_state(start),
            vehicle_normal=start["vehicle_normal"],
            force=phi,
            slope=zero,
        )
    )
    # The step loop starts where the expansion's error, relative O((t / T*)^2), is far
    # below rtol; the solution does not depend on where, so neither does its derivative.
    t_start = jax.lax.stop_gradient(1e-2 * jnp.sqrt(rtol) * time_scale)
    start = series(t_start)
    y0 = as_state(start)
    none = Breakpoints(
        jnp.full((2,), jnp.inf, dtype), jnp.zeros((2,), jnp.int32), jnp.zeros((2,), jnp.int32)
    )
    crushing = Stage(
        phase=jnp.asarray(CRUSHING),
        first=jnp.zeros((), jnp.int32),
        last=jnp.asarray(capacity, jnp.int32),
        breakpoints=none,
        log_rest=zero - jnp.inf,
        t_star=zero,
        separated=jnp.asarray(False),
        overtaken=jnp.asarray(False),
        sliding=start["vehicle_tangential"] > 0.0,
    )
    return loop.start(y0, crushing, recording, t_start, p)


class Outcome(eqx.Module):
    """How a solve ended, for `raise_failures` and `failure_message`: whether it completed,
    the phase it was in, whether the load overtook the hinge ahead, whether its step
    length fell to zero, and the time reached."""

    complete: Bool[Array, ""]
    phase: Int[Array, ""]
    overtaken: Bool[Array, ""]
    time: Scalar
    stalled: Bool[Array, ""]


def outcome_of(solution: Solution) -> Outcome:
    return Outcome(
        solution.complete,
        solution.stage.phase,
        solution.stage.overtaken,
        solution.y.time,
        solution.stalled,
    )


STALLED_MESSAGE = (
    "the step length is no longer positive: the solver cannot advance (a failure of the "
    "step loop, not of the step budget; another rtol may pass)"
)

OVERTAKEN_MESSAGE = (
    "the load caught up with the hinge ahead of it (S1 -> 0) in the contact phase: the "
    "vehicle slides faster than the barrier's plastic zone can run ahead, outside the "
    "three-hinge mechanism of report 3.3"
)


def phase_name(phase: int, moving_load: bool) -> str:
    if phase == CRUSHING:
        return "the moving load" if moving_load else "the crushing phase"
    return {CONTACT: "the contact phase", FREE: "the free phase"}[phase]


def raise_failures(value, outcome: Outcome, moving_load=False):
    """`value`, or a run-time error where any solve failed (`Outcome`): the checks for
    solves traced inside a caller's `jit`, `vmap` or `grad`, whose messages cannot hold the
    values (`failure_message` says more where the outcome is concrete)."""
    for phase in (CRUSHING, CONTACT, FREE):
        value = eqx.error_if(
            value,
            ~outcome.complete & ~outcome.stalled & (outcome.phase == phase),
            f"{phase_name(phase, moving_load)}: the step budget was spent before the phase "
            "ended: pass a larger max_steps (twice the last, say)",
        )
    value = eqx.error_if(value, outcome.stalled, STALLED_MESSAGE)
    return eqx.error_if(value, outcome.overtaken, OVERTAKEN_MESSAGE)
