"""The phase-switching ODE driver: one `diffeqsolve` per phase, ending on a real-valued event.

A phase is a pure vector field plus a real-valued switching function; the phase ends
where that function crosses zero, located by a Newton root find on the solver's dense
interpolant so that the switching time carries an exact gradient (a boolean event would
give a zero one).

diffrax and optimistix are imported where a phase is solved (traced), not with the module:
a process that only loads compiled programs never needs them (`barrierjax` imports them on
first use, about 0.3 s of a second run of the command line).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float, Int, PyTree

if TYPE_CHECKING:
    import diffrax


class PhaseSolution(eqx.Module):
    """The end of one phase, its number of accepted and rejected steps and, if requested,
    its dense interpolant."""

    t_end: Float[Array, ""]
    y_end: PyTree[Float[Array, ""]]
    num_steps: Int[Array, ""]
    switched: Bool[Array, ""]
    dense: diffrax.Solution | None


def default_solver(solver=None):
    """`solver`, or diffrax's Tsit5, the phase models' default (diffrax imported here, on
    first use)."""
    if solver is not None:
        return solver
    import diffrax

    return diffrax.Tsit5()


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
) -> PhaseSolution:
    """Integrate `vector_field(t, y, args)` from `t0` until `switch(t, y, args)` crosses
    zero, or to `t_bound` when there is no switch.

    With a switch, `t_bound` must lie beyond it; reaching it without switching is an
    error (raised at run time with `equinox.error_if`), never a silent truncation, unless
    `switch_required` is False: the phase then ends at the first of the two, and
    `switched` says which.
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
            root_finder=optx.Newton(rtol=root_tol, atol=root_tol),
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
        throw=True,
    )
    t_end = solution.ts[-1]
    switched = jnp.asarray(False) if switch is None else solution.event_mask
    if switch is not None and switch_required:
        t_end = eqx.error_if(
            t_end,
            ~solution.event_mask,
            "phase ended at its time bound without reaching its switching condition",
        )
    return PhaseSolution(
        t_end=t_end,
        y_end=jax.tree.map(lambda y: y[-1], solution.ys),
        num_steps=solution.stats["num_steps"],
        switched=switched,
        dense=solution if dense else None,
    )


def sigma_end(rtol):
    """Where a decelerative phase integrated in sigma = ln(V*/V) hands over to the
    analytic run-out to rest: e^-sigma_end is below rtol by e^-3."""
    return 3.0 - jnp.log(rtol)
