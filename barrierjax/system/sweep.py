"""Sweeps of a barrier-system scene (`barrierjax.sweep` for the files, the chunks and the
resumption): the keys a sweep may vary and the batch's solve, one `vmap` of
`design.crash_numbers` over the varied impact and design parameters."""

from collections.abc import Callable

import jax

from ..sharding import sharded_batch
from .barrier import stable_step
from .design import crash_numbers, redesign
from .scene import FIELDS, SystemScene
from .vehicle import contact_stiffness_bound

# The keys a system sweep varies: the impact's, and the design parameters `redesign` takes.
SWEEP_FIELDS = {
    "impact": {k: FIELDS["impact"][k] for k in ("speed", "angle", "point")},
    "vehicle": {"mass": FIELDS["vehicle"]["mass"]},
    "barrier": {k: FIELDS["barrier"][k] for k in ("post_spacing", "post_strength")},
}
_DESIGN = {"vehicle.mass": "vehicle_mass", "barrier.post_spacing": "post_spacing",
           "barrier.post_strength": "post_strength"}  # fmt: skip


def system_solver(s: SystemScene, varies) -> Callable:
    """The solve of a chunk of rows (n, len(varies)) of `s`: every crash-test number of
    `crash_numbers`, one column each. The step is the stable step of the shortest post
    spacing the sweep reaches."""
    keys = [v.key for v in varies]
    spacing = next((v.low for v in varies if v.key == "barrier.post_spacing"), None)
    _, stiffest = redesign(s.vehicle, s.barrier, post_spacing=spacing)
    dt = stable_step(stiffest, contact_stiffness_bound(s.vehicle))

    def one(row):
        value = dict(zip(keys, row, strict=True))
        design = {name: value[key] for key, name in _DESIGN.items() if key in value}
        vehicle, barrier = redesign(s.vehicle, s.barrier, **design)
        return crash_numbers(vehicle, barrier, speed=value.get("impact.speed", s.speed),
                             angle_deg=value.get("impact.angle", s.angle_deg),
                             impact_point=value.get("impact.point", s.impact_point),
                             duration=s.duration, dt=dt, friction=s.friction)  # fmt: skip

    # A row costs about half a second: parts of 16 rows pay for their thread many times
    # over (a chunk of 64 MASH 3-11 rows on 2 cores: 40.9 s whole, 27.2 s in two parts).
    return sharded_batch(jax.vmap(one), part_size=16)


def scene_numbers(s: SystemScene) -> list:
    """The scene's parts' leaves and the impact's numbers, for a sweep's manifest."""
    return [*jax.tree.leaves((s.vehicle, s.barrier)),
            s.speed, s.angle_deg, s.impact_point, s.duration, s.friction]  # fmt: skip
