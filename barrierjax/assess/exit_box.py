"""Exit boxes (MASH 2016; EN 1317-2 "CEN box"): after the vehicle loses contact with the
barrier, its path must stay within a line parallel to the barrier's original traffic face,
at the box's width A, over the box's length B downstream of the loss of contact. The box
dimensions, with their sources, are `barrierjax.assess.matrices.EXIT_BOXES`
(`mash_exit_box`, `cen_exit_box`).

`exit_box_check` judges a sampled path of the vehicle's wheel track farthest from the
barrier, linear between its samples; past its last sample the path runs on straight.
`result_exit_box` judges an oblique impact's result: the report's vehicle leaves the
barrier with its exit speed and angle and moves on straight (nothing acts on it after the
loss of contact, where its history ends); it is a point that does not turn, so its far
wheel track is taken at the vehicle's width from the barrier's face at contact, moving
with the point.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
from jaxtyping import Array, Bool, Float

from .. import _checks
from . import matrices

__all__ = ["ExitBoxCheck", "exit_box_check", "result_exit_box"]


class ExitBoxCheck(eqx.Module):
    """`passed`: the path stays within the box; `largest_offset`: the path's largest
    distance from the barrier's original face within the box's length, m; `margin`:
    the box's width less it (negative where it leaves the box)."""

    passed: Bool[Array, ""]
    largest_offset: Float[Array, ""]
    margin: Float[Array, ""]


def exit_box_check(along, offset, width_a, length_b) -> ExitBoxCheck:
    """Judge a path (`along` the barrier from the loss of contact and `offset` from its
    original traffic face, m, samples from the loss of contact on; at least 2) against
    a box A = `width_a` by B = `length_b` (m). Differentiable in the path and the box."""
    width_a = _checks.positive("width_a", width_a)
    length_b = _checks.positive("length_b", length_b)
    along, offset = jnp.asarray(along), jnp.asarray(offset)
    if along.shape != offset.shape or along.ndim != 1 or along.shape[0] < 2:
        raise ValueError(
            f"along and offset must be 1-D paths of the same length >= 2; got {along.shape}, {offset.shape}"
        )
    return _judged(along, offset, width_a, length_b)


@jax.jit
def _judged(along, offset, width_a, length_b) -> ExitBoxCheck:
    """`exit_box_check`'s judgement: one program (operation by operation, some twenty small
    programs to compile in each new process)."""
    travelled = along - along[0]
    # The path is judged up to where it first passes B, and at B itself: linear between
    # the samples either side (the sample before it alone under-reads a rising path by up
    # to a sample's rise), or, where the samples end short of B, along their last direction.
    beyond = travelled > length_b
    crossed = jnp.any(beyond)
    last = along.shape[0] - 1
    hi = jnp.where(crossed, jnp.argmax(beyond), last)
    lo = hi - 1
    run = travelled[hi] - travelled[lo]
    still = run == 0.0  # (a vehicle at rest: its path goes no further)
    slope = jnp.where(still, 0.0, (offset[hi] - offset[lo]) / jnp.where(still, 1.0, run))
    at_box_end = offset[lo] + slope * (length_b - travelled[lo])
    inside = jnp.cumsum(beyond) == 0
    largest = jnp.maximum(jnp.max(jnp.where(inside, offset, -jnp.inf)), at_box_end)
    return ExitBoxCheck(passed=largest <= width_a, largest_offset=largest, margin=width_a - largest)


def result_exit_box(result, vehicle_length, vehicle_width, box: str = "MASH") -> ExitBoxCheck:
    """The exit-box check of an oblique impact's `simulate` result (with its history),
    for a vehicle of `vehicle_length` and `vehicle_width` (m) and the box "MASH",
    "CEN car" or "CEN heavy" (`matrices.EXIT_BOXES`)."""
    if box not in matrices.EXIT_BOXES:
        raise ValueError(f"box must be one of {', '.join(matrices.EXIT_BOXES)}; got {box!r}")
    vehicle_length = _checks.positive("vehicle_length", vehicle_length)
    vehicle_width = _checks.positive("vehicle_width", vehicle_width)
    history = result.history
    if history is None:
        raise ValueError(
            "result_exit_box: the result has no history: simulate(scene, n_history>=2)"
        )
    spec = matrices.EXIT_BOXES[box]
    width_a = spec.offset + vehicle_width + spec.length_factor * vehicle_length
    exit_offset = vehicle_width - history.vehicle_displacement[-1]
    rise = spec.downstream * jnp.tan(jnp.radians(result.exit_angle_deg))
    # Measured from the loss of contact, not from the vehicle's position there: (x + B) - x
    # rounds above B for one x in five, and the box's far end then fell outside the box.
    along = jnp.stack([jnp.zeros_like(rise), jnp.full_like(rise, spec.downstream)])
    return exit_box_check(
        along, jnp.stack([exit_offset, exit_offset + rise]), width_a, spec.downstream
    )
