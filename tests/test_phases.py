"""The phase driver's failures (`barrierjax._solve.phases`): a failed solve is an output of
the compiled program, raised outside it with the phase's name."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.phases import (
    NOT_SWITCHED,
    SOLVED,
    STEPS_SPENT,
    default_solver,
    raise_failures,
    solve_phase,
)
from barrierjax.hinge import SolveError

PHASES = ("the first phase", "the second phase")


def _decay(max_steps, switch_at):
    """y' = -y from 1 over [0, 10], switching where y falls to `switch_at`."""
    return solve_phase(
        lambda t, y, args: -y,
        jnp.asarray(1.0),
        0.0,
        10.0,
        None,
        switch=lambda t, y, args: y - switch_at,
        solver=default_solver(),
        rtol=1e-8,
        atol=1e-11,
        max_steps=max_steps,
    )


@pytest.mark.parametrize(
    "max_steps, switch_at, failure",
    [(256, 0.5, SOLVED), (4, 0.5, STEPS_SPENT), (256, -1.0, NOT_SWITCHED)],
)
def test_a_phase_reports_how_it_failed(max_steps, switch_at, failure):
    solved = _decay(max_steps, switch_at)
    assert int(solved.failure) == failure
    if failure == SOLVED:
        assert float(solved.t_end) == pytest.approx(np.log(2.0), rel=1e-7)


def test_concrete_failures_raise_naming_the_phase_and_the_scenario():
    result = {"damage": jnp.ones(3)}
    assert raise_failures("model", result, np.zeros((3, 2), np.int32), PHASES) is result
    failures = np.array([[SOLVED, SOLVED], [SOLVED, STEPS_SPENT], [NOT_SWITCHED, SOLVED]])
    with pytest.raises(
        SolveError,
        match=r"^model: the second phase spent its step budget "
        r"\(scenario 1 of 3; 2 of them failed\)$",
    ) as raised:
        raise_failures("model", result, failures, PHASES)
    assert raised.value.scenario == 1 and raised.value.result is result
    assert raised.value.failures == {
        1: "model: the second phase spent its step budget",
        2: "model: the first phase ended at its time bound without reaching its switching "
        "condition",
    }
    with pytest.raises(
        RuntimeError,
        match=r"the first phase ended at its time bound without "
        r"reaching its switching condition$",
    ) as raised:
        raise_failures("model", result, np.array([NOT_SWITCHED, SOLVED]), PHASES)
    assert raised.value.scenario is None


def test_traced_failures_raise_where_the_program_runs():
    checked = jax.jit(lambda x, failures: raise_failures("model", 2.0 * x, failures, PHASES))
    assert float(checked(1.5, jnp.zeros(2, jnp.int32))) == 3.0
    with pytest.raises(RuntimeError, match="model: the second phase spent its step"):
        jax.block_until_ready(checked(1.5, jnp.asarray([SOLVED, STEPS_SPENT])))
    batched = jax.vmap(checked)
    with pytest.raises(RuntimeError, match="model: the first phase ended at its"):
        jax.block_until_ready(
            batched(jnp.ones(2), jnp.asarray([[SOLVED, SOLVED], [NOT_SWITCHED, SOLVED]]))
        )
