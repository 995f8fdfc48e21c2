r"""The plastic-string stage of report 3.4, (3.4.45)-(3.4.49), which the report sets up
and leaves unsolved.

Once N reaches N0 the beam has no bending strength left and moves as a plastic string of
tension N0 over the span |x| <= xi(t_p) that was moving when it formed; outside, the
backing holds it (3.4.47). In the dimensionless variables of 3.2 (length L, time t0, the
force unit P_b = 2 q0 L) the string obeys, where it moves,

    W_TT = eta0 W_XX - 1/2                                                   (3.4.45)

(m w_tt = N0 w_xx - q0, with m L / t0^2 = 2 q0 and N0 / L = 2 eta0 q0), its wave speed is
eta0^1/2, and the centre carries the contact force Phi = -2 eta0 W_X(0+) (3.4.48). The
speed-free variables of `normal.py` (tau = T/V, w = W/V^2, v = V0/V) keep this form with
eta = eta0 V^2 in place of eta0.

The report stops at two boundary conditions; the model here adds what the motion needs:

- the backing is one-sided and rigid-plastic: a moving point feels the resistance 1/2, a
  point at rest starts only where eta w_XX > 1/2, and a point that would move back stops
  (the velocity stays >= 0);
- the vehicle is rigid-plastic: while it touches the centre the contact force lies in
  [0, phi]; the vehicle crushes at phi while it is faster than the centre, moves with it
  below phi, and separates (force 0) when the string pulls the centre ahead of it, until
  the gap closes again.

Both are monotone set-valued laws of the velocities, so each time step is solved
exactly for them (a projection of the velocities onto >= 0, and a three-way choice for
the contact, which the monotonicity makes unique).

Method: linear finite elements with lumped masses on a uniform grid of the half-span
(symmetry at the centre), and the leapfrog scheme in time (kick-drift-kick, symplectic;
velocities at half steps), with the set-valued laws implicit in each kick. The grid is
scaled with the span, dX = xi_p / cells, and the step with the wave speed,
dT = courant dX / eta^1/2: for the free string at courant 1 leapfrog is the exact
d'Alembert solution on the grid, and with the uniform resistance too. Second order in
smooth motion; stops, starts and contact switches cost an O(dT) each, which the benchmark
measures (benchmarks/axial_force.py).

The flow rule at the corner N = N0, M = 0 of the yield curve |M/M0| + (N/N0)^2 = 1 admits
the plastic rates in the cone between the normals (+-1, 2): N0 eps' >= 2 M0 |kappa'|, the
extension must dominate the curvature rate. The report's (3.4.49), -2 <= N0 eps' /
(M0 kappa') <= 2, is the complement of this cone (a misprint or a slip in the report); in
the variables here the condition reads 4 eta w_X w_Xtau >= |w_XXtau| and is checked at
every moving grid point and step. It is reported, not imposed: (3.4.45) is a membrane of
constant tension, whose tension term gives back what it took where the string shortens,
and nothing here holds an element that would. Of 512 random scenarios, the 179 that reach
the string spend a median 45 % of their nodes' moving time outside the cone (22 to 94 %),
and 8 end shorter than they started, with a negative `string_work` (down to -11 % of the
impact's energy; the energy balance closes all the same): benchmarks/README.md,
"Thirty-third pass".
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int

from .._custom_types import Scalar


class StringStart(eqx.Module):
    """The string's state when N reaches N0 (speed-free variables): its half-span, its
    displacement at the nodes X_j = span j / cells (j = 0..cells, the last is 0), and the
    velocities of the centre (the string's velocity is the beam's, v0 (1 - X/span),
    (3.4.46)) and of the vehicle (faster than the centre while it still crushes)."""

    span: Scalar
    displacement: Float[Array, " nodes"]
    centre_velocity: Scalar
    vehicle_velocity: Scalar


class _State(eqx.Module):
    step: Int[Array, ""]
    displacement: Float[Array, " nodes"]  # w at t_n, nodes 0..cells-1 (the end is held at 0)
    velocity: Float[Array, " nodes"]  # at t_(n+1/2)
    vehicle_velocity: Scalar  # at t_(n+1/2)
    contact_force: Scalar  # over the step ending at t_(n+1/2)
    gap: Scalar  # between vehicle and centre, >= 0
    crush: Scalar
    backing_work: Scalar
    stop_time: Scalar  # when the last motion so far ended
    # Only with a history: the time each node spent moving and, of that, outside the cone.
    moving_time: Float[Array, " nodes"] | None
    flow_rule_violated: Float[Array, " nodes"] | None
    recorder: "_Recorder | None"


class _Grid(eqx.Module):
    mu: Scalar
    phi: Scalar
    eta: Scalar
    dx: Scalar
    dt: Scalar
    mass: Float[Array, " nodes"]  # lumped masses of the half-string: dx/2 at the centre


def _forces(w, grid: _Grid):
    """Nodal tension forces of the half-string, eta d/dX of the slope, with w = 0 at the
    end node and free (symmetric) at the centre."""
    slope = jnp.diff(jnp.append(w, 0.0)) / grid.dx
    return grid.eta * (slope - jnp.concatenate([jnp.zeros(1, w.dtype), slope[:-1]]))


def _kick(state: _State, h, t_old, grid: _Grid) -> _State:
    """Advance the velocities by h under the tension of the current displacement, with
    the backing and the contact solved implicitly (module docstring)."""
    force = _forces(state.displacement, grid)
    trial = state.velocity + h * (force / grid.mass - 0.5)  # moving: resistance 1/2
    velocity = jnp.maximum(trial, 0.0)
    # The centre node and the vehicle (half of each: the half-string carries Phi/2).
    m0, half_mu, half_phi = grid.mass[0], 0.5 * grid.mu, 0.5 * grid.phi
    u = state.vehicle_velocity
    free_v0 = velocity[0]
    opens = state.gap + grid.dt * (free_v0 - u) > 0.0
    crush_u = u - h * half_phi / half_mu
    crush_trial_v0 = trial[0] + h * half_phi / m0
    crushing = ~opens & (crush_u >= jnp.maximum(crush_trial_v0, 0.0))
    stuck_trial = (m0 * trial[0] + half_mu * u) / (m0 + half_mu)
    stuck = jnp.maximum(stuck_trial, 0.0)
    new_u = jnp.where(opens, u, jnp.where(crushing, crush_u, stuck))
    new_v0 = jnp.where(opens, free_v0, jnp.where(crushing, jnp.maximum(crush_trial_v0, 0.0), stuck))
    centre_trial = jnp.where(opens, trial[0], jnp.where(crushing, crush_trial_v0, stuck_trial))
    contact_force = jnp.where(opens, 0.0, jnp.where(crushing, grid.phi, grid.mu * (u - stuck) / h))
    velocity = velocity.at[0].set(new_v0)
    trial = trial.at[0].set(centre_trial)
    # A vehicle that stops in contact stops under at most phi: where that happens within
    # the kick is interpolated on the crushing trajectory (exact if it crushes to rest).
    vehicle_trial = jnp.where(opens, u, crush_u)
    stop_time = jnp.maximum(
        state.stop_time,
        jnp.maximum(
            _last_stop(state.velocity, trial, velocity, t_old, h),
            _last_stop(u, vehicle_trial, new_u, t_old, h),
        ),
    )
    return eqx.tree_at(
        lambda s: (s.velocity, s.vehicle_velocity, s.contact_force, s.stop_time),
        state,
        (velocity, new_u, contact_force, stop_time),
    )


def _last_stop(old, trial, new, t_old, h):
    """The latest time at which a velocity that was positive reached zero in this kick,
    interpolated linearly between `old` and the unprojected `trial` (-inf if none did)."""
    stopped = (old > 0.0) & (new <= 0.0)
    fraction = jnp.clip(old / jnp.where(stopped, old - trial, 1.0), 0.0, 1.0)
    return jnp.max(jnp.where(stopped, t_old + h * fraction, -jnp.inf))


def _drift(state: _State, grid: _Grid) -> _State:
    """Move the string by dt at the half-step velocities; book the crush and the backing
    work over the step."""
    dt = grid.dt
    relative = dt * (state.vehicle_velocity - state.velocity[0])  # approach of the vehicle
    crush = state.crush + jnp.maximum(relative - state.gap, 0.0)
    gap = jnp.maximum(state.gap - relative, 0.0)
    return eqx.tree_at(
        lambda s: (s.step, s.displacement, s.gap, s.crush, s.backing_work),
        state,
        (
            state.step + 1,
            state.displacement + dt * state.velocity,
            gap,
            crush,
            # (1/2) int v dX over the whole string: twice the half's lumped sum, halved.
            state.backing_work + dt * jnp.sum(grid.mass * state.velocity),
        ),
    )


def _book_flow_rule(before: _State, after: _State, grid: _Grid) -> _State:
    """Add the drift from `before` to `after` to each node's moving time and, where the
    corner cone of the flow rule, 4 eta w_X w_Xtau >= |w_XXtau|, fails, to its time
    outside the cone: the extension rate
    w_X w_Xtau averaged from the two neighbouring elements, the curvature rate from the
    second difference of the velocities (the centre's by symmetry)."""
    w = jnp.append(0.5 * (before.displacement + after.displacement), 0.0)
    v = jnp.append(before.velocity, 0.0)
    slope, slope_rate = jnp.diff(w) / grid.dx, jnp.diff(v) / grid.dx
    extension = slope * slope_rate
    previous = jnp.concatenate([extension[:1], extension[:-1]])
    extension_rate = 0.5 * (extension + previous)
    mirrored = jnp.concatenate([-slope_rate[:1], slope_rate[:-1]])
    curvature_rate = (slope_rate - mirrored) / grid.dx
    violated = 4.0 * grid.eta * extension_rate < jnp.abs(curvature_rate)
    moved = before.velocity > 0.0
    return eqx.tree_at(
        lambda s: (s.moving_time, s.flow_rule_violated),
        after,
        (
            after.moving_time + jnp.where(moved, grid.dt, 0.0),
            after.flow_rule_violated + jnp.where(violated & moved, grid.dt, 0.0),
        ),
    )


# --------------------------------------------------------------------------------------
# Samples for the histories: a fixed buffer that keeps every stride-th step and halves
# itself (doubling the stride) when full, so it covers any number of steps.


class _Recorder(eqx.Module):
    stride: Int[Array, ""]
    count: Int[Array, ""]
    samples: Float[Array, "size fields"]
    profiles: Float[Array, "size nodes"]


_RECORDED = (
    "time",
    "vehicle_velocity",
    "barrier_velocity",
    "displacement",
    "contact_force",
    "crush",
    "backing_work",
    "string_work",
    "kinetic_energy",
)


def _record(recorder: _Recorder, step, values, profile) -> _Recorder:
    size = recorder.samples.shape[0]
    full = recorder.count == size

    def halved(buffer):
        return jnp.where(full, jnp.concatenate([buffer[::2], jnp.zeros_like(buffer[size // 2:])]), buffer)

    samples, profiles = halved(recorder.samples), halved(recorder.profiles)
    stride = jnp.where(full, 2 * recorder.stride, recorder.stride)
    count = jnp.where(full, size // 2, recorder.count)
    due = step % stride == 0
    samples = jnp.where(due, samples.at[count].set(values), samples)
    profiles = jnp.where(due, profiles.at[count].set(profile), profiles)
    return _Recorder(stride, jnp.where(due, count + 1, count), samples, profiles)


def _sample(state: _State, before_kick: _State, grid: _Grid, stretched_at_start, time=None):
    """The state at t_n: velocities at t_n as the mean of those before and after the
    kick at t_n (at t_(n-1/2) and t_(n+1/2)); kinetic energies likewise."""
    w = jnp.append(state.displacement, 0.0)
    velocity = 0.5 * (before_kick.velocity + state.velocity)
    vehicle = 0.5 * (before_kick.vehicle_velocity + state.vehicle_velocity)
    values = jnp.stack(
        [
            state.step.astype(grid.dt.dtype) * grid.dt if time is None else time,
            vehicle,
            velocity[0],
            state.displacement[0],
            state.contact_force,
            state.crush,
            state.backing_work,
            _stretching(w, grid) - stretched_at_start,
            jnp.sum(grid.mass * (before_kick.velocity**2 + state.velocity**2)) / 2,
        ]
    )
    return values, w


def _resampled(final: _State, last, n_history: int):
    """The recorded samples and the state at rest, linearly interpolated to n_history
    uniform times over [0, duration]; and per node the share of its moving time outside
    the flow rule's cone (0 at the held end)."""
    recorder, duration = final.recorder, final.stop_time
    values, profile = last
    index = jnp.arange(recorder.samples.shape[0])
    filled = index < recorder.count
    # The steps run past the last stop by up to one step; unfilled slots go beyond.
    recorded = jnp.minimum(recorder.samples[:, 0], duration)
    times = jnp.append(jnp.where(filled, recorded, duration + 1.0 + index.astype(duration.dtype)), duration)
    samples = jnp.concatenate([recorder.samples, values[None]])
    profiles = jnp.concatenate([recorder.profiles, profile[None]])
    at = jnp.linspace(0.0, 1.0, n_history) * duration
    order = jnp.argsort(times)

    def interpolated(column):
        return jnp.interp(at, times[order], column[order])

    history = {
        name: interpolated(samples[:, k]) for k, name in enumerate(_RECORDED) if name != "time"
    }
    history["time"] = at
    history["profile"] = jax.vmap(interpolated, in_axes=1, out_axes=1)(profiles)
    moved = final.moving_time > 0.0
    share = final.flow_rule_violated / jnp.where(moved, final.moving_time, 1.0)
    history["flow_rule"] = jnp.append(share, 0.0)
    return history


def _stretching(w, grid: _Grid):
    """eta int w_X^2 / 2 dX over the whole string: the plastic work of N0 on the
    elongation since the straight state (small slopes)."""
    return grid.eta * jnp.sum(jnp.diff(w) ** 2) / grid.dx


# --------------------------------------------------------------------------------------


class StringStage(eqx.Module):
    """The string stage's outcome, speed-free: its duration, the final displacement
    profile (nodes X_j = span j / cells), the crush, backing and stretching work it adds,
    the number of steps and, if asked for, the history (`plastic_string_stage`)."""

    duration: Scalar
    displacement: Float[Array, " nodes"]
    crush: Scalar
    backing_work: Scalar
    stretching_work: Scalar
    num_steps: Int[Array, ""]
    finished: Bool[Array, ""]
    history: dict | None


def plastic_string_stage(
    start: StringStart,
    mu,
    phi,
    eta,
    *,
    courant: float,
    max_steps: int,
    n_history: int = 0,
) -> StringStage:
    """Solve the string from `start` to rest (module docstring). With `n_history`, the
    result has `history`: that many samples uniform in time (from t_string) of the
    vehicle, the centre, the contact force, the works, the string's kinetic energy and
    its displacement profile, and per node the share of its moving time in which the
    plastic flow lies outside the flow rule's corner cone."""
    cells = start.displacement.shape[0] - 1
    dx = start.span / cells
    mass = jnp.full(cells, dx).at[0].set(0.5 * dx)
    grid = _Grid(mu, phi, eta, dx, courant * dx / jnp.sqrt(eta), mass)
    velocity = start.centre_velocity * (1.0 - jnp.arange(cells, dtype=dx.dtype) / cells)
    zero = jnp.zeros_like(mu)
    record = 4 * n_history
    recorder = None
    if record:
        recorder = _Recorder(
            jnp.asarray(1),
            jnp.asarray(0),
            jnp.zeros((record, len(_RECORDED)), mu.dtype),
            jnp.zeros((record, cells + 1), mu.dtype),
        )
    stretched_at_start = _stretching(start.displacement, grid)
    state = _State(
        step=jnp.asarray(0),
        displacement=start.displacement[:-1],
        velocity=velocity,
        vehicle_velocity=start.vehicle_velocity,
        contact_force=zero,
        gap=zero,
        crush=zero,
        backing_work=zero,
        stop_time=zero,
        moving_time=jnp.zeros(cells, mu.dtype) if record else None,
        flow_rule_violated=jnp.zeros(cells, mu.dtype) if record else None,
        recorder=recorder,
    )
    kicked = _kick(state, 0.5 * grid.dt, 0.0, grid)
    if record:
        # At t = 0 the velocities are the initial ones, not a mean across the half kick.
        sample = _sample(state, state, grid, stretched_at_start)
        kicked = eqx.tree_at(lambda s: s.recorder, kicked, _record(recorder, 0, *sample))
    state = kicked

    def moving(state):
        return ((jnp.max(state.velocity) > 0.0) | (state.vehicle_velocity > 0.0)) & (
            state.step < max_steps
        )

    def step(state):
        after = _drift(state, grid)
        if record:
            after = _book_flow_rule(state, after, grid)
        kicked = _kick(after, grid.dt, (after.step.astype(grid.dt.dtype) - 0.5) * grid.dt, grid)
        if record:
            sample = _sample(kicked, after, grid, stretched_at_start)
            kicked = eqx.tree_at(lambda s: s.recorder, kicked, _record(kicked.recorder, kicked.step, *sample))
        return kicked

    final = jax.lax.while_loop(moving, step, state)
    w_final = jnp.append(final.displacement, 0.0)
    history = None
    if record:
        last = _sample(final, final, grid, stretched_at_start, time=final.stop_time)
        history = _resampled(final, last, n_history)
    return StringStage(
        duration=final.stop_time,
        displacement=w_final,
        crush=final.crush,
        backing_work=final.backing_work,
        stretching_work=_stretching(w_final, grid) - stretched_at_start,
        num_steps=final.step,
        finished=final.step < max_steps,
        history=history,
    )
