"""barrierjax._solve.batching: the padded batch sizes that let sweeps of nearby sizes share
one compiled program."""

import threading

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve import batching
from barrierjax._solve.batching import padded_size, solve_padded, sorted_chunks


def test_padded_sizes_are_powers_of_two_then_multiples_of_the_quantum():
    sizes = [padded_size(n, 1024) for n in range(1, 5000)]
    expected = {1: 1, 2: 2, 3: 4, 5: 8, 100: 128, 1000: 1024, 1024: 1024, 1025: 2048}
    assert {n: padded_size(n, 1024) for n in expected} == expected
    assert padded_size(10_000, 1024) == 10_240
    n = np.arange(1, 5000)
    assert np.all(np.asarray(sizes) >= n) and np.all(np.diff(sizes) >= 0)
    assert np.all(np.asarray(sizes) < np.maximum(2 * n, n + 1024))
    assert len(set(sizes)) == 11 + 4  # 1 .. 1024, then 2048 .. 5120


def test_the_padded_solve_returns_the_real_rows_and_their_derivatives():
    calls = []

    def solve(x, y, count):
        calls.append((x.shape, int(count)))
        return {"sum": x + y, "rows": jnp.stack([x, 2 * y], axis=-1)}

    x, y = jnp.arange(5.0), jnp.arange(5.0) ** 2
    out = solve_padded(solve, (x, y), 1024)
    assert calls == [((8,), 5)]
    np.testing.assert_array_equal(out["sum"], x + y)
    assert out["rows"].shape == (5, 2)
    grad = jax.grad(lambda x: jnp.sum(solve_padded(solve, (x, y), 1024)["sum"] ** 2))(x)
    np.testing.assert_allclose(grad, 2 * (x + y), rtol=1e-15)
    # Inputs of any one shape: solved flat, returned in that shape.
    grid = solve_padded(solve, (x[:4].reshape(2, 2), y[:4].reshape(2, 2)), 1024)
    assert calls[-1] == ((4,), 4) and grid["rows"].shape == (2, 2, 2)
    np.testing.assert_array_equal(grid["sum"], (x[:4] + y[:4]).reshape(2, 2))


def _recording_solve(calls):
    def solve(x, y, count):
        calls.append((x.shape, int(count), threading.current_thread().name))
        return {"sum": x + y, "rows": jnp.stack([x, 2 * y], axis=-1)}

    return solve


def test_large_concrete_batches_are_solved_in_equal_parts_from_threads(monkeypatch):
    monkeypatch.setattr(batching, "_parts", lambda n, inputs: 3)
    calls = []
    x, y = jnp.arange(2500.0).reshape(50, 50), jnp.arange(2500.0).reshape(50, 50) ** 2
    out = solve_padded(_recording_solve(calls), (x, y), 256)
    # 834, 834 and 832 scenarios, each part padded to 1024: one program for the three.
    assert sorted(call[:2] for call in calls) == [((1024,), 832), ((1024,), 834), ((1024,), 834)]
    assert all(call[2].startswith("barrierjax-part") for call in calls)
    np.testing.assert_array_equal(out["sum"], x + y)
    np.testing.assert_array_equal(out["rows"], jnp.stack([x, 2 * y], axis=-1))


def test_each_part_is_waited_for_in_the_thread_that_dispatched_it():
    """JAX's CPU client runs the programs one thread dispatches in turn: a thread that
    dispatched a part and went on to the next part made the two run one after the other.
    So each part's thread waits for its result before it takes another part."""
    events = []

    class Dispatched:
        """A result whose wait (`jax.block_until_ready`) is recorded."""

        def __init__(self, part):
            self.part = part

        def block_until_ready(self):
            events.append((threading.get_ident(), "waited", self.part))
            return self

    def solve(part):
        events.append((threading.get_ident(), "dispatched", int(part)))
        return Dispatched(int(part))

    results = batching._side_by_side(solve, [(jnp.asarray(k),) for k in range(6)])
    assert [r.part for r in results] == list(range(6))
    for thread in {ident for ident, _, _ in events}:
        own = [(what, part) for ident, what, part in events if ident == thread]
        assert own[0::2] == [("dispatched", part) for _, part in own[0::2]]
        assert own[1::2] == [("waited", part) for _, part in own[0::2]], own


def test_parts_follow_the_cores_and_leave_traced_inputs_whole(monkeypatch):
    monkeypatch.setattr(batching.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    x = jnp.zeros(10_000)
    assert batching._parts(10_000, (x,)) == 2
    assert batching._parts(1024, (x[:1024],)) == 2
    assert batching._parts(1023, (x[:1023],)) == 1  # under two parts' worth
    monkeypatch.setattr(batching.os, "sched_getaffinity", lambda pid: set(range(64)), raising=False)
    assert batching._parts(10_000, (x,)) == 8  # the most, unless BARRIERJAX_PARTS says
    assert batching._parts(1600, (x[:1600],)) == 3
    monkeypatch.setenv("BARRIERJAX_PARTS", "3")
    assert batching._parts(10_000, (x,)) == 3
    monkeypatch.setenv("BARRIERJAX_PARTS", "1")
    assert batching._parts(10_000, (x,)) == 1
    for bad in ("0", "two", "1.5"):
        monkeypatch.setenv("BARRIERJAX_PARTS", bad)
        with pytest.raises(ValueError, match="BARRIERJAX_PARTS must be a whole number >= 1"):
            batching._parts(10_000, (x,))
    monkeypatch.delenv("BARRIERJAX_PARTS")
    calls = []
    grad = jax.grad(lambda x: jnp.sum(solve_padded(_recording_solve(calls), (x, x), 256)["sum"]))(x)
    assert [call[:2] for call in calls] == [((10_240,), 10_000)]
    np.testing.assert_array_equal(grad, 2.0)


def test_the_parts_trace_with_the_callers_x64_setting(monkeypatch):
    """jax_enable_x64 set by a context manager holds in the calling thread only: the parts'
    threads take it from the caller."""
    monkeypatch.setattr(batching, "_parts", lambda n, inputs: 2)

    def solve(x, count):
        return x + jnp.ones(x.shape)  # float64 where x64 is on, float32 where off

    with jax.enable_x64(False):
        x = jnp.arange(3000.0)
        out = solve_padded(solve, (x,), 256)
        assert out.dtype == jnp.float32 == x.dtype
    np.testing.assert_array_equal(out, np.arange(3000.0) + 1)


def test_sorted_chunks_are_of_one_size_and_return_the_inputs_order():
    traces = []

    def solve(x, y):
        traces.append(x.shape)
        return x * y

    x = jnp.asarray([5.0, 1.0, 4.0, 2.0, 3.0])
    out = sorted_chunks(solve, (x, 10 * x), key=x, batch_size=2)
    assert traces == [()]  # the one chunk size of three (two real rows and a copy)
    np.testing.assert_array_equal(out, 10 * x**2)


def test_a_model_in_parts_gives_the_whole_batchs_answer(monkeypatch):
    from barrierjax.hinge import normal_impact

    monkeypatch.setattr(batching.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    rng = np.random.default_rng(3)
    mu, phi, v = (rng.uniform(lo, hi, 2100) for lo, hi in ((0.1, 10.0), (1.1, 8.0), (0.1, 1.0)))
    parts = normal_impact(mu, phi, v)
    monkeypatch.setenv("BARRIERJAX_PARTS", "1")
    whole = normal_impact(mu, phi, v)
    for a, b in zip(jax.tree.leaves(whole), jax.tree.leaves(parts), strict=True):
        np.testing.assert_array_equal(a, b)


def test_rows_in_parts_joins_the_rows_and_keeps_one_value_for_all(monkeypatch):
    monkeypatch.setattr(batching, "_parts", lambda n, inputs, part_size: 3)
    shapes = []

    @jax.jit
    def solve(rows):
        shapes.append(rows.shape)
        return {"sum": rows.sum(axis=1), "scale": jnp.asarray(2.0), "grid": jnp.ones(5)}

    rows = jnp.arange(5000.0).reshape(2500, 2)
    out = batching.rows_in_parts(solve, rows)
    assert shapes == [(834, 2)]  # three parts, one program
    np.testing.assert_array_equal(out["sum"], rows.sum(axis=1))
    assert out["scale"] == 2.0 and out["grid"].shape == (5,)


def test_rows_in_parts_splits_at_the_callers_part_size(monkeypatch):
    monkeypatch.setattr(batching.os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    shapes = []

    @jax.jit
    def solve(rows):
        shapes.append(rows.shape)
        return rows[:, 0] * 2

    rows = jnp.arange(128.0).reshape(64, 2)
    whole = batching.rows_in_parts(solve, rows)  # under two parts of 512: whole
    parts = batching.rows_in_parts(solve, rows, part_size=16)
    assert shapes == [(64, 2), (32, 2)]
    np.testing.assert_array_equal(parts, whole)


def test_solved_again_solves_the_flagged_scenarios_alone_and_keeps_the_others():
    # A toy solve whose "budget" is the attempt: a scenario completes where it is at most
    # the attempt. The 2 x 3 batch's scenarios needing more are solved again, those alone:
    # two together at attempt 2 (padded to 16 rows, the program of every few), then the one
    # still short as a scalar at attempt 4.
    calls = []

    def solve(args, attempt):
        (need,) = args
        calls.append((need.shape, attempt))
        done = need <= attempt
        return {"value": need * 10.0 + attempt, "rows": jnp.stack([need, need], -1)}, done

    need = jnp.asarray([[1.0, 2.0, 1.0], [3.0, 1.0, 1.0]])
    larger = lambda attempt, args, done: 2 * attempt if attempt < 4 else None
    again = lambda done: ~np.asarray(done)
    result, done, last = batching.solved_again(solve, (need,), 1, larger, again)
    assert calls == [((2, 3), 1), ((16,), 2), ((), 4)]
    assert last == 4 and bool(np.all(done))
    np.testing.assert_array_equal(result["value"], [[11.0, 22.0, 11.0], [34.0, 11.0, 11.0]])
    np.testing.assert_array_equal(result["rows"], np.stack([need, need], -1))
    # Five flagged are the same program as two; more than 16 are solved at their number.
    for flagged, shape in ((5, (16,)), (18, (18,))):
        calls.clear()
        need = jnp.ones(40).at[7 : 7 + flagged].set(2.0)
        result, done, _ = batching.solved_again(solve, (need,), 1, larger, again)
        assert calls == [((40,), 1), (shape, 2)] and bool(np.all(done))
        np.testing.assert_array_equal(result["value"], np.where(need == 2.0, 22.0, 11.0))
    need = jnp.asarray([[1.0, 2.0, 1.0], [3.0, 1.0, 1.0]])
    # `larger` giving None ends it: the scenarios still flagged keep their last solve.
    calls.clear()
    stop = lambda attempt, args, done: None
    result, done, last = batching.solved_again(solve, (need,), 1, stop, again)
    assert calls == [((2, 3), 1)] and last == 1
    np.testing.assert_array_equal(done, need <= 1)
    # A scalar input is solved again as a scalar; a traced status ends after the first solve.
    calls.clear()
    assert batching.solved_again(solve, (jnp.asarray(3.0),), 1, larger, again)[2] == 4
    assert calls == [((), 1), ((), 2), ((), 4)]
    calls.clear()
    jax.jit(lambda need: batching.solved_again(solve, (need,), 1, larger, again)[0])(need)
    assert calls == [((2, 3), 1)]
