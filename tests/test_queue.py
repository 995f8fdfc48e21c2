"""barrierjax._solve.queue: many solves of different lengths in refilled lanes."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.queue import solve_queued

CAPACITY = 16


def start(problem):
    """Count to `steps`, recording `scale * k` at step k after a seed row `scale`."""
    steps, scale = problem
    rows = jnp.zeros((CAPACITY,), scale.dtype).at[0].set(scale)
    return {
        "k": jnp.zeros((), jnp.int32),
        "steps": steps,
        "scale": scale,
        "rows": rows,
        "n": jnp.ones((), jnp.int32),
    }


def step(state):
    value = state["scale"] * state["k"].astype(state["scale"].dtype)
    rows = state["rows"].at[state["n"]].set(value, unique_indices=True)
    return state | {"k": state["k"] + 1, "rows": rows, "n": state["n"] + 1}


def running(state):
    return state["k"] < state["steps"]


def finish(state, lane):
    # The rows of every lane: this lane's are row `lane`.
    recorded = jnp.arange(CAPACITY, dtype=jnp.int32) < state["n"]
    return {"total": jnp.sum(jnp.where(recorded, state["rows"][lane], 0.0)), "k": state["k"]}


def solve(steps, scale, lanes, refill, count=None, order=None):
    return solve_queued(
        start,
        step,
        running,
        finish,
        (steps, scale),
        buffers=lambda state: state["rows"],
        seed_rows=1,
        lanes=lanes,
        refill=refill,
        count=count,
        order=order,
    )


@pytest.mark.parametrize("lanes, refill", [(3, 2), (4, 1), (10, 4), (32, 32)])
def test_every_problem_is_solved_once_in_its_place(lanes, refill):
    # Problems of different lengths, more than the lanes: each lane is refilled several
    # times, and a refilled lane's buffer still holds its last problem's rows.
    steps = jnp.array([5, 1, 12, 3, 7, 2, 9, 4, 6, 11], jnp.int32)
    scale = jnp.linspace(1.0, 2.0, 10)
    out = jax.jit(solve, static_argnums=(2, 3))(steps, scale, lanes, refill)
    m = np.asarray(steps)
    np.testing.assert_array_equal(out["k"], m)
    np.testing.assert_allclose(out["total"], np.asarray(scale) * (1 + m * (m - 1) / 2), rtol=1e-12)


def test_tangents_follow_each_problem(id_arrays):
    """And the lanes' buffers carry theirs as the values: refilling writes the seed rows
    alone (no pass over every lane's whole buffer, as a scatter whose indices may repeat
    is differentiated)."""
    steps = jnp.array([5, 1, 12, 3, 7], jnp.int32)
    scale = jnp.linspace(1.0, 2.0, 5)
    tangent = jnp.arange(1.0, 6.0)
    differentiated = lambda s, t: jax.jvp(lambda s: solve(steps, s, 2, 1)["total"], (s,), (t,))
    _, d = differentiated(scale, tangent)
    m = np.asarray(steps)
    np.testing.assert_allclose(d, np.asarray(tangent) * (1 + m * (m - 1) / 2), rtol=1e-12)
    assert not id_arrays(jax.make_jaxpr(differentiated)(scale, tangent), (2, CAPACITY))


def test_no_problems_give_empty_results():
    out = solve(jnp.zeros(0, jnp.int32), jnp.zeros(0), 3, 2)
    assert out["total"].shape == (0,) and out["k"].shape == (0,)


@pytest.mark.parametrize("count", [0, 2, 7])
def test_problems_past_the_count_are_never_started(count):
    """The padding of a batch: its problems are neither stepped nor finished (zeros), and
    the real ones are solved as without it; the count is traced (one program for all)."""
    steps = jnp.array([5, 1, 12, 3, 7, 2, 9, 4], jnp.int32)
    scale = jnp.linspace(1.0, 2.0, 8)
    out = jax.jit(solve, static_argnums=(2, 3))(steps, scale, 3, 2, jnp.asarray(count))
    m = np.asarray(steps)[:count]
    np.testing.assert_array_equal(out["k"], np.concatenate([m, np.zeros(8 - count, int)]))
    expected = np.asarray(scale)[:count] * (1 + m * (m - 1) / 2)
    np.testing.assert_allclose(out["total"][:count], expected, rtol=1e-12)
    assert not np.any(np.asarray(out["total"][count:]))


@pytest.mark.parametrize("count", [None, 5])
def test_problems_started_in_another_order_are_solved_in_their_places(count):
    """`order` starts the problems in another sequence (the real ones first); each result
    still lands at its problem's index, and the padding is still never started."""
    steps = jnp.array([5, 1, 12, 3, 7, 2, 9, 4], jnp.int32)
    scale = jnp.linspace(1.0, 2.0, 8)
    order = jnp.array([2, 0, 4, 3, 1, 7, 6, 5])  # the five real ones first
    traced_count = None if count is None else jnp.asarray(count)
    out = jax.jit(solve, static_argnums=(2, 3))(steps, scale, 3, 2, traced_count, order)
    given = jax.jit(solve, static_argnums=(2, 3))(steps, scale, 3, 2, traced_count)
    for name in ("k", "total"):
        np.testing.assert_array_equal(out[name], given[name])
    real = 8 if count is None else count
    m = np.asarray(steps)[:real]
    np.testing.assert_array_equal(out["k"][:real], m)
    assert not np.any(np.asarray(out["total"][real:]))
