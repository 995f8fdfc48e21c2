"""The phase-switching ODE driver: one `diffeqsolve` per phase, ending on a real-valued event.

A phase is a pure vector field plus a real-valued switching function; the phase ends
where that function crosses zero, located by a Newton root find on the solver's dense
interpolant so that the switching time carries an exact gradient (a boolean event would
give a zero one).

A failed solve is an output (`PhaseSolution.failure`), raised outside the compiled program
(`raise_failures`), not a run-time check inside it: a check is a host callback, and neither
JAX's persistent cache nor `compilation_cache.stored_program` can keep a program holding
one (each process would compile the model again).

diffrax and optimistix are imported where a phase is solved (traced), not with the module:
a process that only loads compiled programs never needs them (`barrierjax` imports them on
first use, about 0.3 s of a second run of the command line).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import TYPE_CHECKING

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float, Int, PyTree

if TYPE_CHECKING:
    import diffrax


# `PhaseSolution.failure`: how a solve failed, if it did.
SOLVED, STEPS_SPENT, SOLVER_FAILED, NOT_SWITCHED = range(4)
_FAILURES = {
    STEPS_SPENT: "spent its step budget",
    SOLVER_FAILED: "failed in the ODE solver (a step size fell to nothing, or the state "
    "became non-finite)",
    NOT_SWITCHED: "ended at its time bound without reaching its switching condition",
}


class SolveError(RuntimeError):
    """A model's solve that failed: its first failure in one line (the model, the phase,
    what to do) and, in a batch, `failures`, each failed scenario's reason by its flat
    index; `scenario`, the first of them (None for a single solve). `result`, where the
    model had solved the whole batch before it raised, is that result: its entries for
    the failed scenarios are no answers, the others are (`barrierjax sweep
    --skip-failures` keeps them instead of solving the batch again); None otherwise."""

    def __init__(self, message: str, failures: dict[int, str] | None = None, result=None):
        super().__init__(message)
        self.failures = failures or {}
        self.result = result

    @property
    def scenario(self) -> int | None:
        return min(self.failures) if self.failures else None

    @classmethod
    def of(cls, reasons: dict[int, str], size: int | None, result=None) -> SolveError:
        """The error of the scenarios that failed, `reasons` by flat index, of a batch of
        `size` (None for a single solve, whose index is 0), with the batch's `result`."""
        first = min(reasons)
        if size is None:
            return cls(reasons[first], result=result)
        more = f"; {len(reasons)} of them failed" * (len(reasons) > 1)
        return cls(f"{reasons[first]} (scenario {first} of {size}{more})", reasons, result)


class PhaseSolution(eqx.Module):
    """The end of one phase, its number of accepted and rejected steps, how it failed
    (`SOLVED` if it did not) and, if requested, its dense interpolant."""

    t_end: Float[Array, ""]
    y_end: PyTree[Float[Array, ""]]
    num_steps: Int[Array, ""]
    switched: Bool[Array, ""]
    failure: Int[Array, ""]
    dense: diffrax.Solution | None


def default_solver(solver=None):
    """`solver` (a diffrax solver, checked), or diffrax's Tsit5, the phase models' default
    (diffrax imported here, on first use)."""
    import diffrax

    if solver is None:
        return diffrax.Tsit5()
    if not isinstance(solver, diffrax.AbstractSolver):
        raise ValueError(
            f"solver must be a diffrax solver, e.g. diffrax.Tsit5(); got {solver!r}"
        )
    return solver


def solve_phase(
    vector_field,
    y0,
    t0,
    t_bound,
    args,
    *,
    switch=None,
    solver: diffrax.AbstractSolver,
    rtol: float,
    atol: float,
    dense: bool = False,
    max_steps: int = 4096,
    switch_required: bool = True,
    bisect: bool = False,
) -> PhaseSolution:
    """Integrate `vector_field(t, y, args)` from `t0` until `switch(t, y, args)` crosses
    zero, or to `t_bound` when there is no switch.

    With a switch, `t_bound` must lie beyond it; reaching it without switching is a
    failure (`NOT_SWITCHED`), never a silent truncation, unless `switch_required` is
    False: the phase then ends at the first of the two, and `switched` says which.

    The switch falls through zero. It is located by Newton's method from the end of the
    step that crosses it, or with `bisect` by bisection on that step: for a switch with
    kinks (the least of several functions) or one that dips through zero where it is
    nearly flat, where Newton's iterations can cycle within the step without converging
    (`SOLVER_FAILED`).
    """
    import diffrax
    import optimistix as optx

    event = None
    if switch is not None:
        # The switch is located on the dense interpolant, itself accurate to about rtol;
        # asking for much less than rounding would exhaust the root finder.
        root_tol = jnp.maximum(1e-2 * rtol, 1e-13)
        event = diffrax.Event(
            lambda t, y, args, **kwargs: switch(t, y, args),
            root_finder=_bisection() if bisect else optx.Newton(rtol=root_tol, atol=root_tol),
        )
    solution = diffrax.diffeqsolve(
        diffrax.ODETerm(vector_field),
        solver,
        t0=t0,
        t1=t_bound,
        dt0=None,
        y0=y0,
        args=args,
        saveat=diffrax.SaveAt(t1=True, dense=dense),
        stepsize_controller=diffrax.PIDController(rtol=rtol, atol=atol),
        event=event,
        max_steps=max_steps,
        # Models differentiate their solves in forward mode (`sensitivity.py`); a plain
        # while loop then serves both the forward pass and the JVP.
        adjoint=diffrax.ForwardMode(),
        throw=False,
    )
    switched = jnp.asarray(False) if switch is None else solution.event_mask
    failure = jnp.where(
        diffrax.is_okay(solution.result),
        jnp.where(switch_required & (switch is not None) & ~switched, NOT_SWITCHED, SOLVED),
        jnp.where(solution.result == diffrax.RESULTS.max_steps_reached, STEPS_SPENT, SOLVER_FAILED),
    ).astype(jnp.int32)
    return PhaseSolution(
        t_end=solution.ts[-1],
        y_end=jax.tree.map(lambda y: y[-1], solution.ys),
        num_steps=solution.stats["num_steps"],
        switched=switched,
        failure=failure,
        dense=solution if dense else None,
    )


@functools.cache
def _bisection():
    """optimistix's bisection on a switch that falls through zero, to a bracket of a few
    units in the last place: Newton's method converges to rounding, and a bracket as wide
    as its tolerance would leave the answer batched and alone that far apart (its own test
    also asks |switch| < atol, which rounding may never grant so near). Its sign is given
    (`flip`): "detect" would be a run-time check, a host callback."""
    import optimistix as optx

    class Bisection(optx.Bisection):
        def terminate(self, fn, y, args, options, state, tags):
            width = jnp.abs(state.upper - state.lower)
            return width <= self.atol + self.rtol * jnp.abs(y), optx.RESULTS.successful

    return Bisection(rtol=1e-15, atol=1e-15, flip=True)


def raise_failures(name: str, result, failures, phases: Sequence[str]):
    """`result`, or an error naming the first phase of the first scenario whose solve
    failed. `failures`: the phases' `PhaseSolution.failure` codes along the last axis, the
    scenarios' shape before it; `phases` names them. Concrete failures raise a
    `SolveError` here, which carries `result` (the other scenarios' answers); traced ones
    (inside a caller's `jit`, `vmap` or `grad`) a run-time error where the program runs
    (`equinox.branched_error_if`)."""
    kinds = len(_FAILURES)
    messages = [f"{name}: {phase} {_FAILURES[code]}" for phase in phases for code in _FAILURES]
    if isinstance(failures, jax.core.Tracer):
        flat = jnp.reshape(failures, (-1, len(phases))).astype(jnp.int32)
        codes = jnp.arange(len(phases), dtype=jnp.int32) * kinds + flat - 1
        codes = jnp.where(flat != SOLVED, codes, len(messages))
        first = jnp.min(codes)
        failed = first < len(messages)
        # (Under `vmap` the message is the largest index's of all members: 0 where none.)
        return eqx.branched_error_if(result, failed, jnp.where(failed, first, 0), messages)
    flat = np.asarray(failures).reshape(-1, len(phases))
    failed = np.flatnonzero((flat != SOLVED).any(axis=1))
    if failed.size == 0:
        return result
    phase = np.argmax(flat != SOLVED, axis=1)  # the first that failed
    reasons = {int(k): messages[phase[k] * kinds + flat[k, phase[k]] - 1] for k in failed}
    raise SolveError.of(reasons, None if np.ndim(failures) == 1 else len(flat), result)


def sigma_end(rtol):
    """Where a decelerative phase integrated in sigma = ln(V*/V) hands over to the
    analytic run-out to rest: e^-sigma_end is below rtol by e^-3."""
    return 3.0 - jnp.log(rtol)
