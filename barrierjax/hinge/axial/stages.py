r"""Normal impact on an axially restrained beam: the beam stage of report 3.4,
(3.4.23)-(3.4.40), with the interaction of bending and axial force.

The beam of 3.2, held against axial motion far away, stretches as it deflects: the three
hinges (rotation rates 2 v0/xi at the centre, v0/xi at each side) must supply the
elongation rate of the deflected beam, int w_x v_x dx = 2 v0 w0 / xi. With the
rectangle's yield curve |M/M0| + (N/N0)^2 = 1 (3.4.7) and its flow rule (3.4.8), each
hinge extends at 2 (N/N0)(M0/N0) times its rotation rate, so that (3.4.33)

    n = N/N0 = N0 w0 / (4 M0) = 2 eta0 W0,   eta0 = N0 / (4 (M0 q0)^1/2),

in the dimensionless variables of 3.2 (docs/errata.md, 3.3.14). The moment equation of the half-beam
(3.4.28) holds 2 M + N w0 = 2 M0 (1 - n^2) + 4 M0 n^2 = 2 M0 (1 + n^2): the axial force
stiffens the mechanism as if M0 were M0 (1 + n^2), and (3.4.34)-(3.4.35) read, with
K = 3/2 (1 + n^2) (docs/errata.md, 3.4.34),

    V0'    = 2 phi / S - 1/2 - K / S^2
    V0 S'  = K / S - S/2 - phi                                            (3.4.35)

The same identity follows from virtual power: the hinges dissipate M0 (1 - n^2) 4 v0/xi
in bending and N 2 v0 w0/xi = M0 2 n^2 4 v0/xi in stretching. The hinge distance is
non-decreasing throughout (its rate is K/S - S/2 - phi >= 0 once n > 0), as (3.4.24)
requires.

Accelerative phase: P = P0 (phi constant), from V0 = 0, W0 = 0, S = S* (3.4.37), until the
vehicle's velocity 1 - phi T/mu meets V0 (3.4.38), or until the beam stops first: as K
grows with n, V0' can turn negative before either the velocities meet or n reaches 1
(phi near 1, strong axial force). The report does not meet this case. The backing does
not push the beam back, so the beam locks where it stopped, and the vehicle crushes to
rest against it at phi, at T = mu/phi (speed-free); `t_final` is that time.

At T = 0, V0 S' = 0 = V0, and S' is 0/0; its limit is 0 (K/S - S/2 - phi is O(n^2) =
O(T^4) there), which is the value used at V0 = 0 exactly. S moves by O(T^4) at first;
near T = 0 the rate of S relaxes as 1/V0, which the explicit Tsit5 handles in fewer steps
than the L-stable Kvaerno5 (2-30 times fewer, measured over light to heavy vehicles at
rtol 1e-6 and 1e-9), whose error estimate is the more cautious there.

Decelerative phase: phi = -mu V0' (3.4.38), which gives (3.4.39):

    V0'   = -(S/2 + K/S) / (S + 2 mu)
    V0 S' = K (S + mu) / (S (S + 2 mu)) - S (S + 3 mu) / (2 (S + 2 mu))

integrated, as in 3.2, in sigma = ln(V*/V0), in which the approach to rest is smooth, to
V0 = V* rtol e^-3 (the vehicle rides with the beam to the end, as (3.4.38) assumes; see
"Not modelled" below); the rest is added with S frozen. At rest S is the positive root of
the cubic (3.4.40), S^3 + 3 mu S^2 - 3 (1 + n_f^2) S - 3 mu (1 + n_f^2) = 0, n_f = 2 lambda_f.

All of it runs in the speed-free variables of `barrierjax.hinge.normal` (tau = T/V, v = V0/V, w = W0/V^2
for the impact speed V): n = 2 eta w with eta = eta0 V^2, so the speed enters through eta.

Not modelled: a second crushing. As n grows, the contact force -mu V0' of the
decelerative phase grows with K and can exceed the crush force phi (heavy vehicles and
strong axial force: mu 25, phi 1.414, V 0.288, eta0 4.71, `examples/axial_scene.toml`,
reaches 1.075 phi just before the string). The vehicle would then crush again at phi
while the beam decelerates under it; the model keeps it riding with the beam, so the
history's contact force exceeds phi there. None of 128 random scenarios of
`benchmarks/axial_force.py` (mu 0.1 to 30) met this.

Near that limit the vehicle and the beam decelerate alike as they meet, and their relative
velocity can dip through zero and rise again (by 1.3e-3 of the impact speed for a 1,434 kg
vehicle at 108.5 km/h on that scene's barrier): the crushing phase ends at the first
crossing of the least of its three end functions, located by bisection on the step that
crosses it (Newton's method cycled there). A step that spans the whole dip does not see
it: at rtol 1e-6 that vehicle crushes on to the string (t_star 16 % late, the string work
1.5 % and the damage 6e-4 off); at the default 1e-8 the steps resolve it.

The beam stage ends where n reaches 1 (eta0 W0 = 1/2, (3.4.43)), at `t_string`: the beam
is then a plastic string (3.4.45), which `string.py` carries to rest from the initial
conditions (3.4.46) built here.
"""

import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.flatten_util
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..._custom_types import Scalar
from ..._solve.phases import SOLVED, STEPS_SPENT, default_solver, solve_phase
from ..._solve.phases import sigma_end as _sigma_end
from ..string import StringStage, StringStart, plastic_string_stage


class _Params(eqx.Module):
    mu: Scalar
    phi: Scalar
    eta: Scalar  # eta0 V^2: n = 2 eta w
    s_star: Scalar


def _axial(w, p: _Params):
    """n = N/N0 (3.4.33) and K = 3/2 (1 + n^2)."""
    n = 2.0 * p.eta * w
    return n, 1.5 * (1.0 + n * n)


class _Accelerating(eqx.Module):
    vehicle_velocity: Scalar
    beam_velocity: Scalar
    hinge_offset: Scalar  # S - S*, free of the cancellation in K/S - S/2 - phi
    displacement: Scalar
    crush: Scalar
    backing_work: Scalar
    bending_work: Scalar
    stretching_work: Scalar


def _accelerating_field(tau, y: _Accelerating, p: _Params) -> _Accelerating:
    v, w = y.beam_velocity, y.displacement
    n, k = _axial(w, p)
    s = p.s_star + y.hinge_offset
    # K/S - S/2 - phi = 3/2 n^2 / S - (S - S*)(S + S* + 2 phi) / (2 S): S* is the root.
    hinge_rate_times_v = 1.5 * n * n / s - y.hinge_offset * (s + p.s_star + 2.0 * p.phi) / (2 * s)
    moving = v > 0.0
    return _Accelerating(
        vehicle_velocity=-p.phi / p.mu + 0.0 * v,
        beam_velocity=2.0 * p.phi / s - 0.5 - k / s**2,
        hinge_offset=jnp.where(moving, hinge_rate_times_v / jnp.where(moving, v, 1.0), 0.0),
        displacement=v,
        crush=y.vehicle_velocity - v,
        backing_work=0.5 * v * s,
        bending_work=0.5 * v / s * (1.0 - n * n),
        stretching_work=v * n * n / s,
    )


class _Decelerating(eqx.Module):
    hinge: Scalar
    time: Scalar
    displacement: Scalar
    backing_work: Scalar
    bending_work: Scalar
    stretching_work: Scalar


def _decelerating_rates(s, w, p: _Params):
    """(3.4.39): V0' and V0 S'."""
    n, k = _axial(w, p)
    total = s + 2.0 * p.mu
    acceleration = -(0.5 * s + k / s) / total
    hinge_rate_times_v = k * (s + p.mu) / (s * total) - s * (s + 3.0 * p.mu) / (2.0 * total)
    return n, acceleration, hinge_rate_times_v


def _decelerating_field(sigma, y: _Decelerating, args) -> _Decelerating:
    """Against sigma = ln(V*/V0): d/dsigma = -(V0 / V0') d/dT."""
    p, v_star = args
    v = v_star * jnp.exp(-sigma)
    n, acceleration, hinge_rate_times_v = _decelerating_rates(y.hinge, y.displacement, p)
    dtau = -v / acceleration
    dw = v * dtau
    return _Decelerating(
        hinge=-hinge_rate_times_v / acceleration,
        time=dtau,
        displacement=dw,
        backing_work=0.5 * dw * y.hinge,
        bending_work=0.5 * dw / y.hinge * (1.0 - n * n),
        stretching_work=dw * n * n / y.hinge,
    )


# The step budgets of the three solves at `budget` 1: the crushing phase, the decelerative
# phase and the string stage. An explicit solver's crushing phase needs steps in proportion
# to 1 / (phi - 1) as phi -> 1 (the hinge moves at a rate over V0, and V0'(0) is
# proportional to phi - 1), about 5,000 at phi - 1 = 1e-3 for heavy vehicles; the string of
# a heavy, fast vehicle a million or more.
_BUDGETS = (4096, 16384, 1_000_000)


def _beam_phases(p: _Params, *, rtol, solver, dense, budget, stiff):
    """The two phases of the beam stage, each ending where N reaches N0 if it does; with
    `stiff`, the crushing phase in the implicit steps of diffrax's Kvaerno5."""
    import diffrax  # (on first use: see `_solve.phases`)

    options = {"solver": solver, "rtol": rtol, "atol": 1e-3 * rtol, "dense": dense}
    crushing = dict(options, solver=diffrax.Kvaerno5()) if stiff else options
    zero = jnp.zeros_like(p.mu)
    first = solve_phase(
        _accelerating_field,
        _Accelerating(zero + 1.0, zero, zero, zero, zero, zero, zero, zero),
        zero,
        p.mu / p.phi,
        p,
        switch=lambda t, y, p: jnp.min(jnp.stack(_crushing_ends(t, y, p, rtol))),
        bisect=True,  # the least of three: kinks, and the velocities can meet tangentially
        max_steps=_BUDGETS[0] * budget,
        **crushing,
    )
    a = first.y_end
    velocities_met, string_reached, beam_stopped = _crushing_ends(first.t_end, a, p, rtol)
    string_in_first = string_reached <= jnp.minimum(velocities_met, beam_stopped)
    locked = beam_stopped < jnp.minimum(velocities_met, string_reached)
    second = solve_phase(
        _decelerating_field,
        _decelerating_start(first, p),
        zero,
        jnp.where(string_in_first | locked, zero, _sigma_end(rtol)),
        (p, a.beam_velocity),
        switch=lambda sigma, y, args: 1.0 - _axial(y.displacement, args[0])[0],
        switch_required=False,
        max_steps=_BUDGETS[1] * budget,
        **options,
    )
    return first, second, string_in_first, locked


def _crushing_ends(t, y: _Accelerating, p: _Params, rtol):
    """The three ways the crushing phase ends, each a function that falls through zero
    there: the velocities meet (3.4.36); N reaches N0 (the string); or the beam stops
    while the vehicle still crushes. The last happens where the axial force has grown
    enough that the crush force no longer drives the mechanism (V0' < 0): the beam then
    locks (the backing does not push it back) and the vehicle crushes to rest against
    it. Its function is V0/T over its value at T = 0, (phi - S*)/S*, less `rtol`: as V0
    falls to zero the hinge's equation (V0 S' = ...) is stiff in proportion to 1/V0, and
    explicit steps shrank to nothing before V0 = 0 (phi near 1: 217 of 32,768 random
    scenarios failed so). What is left at V0 = rtol of the starting rate moves the results
    by O(rtol): those 540 of them with phi below 1.06, at rtol 1e-8 against 1e-11, lie
    within 3.8e-8 (the hinge) and 6.6e-9 (the rest). The velocities meet by T = mu/phi
    at the latest (the vehicle's has fallen to zero), the phase's bound."""
    at_start = (p.phi - p.s_star) / p.s_star
    beam_moving = jnp.where(t > 0.0, y.beam_velocity / jnp.where(t > 0.0, t, 1.0), at_start)
    return (
        y.vehicle_velocity - y.beam_velocity,
        1.0 - _axial(y.displacement, p)[0],
        beam_moving / at_start - rtol,
    )


def _decelerating_start(first, p: _Params) -> _Decelerating:
    a = first.y_end
    return _Decelerating(
        p.s_star + a.hinge_offset,
        first.t_end,
        a.displacement,
        a.backing_work,
        a.bending_work,
        a.stretching_work,
    )


class _Trace(eqx.Module):
    """Samples of the beam stage at uniform steps h of its independent variable: the
    hinge distance S, the centre's displacement W0 and the centre's slope q = int v0/xi
    dt (the half-rotation of the centre hinge), with their rates."""

    h: Scalar
    values: Float[Array, "3 samples"]
    rates: Float[Array, "3 samples"]


def _trace(field, hinge, y0, q0, t_end, args, *, samples, solver) -> _Trace:
    """Solve a beam phase again over [0, t_end], with q alongside, in `samples` - 1 equal
    steps of `solver` (none where t_end is 0). `hinge = (name, offset)`: S is offset + the
    state's field `name`.

    The steps are the solver's own (`solver.step`) in a loop that writes each step's end
    in place. The samples are the step ends, so `diffeqsolve`'s step-size control, event
    handling and interpolation onto saved times have nothing to do here; without them
    the model's first call compiles in a quarter less time. The loop runs no step where
    t_end is 0: under `vmap` it steps while any member does, so that a chunk in which no
    scenario reaches the string takes none (a `lax.scan` took all of them everywhere:
    the batch ran 3.2 times as long, benchmarks/README.md, "The axial batch's string
    start")."""
    import diffrax  # (on first use: see `_solve.phases`)

    name, offset = hinge

    def traced(t, state, args):
        y, _ = state
        rates = field(t, y, args)
        return rates, rates.displacement / (offset + getattr(y, name))

    if isinstance(solver, diffrax.AbstractImplicitSolver):
        # (Its root find could fail within a step, and nothing here would see it.)
        raise TypeError(f"the string's start takes an explicit solver's steps; got {solver}")
    term = diffrax.ODETerm(traced)
    if getattr(solver, "scan_kind", "") is None:
        # Runge-Kutta stages in a plain loop, as `diffrax.ForwardMode` has them: forward
        # derivatives cannot pass the default checkpointed one.
        solver = eqx.tree_at(lambda s: s.scan_kind, solver, "lax", is_leaf=lambda x: x is None)
    h = t_end / (samples - 1)
    ts = t_end * jnp.linspace(0.0, 1.0, samples)

    start = (y0, q0)
    steps = jnp.where(t_end > 0.0, samples - 1, 0)

    flat, unflatten = jax.flatten_util.ravel_pytree(start)
    ravel = lambda state: jax.flatten_util.ravel_pytree(state)[0]

    def advance(carry):
        k, state, solver_state, ends = carry
        state, _, _, solver_state, _ = solver.step(
            term, ts[k], ts[k + 1], state, args, solver_state, made_jump=False
        )
        return k + 1, state, solver_state, ends.at[k + 1].set(ravel(state))

    # One row a sample, the start in every row until a step's end is written over it (in
    # place, `buffers`: lax's while loop under `vmap` would select it whole at each step).
    ends = jnp.broadcast_to(flat, (samples, flat.size))
    first = (0 * steps, start, solver.init(term, ts[0], ts[1], start, args), ends)
    *_, ends = eqxi.while_loop(
        lambda carry: carry[0] < steps, advance, first, kind="lax", buffers=lambda c: c[3]
    )
    y, q = jax.vmap(unflatten)(ends)
    rates, q_rate = jax.vmap(traced, in_axes=(0, 0, None))(ts, (y, q), args)
    return _Trace(
        h=h,
        values=jnp.stack([offset + getattr(y, name), y.displacement, q]),
        rates=jnp.stack([getattr(rates, name), rates.displacement, q_rate]),
    )


def _hermite(trace: _Trace, k, theta):
    """The cubic Hermite interpolant of all three traced quantities on interval k."""
    t2, t3 = theta * theta, theta**3
    h00, h10, h01, h11 = 2 * t3 - 3 * t2 + 1, t3 - 2 * t2 + theta, 3 * t2 - 2 * t3, t3 - t2
    y, m = trace.values, trace.rates * trace.h
    return h00 * y[:, k] + h10 * m[:, k] + h01 * y[:, k + 1] + h11 * m[:, k + 1]


def _when_hinge_passed(trace: _Trace, x):
    """W0 and q when the hinge passed x (W0 = q = ... at the start if it started beyond
    x): the interval by search, the point in it by bisection on the interpolant of S.
    Not differentiated: w(x) below is stationary in this point (its rate there is
    v0 (1 - x/S) = 0)."""
    trace = jax.lax.stop_gradient(trace)
    s = trace.values[0]
    k = jnp.clip(jnp.searchsorted(s, x) - 1, 0, s.shape[0] - 2)

    def halve(bounds, _):
        lower, upper = bounds
        middle = 0.5 * (lower + upper)
        below = _hermite(trace, k, middle)[0] < x
        return (jnp.where(below, middle, lower), jnp.where(below, upper, middle)), None

    start = (jnp.zeros_like(x), jnp.ones_like(x))
    (lower, upper), _ = jax.lax.scan(halve, start, None, length=48)
    return k, 0.5 * (lower + upper)


def _profile(trace: _Trace, x):
    """w(x) = int v0 (1 - x/xi)_+ dt (3.4.46) = [W0 - x q] from when the hinge passed x
    to the end of the trace."""
    k, theta = _when_hinge_passed(trace, x)
    _, w_passed, q_passed = _hermite(trace, k, theta)
    w_end, q_end = trace.values[1, -1], trace.values[2, -1]
    return (w_end - w_passed) - x * (q_end - q_passed)


def _string_start(first, second, string_in_first, p: _Params, *, cells, solver):
    """The string's initial conditions (3.4.46): the span and the velocities where N
    reaches N0, and the displacement at the string's nodes, from a second pass over the
    beam stage (to the same ends, known only after the first) that samples S, W0 and q
    finely enough for cubic interpolation. Where the string is never reached the passes
    are empty and the start is a string at rest.

    The second pass takes 2 equal steps of `solver` per node and phase, side by side
    against the adaptive steps it replaced (2026-11-27): the final quantities of 64
    random scenarios (31 reach the string) lie within 3.2e-9 of 16 steps a node, where
    the adaptive pass at rtol 1e-8 lay 1.6e-7 off; the 64 take 67-69 ms against
    228-231 ms, and 100 that reach the string 751 us each against 1,381. One scenario
    that reaches the string takes longer, 3.0 ms against 1.35 (its gradient 11-15 ms
    against 6.4-6.6). Tracing and compiling the gradient of one: 12.5-12.9 s against
    13.4-13.8 s."""
    a, d = first.y_end, second.y_end
    reached = string_in_first | second.switched
    span = jnp.where(reached, jnp.where(string_in_first, p.s_star + a.hinge_offset, d.hinge), 1.0)
    nodes = span * jnp.arange(cells + 1, dtype=span.dtype) / cells
    samples = 2 * cells + 1
    zero = jnp.zeros_like(p.mu)
    accelerating = _trace(
        _accelerating_field,
        ("hinge_offset", p.s_star),
        _Accelerating(zero + 1.0, zero, zero, zero, zero, zero, zero, zero),
        zero,
        jnp.where(reached, first.t_end, zero),
        p,
        samples=samples,
        solver=solver,
    )
    decelerating = _trace(
        _decelerating_field,
        ("hinge", 0.0),
        _decelerating_start(first, p),
        accelerating.values[2, -1],
        jnp.where(reached & ~string_in_first, second.t_end, zero),
        (p, a.beam_velocity),
        samples=samples,
        solver=solver,
    )
    in_first = jnp.where(string_in_first, True, nodes <= accelerating.values[0, -1])
    w_first = jax.vmap(_profile, in_axes=(None, 0))(accelerating, nodes)
    # A node passed in the first phase lies at w(x) from the first phase's trace plus the
    # uniform growth W0 - x q of the second.
    growth = (decelerating.values[1, -1] - decelerating.values[1, 0]) - nodes * (
        decelerating.values[2, -1] - decelerating.values[2, 0]
    )
    w_second = jax.vmap(_profile, in_axes=(None, 0))(decelerating, nodes)
    displacement = jnp.where(in_first, w_first + jnp.where(string_in_first, 0.0, growth), w_second)
    v_string = a.beam_velocity * jnp.exp(-second.t_end)
    centre = jnp.where(string_in_first, a.beam_velocity, v_string)
    vehicle = jnp.where(string_in_first, a.vehicle_velocity, v_string)
    return reached, StringStart(
        span=span,
        displacement=displacement.at[-1].set(0.0),
        centre_velocity=jnp.where(reached, centre, 0.0),
        vehicle_velocity=jnp.where(reached, vehicle, 0.0),
    )


def _at_rest(second, p: _Params, v_star, rtol):
    """The end of a decelerative phase that ran to V0 = V* e^-sigma_end, completed to rest
    with S frozen and V0' constant."""
    d = second.y_end
    v_end = v_star * jnp.exp(-_sigma_end(rtol))
    n_end, acceleration, _ = _decelerating_rates(d.hinge, d.displacement, p)
    remaining = v_end / -acceleration
    dw = 0.5 * v_end * remaining
    return {
        "s_final": d.hinge,
        "t_final": d.time + remaining,
        "w_final": d.displacement + dw,
        "backing_work": d.backing_work + 0.5 * dw * d.hinge,
        "bending_work": d.bending_work + 0.5 * dw / d.hinge * (1.0 - n_end**2),
        "stretching_work": d.stretching_work + dw * n_end**2 / d.hinge,
    }


def _after_string(first, second, string_in_first, string: StringStage, start: StringStart):
    """The final state when the string stage carried the motion to rest: the works of
    the beam stage up to t_string plus the string's backing work (its stretching work is
    reported on its own)."""
    a, d = first.y_end, second.y_end

    def at_string(field):
        return jnp.where(string_in_first, getattr(a, field), getattr(d, field))

    return {
        "s_final": start.span,
        "t_final": jnp.where(string_in_first, first.t_end, d.time) + string.duration,
        "w_final": string.displacement[0],
        "backing_work": at_string("backing_work") + string.backing_work,
        "bending_work": at_string("bending_work"),
        "stretching_work": at_string("stretching_work"),
    }


# The solves of `axial_stages`, as `_solve.phases.raise_failures` names them.
PHASES = ("the crushing phase", "the decelerative phase", "the plastic string stage")


def axial_stages(
    mu,
    phi,
    eta,
    *,
    rtol: float,
    n_history: int = 0,
    solver=None,
    string_cells: int = 128,
    string_courant: float = 1.0,
    budget: int = 1,
    stiff: bool = False,
) -> dict:
    """Both stages, speed-free (see the module docstring); `eta` = eta0 V^2. Returns the
    end-of-crushing state, the state at rest, the works, `t_string` (inf where n stays
    below 1), `string_work`, the string's flow-rule check, `failure` (the solves' codes,
    `PHASES`, as `_solve.phases.PhaseSolution` has them) and, with `n_history`,
    `history`: samples per phase and the state at rest, in the fields of `normal`'s
    histories plus `axial_force`. The solves' step budgets are `budget` times `_BUDGETS`;
    with `stiff`, the crushing phase takes implicit steps (`_beam_phases`)."""
    solver = default_solver(solver)
    root = jnp.sqrt(phi**2 + 3.0)
    p = _Params(mu, phi, eta, 3.0 / (root + phi))
    first, second, string_in_first, locked = _beam_phases(
        p, rtol=rtol, solver=solver, dense=bool(n_history), budget=budget, stiff=stiff
    )
    reached, start = _string_start(
        first, second, string_in_first, p, cells=string_cells, solver=solver
    )
    string = plastic_string_stage(
        start,
        mu,
        phi,
        jnp.where(reached, eta, 1.0),
        courant=string_courant,
        max_steps=_BUDGETS[2] * budget,
        n_history=n_history,
    )
    v_star = first.y_end.beam_velocity
    beam_only = _at_rest(second, p, v_star, rtol)
    with_string = _after_string(first, second, string_in_first, string, start)
    final = {key: jnp.where(reached, with_string[key], beam_only[key]) for key in beam_only}
    # A locked beam: the vehicle crushes on at phi against it, to rest at T = mu/phi.
    vehicle = first.y_end.vehicle_velocity
    final["t_final"] = jnp.where(locked, p.mu / p.phi, final["t_final"])
    crush = first.y_end.crush + jnp.where(locked, 0.5 * p.mu * vehicle**2 / p.phi, 0.0)
    t_string = jnp.where(string_in_first, first.t_end, second.y_end.time)
    return dict(
        history=_history(first, second, string_in_first, p, final, string, reached, n_history)
        if n_history
        else None,
        s_star=p.s_star,
        t_star=first.t_end,
        v_star=v_star,
        w_star=first.y_end.displacement,
        damage=crush + jnp.where(reached, string.crush, 0.0),
        t_string=jnp.where(reached, t_string, jnp.inf),
        string_work=jnp.where(reached, string.stretching_work, 0.0),
        string_steps=string.num_steps,
        failure=jnp.stack(  # `PHASES`
            [first.failure, second.failure, jnp.where(string.finished, SOLVED, STEPS_SPENT)],
            axis=-1,
        ),
        **final,
    )


def _history(
    first, second, string_in_first, p: _Params, final, string: StringStage, reached, n_history
):
    """Phase 1 uniform in time (n_history samples), phase 2 uniform in sigma after its
    start up to where it stopped (n_history - 1), the string stage uniform in time
    (n_history), then the state at rest. A stage that does not occur repeats the state it
    would have started from (phase 2 when the string begins in phase 1; the string when
    the beam comes to rest)."""
    k = jnp.linspace(0.0, 1.0, n_history)
    a = jax.vmap(first.dense.evaluate)(first.t_end * k)
    sigma = second.t_end * k[1:]
    d = jax.vmap(second.dense.evaluate)(sigma)
    d = jax.tree.map(  # no second phase: its block repeats the end of the first
        lambda x, y: jnp.where(string_in_first, y, x), d, _decelerating_start(first, p)
    )
    v = a.beam_velocity[-1] * jnp.exp(-sigma)
    n1, _ = _axial(a.displacement, p)
    n2, acceleration, _ = _decelerating_rates(d.hinge, d.displacement, p)
    s2 = string.history
    beam = {
        "time": jnp.concatenate([first.t_end * k, d.time]),
        "vehicle_velocity": jnp.concatenate(
            [a.vehicle_velocity, jnp.where(string_in_first, a.vehicle_velocity[-1], v)]
        ),
        "barrier_velocity": jnp.concatenate([a.beam_velocity, v]),
        "hinge": jnp.concatenate([p.s_star + a.hinge_offset, d.hinge]),
        "displacement": jnp.concatenate([a.displacement, d.displacement]),
        "contact_force": jnp.concatenate(
            [jnp.full_like(k, p.phi), jnp.where(string_in_first, p.phi, -p.mu * acceleration)]
        ),
        "crush": jnp.concatenate([a.crush, jnp.full_like(sigma, a.crush[-1])]),
        "backing_work": jnp.concatenate([a.backing_work, d.backing_work]),
        "hinge_work": jnp.concatenate(
            [a.bending_work + a.stretching_work, d.bending_work + d.stretching_work]
        ),
        "string_work": jnp.zeros(2 * n_history - 1, k.dtype),
        "axial_force": jnp.concatenate([n1, n2]),
    }
    beam["beam_kinetic_energy"] = beam["barrier_velocity"] ** 2 * beam["hinge"] / 3.0
    # The string starts from the last beam sample (phase 2's last, or phase 1's).
    last = {key: value[-1] for key, value in beam.items()}
    at_rest = {
        "time": final["t_final"],
        "vehicle_velocity": 0.0,
        "barrier_velocity": 0.0,
        "hinge": final["s_final"],
        "displacement": final["w_final"],
        "contact_force": 0.0,
        "crush": last["crush"] + jnp.where(reached, string.crush, 0.0),
        "backing_work": final["backing_work"],
        "hinge_work": final["bending_work"] + final["stretching_work"],
        "string_work": jnp.where(reached, string.stretching_work, 0.0),
        "axial_force": jnp.minimum(_axial(final["w_final"], p)[0], 1.0),
        "beam_kinetic_energy": 0.0,
    }
    on_string = {
        "time": last["time"] + s2["time"],
        "vehicle_velocity": s2["vehicle_velocity"],
        "barrier_velocity": s2["barrier_velocity"],
        "hinge": jnp.full_like(k, final["s_final"]),
        "displacement": s2["displacement"],
        "contact_force": s2["contact_force"],
        "crush": last["crush"] + s2["crush"],
        "backing_work": last["backing_work"] + s2["backing_work"],
        "hinge_work": jnp.full_like(k, last["hinge_work"]),
        "string_work": s2["string_work"],
        "axial_force": jnp.ones_like(k),
        "beam_kinetic_energy": s2["kinetic_energy"],
    }
    string_block = {
        key: jnp.where(reached, on_string[key], jnp.broadcast_to(at_rest[key], k.shape))
        for key in on_string
    }
    history = {
        key: jnp.concatenate([beam[key], string_block[key], jnp.atleast_1d(at_rest[key])])
        for key in beam
    }
    history["profile"] = jnp.where(reached, s2["profile"], 0.0)
    history["flow_rule"] = jnp.where(reached, s2["flow_rule"], 0.0)
    return history
