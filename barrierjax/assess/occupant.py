"""`occupant_risk`: every occupant-risk metric of a crash test from one record of the
vehicle's accelerations, as MASH 2016 (OIV, ORA), NCHRP Report 350 (the same) and EN 1317-1
(ASI, THIV, PHD) define them.

The record: uniformly sampled times `t` (s) and the acceleration of the vehicle's centre of
gravity on its own axes, `ax` forward and `ay` to the left (m/s^2; a frontal impact gives
negative `ax`), with the yaw rate (rad/s, positive to the left) and the vertical
acceleration where measured. The channels are read as given: condition them first as the
standard prescribes (`barrierjax.assess.filters.cfc_filter`; `barrierjax assess` applies CFC
180). Pure JAX: `jit`, `vmap` and `grad` go through it (`t` stays concrete: it fixes the
filters' padding); leading batch axes of the accelerations are mapped over.
"""

import functools
import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer
from jaxtyping import Array, Bool, Float

from .. import _checks
from ..compilation_cache import stored_program
from .asi import EDITIONS, asi_history
from .flail import FLAIL_X, FLAIL_Y, flail_space, ridedown
from .head import head_impact, post_impact_head_deceleration

__all__ = ["OccupantRisk", "occupant_risk", "record_size", "sampling_step"]

Metric = Float[Array, "..."]


class OccupantRisk(eqx.Module):
    """The occupant-risk metrics of one record (or a batch), SI.

    - `t_impact`: occupant impact (flail space), s from the record's first sample; +inf if
      the occupant never moves relative to the vehicle.
    - `oiv_x`, `oiv_y`: occupant impact velocity relative to the vehicle, m/s, signed on
      the vehicle's axes (positive forward and to the left); the standards judge |OIV|.
    - `ora_x`, `ora_y`: ridedown acceleration, the largest |10 ms average| after the
      occupant impact, m/s^2.
    - `t_head`, `thiv`: the theoretical head's impact (with the yaw) and its speed
      relative to the vehicle then, m/s (EN 1317 prints km/h: x 3.6).
    - `phd`: post-impact head deceleration, m/s^2 (informative since EN 1317-2:2010).
    - `asi`: acceleration severity index, dimensionless.
    - `impact_in_record`, `head_impact_in_record`: whether the impacts fall within the
      record. If not, the vehicle was taken to move on unaccelerated after it (right for a
      model's history, which ends at rest or at exit; a measured record too short to reach
      the occupant impact is refused by `barrierjax assess`).
    """

    t_impact: Metric
    oiv_x: Metric
    oiv_y: Metric
    ora_x: Metric
    ora_y: Metric
    t_head: Metric
    thiv: Metric
    phd: Metric
    asi: Metric
    impact_in_record: Bool[Array, "..."]
    head_impact_in_record: Bool[Array, "..."]


def sampling_step(t) -> float:
    """The step of the uniformly sampled, concrete times `t`, to 12 significant digits
    (ValueError naming `t` if they are not uniformly sampled)."""
    if isinstance(t, Tracer):
        raise ValueError(
            "t must be concrete (not traced under jit or vmap): the step fixes the filters' "
            "padding; close over t, or batch the accelerations only"
        )
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 3:
        raise ValueError(f"t must be a 1-D array of at least 3 samples; got shape {t.shape}")
    if not np.all(np.isfinite(t)):
        raise ValueError("t must be finite (no NaN or inf)")
    steps = np.diff(t)
    if np.any(steps <= 0):
        raise ValueError(f"t must be strictly increasing (sample {int(np.argmax(steps <= 0)) + 1})")
    dt = (t[-1] - t[0]) / (t.size - 1)
    if np.max(np.abs(steps - dt)) > 1e-6 * dt:
        raise ValueError(
            f"t must be uniformly sampled (steps from {steps.min():g} to {steps.max():g} s)"
        )
    # To 12 digits (5e-13 relative at most, where uniform means within 1e-6): records of
    # one sampling rate then share one compiled program whatever the rounding in their
    # times (10 kHz came out as 1e-4 and as 9.999999999999999e-05).
    return float(f"{dt:.12g}")


def record_size(n: int) -> int:
    """The length a record of `n` samples is padded to (with zeros, read as past its end):
    the first of 64, 96, 128, 192, 256, 384, ... (2^k and 3 2^(k-1)) that holds it, so
    that records of nearby lengths share one compiled program, at most half again as long.
    A model's history of another duration, or another crash test's record, then compiles
    nothing new (`_records` took 0.5 s to compile for each length, 2 cores)."""
    size = 64
    while size < n:
        size = size * 3 // 2 if size & (size - 1) == 0 else size * 4 // 3
    return size


def _padded(x, size: int):
    """`x` with zeros after its last sample (last axis) up to `size` samples: in NumPy
    where concrete (no JAX program to compile), in JAX where traced."""
    widths = [(0, 0)] * (np.ndim(x) - 1) + [(0, size - np.shape(x)[-1])]
    return jnp.pad(x, widths) if isinstance(x, Tracer) else np.pad(np.asarray(x), widths)


@stored_program
@functools.partial(jax.jit, static_argnames=("dt", "edition"))
def _records(ax, ay, yaw_rate, az, flail_x, flail_y, t0, n_real, *, dt, edition):
    """`_one_record` of each record (the channels' last axis, padded after the first
    `n_real` samples; their leading axes a batch that broadcasts): one executable per
    padded shape and step (the start time `t0` and the length `n_real` arguments: records
    that start at other times, or of other lengths padded alike, share it), broadcasts and
    reshapes included."""
    channels = ax, ay, yaw_rate, az
    shape = jnp.broadcast_shapes(*(c.shape for c in channels if c is not None))
    rows = lambda c: None if c is None else jnp.broadcast_to(c, shape).reshape(-1, shape[-1])
    one = functools.partial(_one_record, dt=dt, edition=edition)
    in_axes = (0, 0, 0, 0, None, None, None, None)
    risk = jax.vmap(one, in_axes=in_axes)(*map(rows, channels), flail_x, flail_y, t0, n_real)
    return jax.tree.map(lambda leaf: leaf.reshape(shape[:-1]), risk)


def _one_record(ax, ay, yaw_rate, az, flail_x, flail_y, t0, n_real, *, dt, edition):
    # The record is its first n_real samples; after them the vehicle moves on freely, as
    # after any record: its accelerations zero, the occupant's and the head's paths straight.
    real = jnp.arange(ax.shape[-1], dtype=n_real.dtype) < n_real
    ax, ay, yaw_rate, az = (
        None if c is None else jnp.where(real, c, 0.0) for c in (ax, ay, yaw_rate, az)
    )
    end = (n_real - 1).astype(ax.dtype) * dt
    t_impact, oiv, in_record = flail_space(ax, ay, dt, flail_x, flail_y, n_real)
    ora_x, ora_y = ridedown(ax, ay, dt, t_impact, end=end)
    if yaw_rate is None:  # the head moves as the flail-space occupant
        t_head, thiv, head_in_record = t_impact, jnp.hypot(oiv[0], oiv[1]), in_record
    else:
        t_head, thiv, head_in_record = head_impact(
            ax, ay, yaw_rate, dt, flail_x, flail_y, n_real
        )
    asi = jnp.where(real, asi_history(ax, ay, az, dt, edition, end), 0.0)
    return OccupantRisk(
        t_impact=t0 + t_impact,
        oiv_x=oiv[0],
        oiv_y=oiv[1],
        ora_x=ora_x,
        ora_y=ora_y,
        t_head=t0 + t_head,
        thiv=thiv,
        phd=post_impact_head_deceleration(ax, ay, dt, t_head, end=end),
        asi=jnp.max(asi),  # az None: two channels
        impact_in_record=in_record,
        head_impact_in_record=head_in_record,
    )


def occupant_risk(
    t,
    ax,
    ay,
    yaw_rate=None,
    az=None,
    *,
    asi_edition: str = "2010",
    flail_x: float = FLAIL_X,
    flail_y: float = FLAIL_Y,
) -> OccupantRisk:
    """The occupant-risk metrics of a crash-test record (`OccupantRisk`).

    **Arguments:**

    - `t`: sample times, s, uniformly spaced (concrete), shape (n,).
    - `ax`, `ay`: the vehicle's accelerations on its forward and left axes, m/s^2, shape
      (..., n); leading axes are a batch of records.
    - `yaw_rate`: rad/s, positive to the left; None for none (the head model then moves
      as the flail-space occupant, and THIV = |OIV|).
    - `az`: vertical acceleration, m/s^2, for the ASI; None for none.
    - `asi_edition`: "2010" (EN 1317-1:2010, 13 Hz filter; the default) or "1998" (50 ms
      average).
    - `flail_x`, `flail_y`: the flail distances, m (0.6 and 0.3 in every standard).

    Differentiable in the accelerations (and the flail distances) wherever the impact's
    crossing and the largest averages are unique; the impact times are roots of the
    interpolated motion, not sample indices.
    """
    if asi_edition not in EDITIONS:
        raise ValueError(f"asi_edition must be one of {EDITIONS}; got {asi_edition!r}")
    dt = sampling_step(t)
    t0 = float(np.asarray(t, dtype=float)[0])
    given = {"ax": ax, "ay": ay, "yaw_rate": yaw_rate, "az": az}
    channels = {name: x for name, x in given.items() if x is not None}
    for name, x in channels.items():
        if np.shape(x)[-1:] != np.shape(t):
            raise ValueError(
                f"{name} must have the samples of t on its last axis ({len(t)}); got shape {np.shape(x)}"
            )
    finite = lambda x: abs(x) < math.inf  # NumPy's on a concrete record, JAX's on a traced one
    size = record_size(len(t))
    channels = {
        name: _checks.check(name, _padded(x, size), finite, "finite (no NaN or inf)")
        for name, x in channels.items()
    }
    return _records(
        channels["ax"],
        channels["ay"],
        channels.get("yaw_rate"),
        channels.get("az"),
        _checks.positive("flail_x", flail_x),
        _checks.positive("flail_y", flail_y),
        _checks.float_array(t0),
        jax.device_put(np.int32(len(t))),
        dt=dt,
        edition=asi_edition,
    )
