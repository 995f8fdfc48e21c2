"""barrierjax.hinge.oblique.memory: the pieces of the hinge's trace that a step reads."""

from types import SimpleNamespace

import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax._solve.hermite import quintic_hermite
from barrierjax._solve.recorded_rk import Recording
from barrierjax.hinge.oblique.memory import MEMORY, read_past, slope_memory

psi = lambda h: np.sin(2.0 * h) + h**2 / 3.0
dpsi = lambda h: 2.0 * np.cos(2.0 * h) + 2.0 * h / 3.0
d2psi = lambda h: -4.0 * np.sin(2.0 * h) + 2.0 / 3.0


def _trace(points):
    """The right hinge's trace recorded at `points`, with Psi's exact derivatives there."""
    recording = Recording.empty(MEMORY, 64, jnp.float64)
    for h in points:
        sample = dict(zip(MEMORY, (h, psi(h), dpsi(h), d2psi(h))))
        recording = recording.append(sample)
    return recording


def _past(points, x, travel):
    """The view of a step that starts with the load at `x` and that the controller would
    take `travel` along the barrier, within one open segment (from the first sample on)."""
    stage = SimpleNamespace(first=jnp.asarray(0, jnp.int32), last=jnp.asarray(64, jnp.int32))
    y, f = SimpleNamespace(position=jnp.asarray(x)), SimpleNamespace(position=jnp.asarray(travel))
    return read_past(y, f, 1.0, stage, _trace(points))


def _interval_quintic(points, a, b, x):
    """Psi' at x by the quintic Hermite interpolant of samples a and b (what a step reads
    on that interval wherever it lies)."""
    ends = [(psi(points[k]), dpsi(points[k]), d2psi(points[k])) for k in (a, b)]
    width = points[b] - points[a]
    return float(quintic_hermite((x - points[a]) / width, width, *ends, derivatives=1)[1])


POINTS = [0.0, 0.3, 0.5, 0.9, 1.4, 2.0]


def test_a_step_on_its_interval_reads_that_intervals_quintic():
    past = _past(POINTS, 0.4, 0.05)
    assert not bool(past.crossing)
    assert float(past.room) == pytest.approx(1.01 * (0.5 - 0.4), rel=1e-12)
    for x in (0.4, 0.45, 0.5):
        _, slope = slope_memory(past, jnp.asarray(x), 0.0)
        assert float(slope) == pytest.approx(_interval_quintic(POINTS, 1, 2, x), abs=1e-13)


def test_a_step_crossing_a_sample_reads_each_intervals_own_quintic():
    # The load at 0.4 would travel 0.3, past the sample at 0.5: the next interval's piece
    # is formed too, and each position reads the piece of the interval it lies on (the
    # one-interval view alone would end the step at 0.5).
    past = _past(POINTS, 0.4, 0.3)
    assert bool(past.crossing) and float(past.joint) == 0.5
    assert float(past.room) == pytest.approx(1.01 * (0.9 - 0.4), rel=1e-12)
    for x, (a, b) in ((0.42, (1, 2)), (0.499, (1, 2)), (0.5, (2, 3)), (0.6, (2, 3)), (0.9, (2, 3))):
        _, slope = slope_memory(past, jnp.asarray(x), 0.0)
        assert float(slope) == pytest.approx(_interval_quintic(POINTS, a, b, x), abs=1e-13), x
    # And the two pieces meet at the sample: Psi' is continuous there to rounding.
    below = slope_memory(past, jnp.asarray(np.nextafter(0.5, 0.0)), 0.0)[1]
    above = slope_memory(past, jnp.asarray(0.5), 0.0)[1]
    assert float(above) == pytest.approx(float(below), abs=1e-12)


def test_a_load_short_of_the_trace_start_passes_the_piece_by_its_own_margin():
    # The crushing phase, the load at 0.5 ahead of S* = 1 where the trace starts, whose
    # first intervals are short (the steps that start the solve): the piece spans the
    # view's eight samples, to 1.0007, and the step may take the load to its end, the
    # view's last sample (no further: `test_a_step_never_carries_the_load_past_what_the_
    # next_view_can_find`). A hundredth of the distance from the load (1.01 times it, as
    # within a piece) reached 1.0057, past more samples than the next step's view holds:
    # that view lost the load, and its step length was zero for good.
    points = [1.0 + 1e-4 * k for k in range(60)] + [2.0]
    past = _past(points, 0.5, 0.6)
    end = float(past.origin + past.width)
    assert float(past.origin) == 1.0 and end == pytest.approx(1.0007, rel=1e-12)
    assert 0.5 + float(past.room) == pytest.approx(end, rel=1e-12)
    # Short of the view's last sample, a piece is passed by a hundredth of itself.
    points = [1.0 + 1e-4 * k for k in range(5)] + [2.0, 3.0, 4.0, 5.0]
    past = _past(points, 0.5, 0.45)
    end = float(past.origin + past.width)
    assert end == pytest.approx(1.0004, rel=1e-12)
    assert 0.5 + float(past.room) == pytest.approx(end + 0.01 * (end - 1.0), rel=1e-12)


def test_a_cluster_of_short_intervals_is_spanned_by_one_piece():
    # Samples recorded in steps a thousandth of the load's: the piece runs from the
    # interval holding the load over the short ones to 1.004, and the step may cross into
    # the long interval after it.
    points = [0.0, 1.0, 1.001, 1.002, 1.004, 2.0, 3.0]
    past = _past(points, 1.0005, 0.5)
    assert float(past.origin) == 1.0 and float(past.width) == pytest.approx(0.004, rel=1e-12)
    assert bool(past.crossing) and float(past.joint) == 1.004
    assert float(past.room) == pytest.approx(1.01 * (2.0 - 1.0005), rel=1e-12)
    _, slope = slope_memory(past, jnp.asarray(1.5), 0.0)
    assert float(slope) == pytest.approx(_interval_quintic(points, 4, 5, 1.5), abs=1e-13)
    # With no short interval, no span: the same cluster read by a step of 0.005.
    short_step = _past(points, 1.0005, 0.005)
    assert float(short_step.width) == pytest.approx(0.001, rel=1e-9)


def test_a_step_never_carries_the_load_past_what_the_next_view_can_find():
    # The crushing phase of a force ratio near 1 (mass ratio 8.2, phi 1.011, rtol 1e-9):
    # where the load crossed S*, the steps restarted short, and the hinge recorded a
    # cluster of intervals of 1e-6, more of them than a view holds. Later the load comes
    # up to it in steps of 0.02. The piece spans the view's samples of the cluster, and
    # 1.01 times the distance to its end reached past the rest of the cluster: the next
    # step's view (from the last sample of this one's) held none beyond the load, its room
    # was zero and the solve stalled. The load now stays within its step's view.
    points = [0.0, 1.0, 1.5, 2.0] + [2.0 + 1e-6 * k for k in range(1, 21)] + [3.0]
    stage = SimpleNamespace(first=jnp.asarray(0, jnp.int32), last=jnp.asarray(64, jnp.int32))
    recording = _trace(points)
    view = lambda x, previous=None: read_past(
        SimpleNamespace(position=jnp.asarray(x)),
        SimpleNamespace(position=jnp.asarray(0.6)),
        1.0,
        stage,
        recording,
        previous,
    )
    past = view(1.6)
    last = float(np.max(past.hinge[np.isfinite(past.hinge)]))
    assert last == pytest.approx(2.000006, rel=1e-12)
    assert float(past.origin + past.width) == last and 1.6 + float(past.room) == last
    following = view(1.6 + float(past.room), past)
    assert float(following.origin) <= last and float(following.room) > 0.0
