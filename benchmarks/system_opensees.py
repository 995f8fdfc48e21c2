"""The barrier-system run against OpenSees: the same rail and posts under the same contact
forces.

    python benchmarks/system_opensees.py [--quick] [--out DIR]

MASH 3-11 on the MGS (`examples/mash_3_11.toml`, 0.6 s of impact, the scene's mesh, the
rail's stable step): barrierjax's run gives the contact's force on every rail node at every
step (`history.contact_on_rail`); OpenSees (`_opensees_guardrail.py`, the same elements,
sections, masses, posts and anchors, explicit central differences at the same step) is
driven by that history; twice, with the MGS's posts (failing at 0.4 m: barrierjax drops a
failed post's longitudinal force with its lateral one, OpenSees's springs fail one by one)
and with posts that never fail (the same model in both). Compared: the rail's lateral displacements at every node every 20
steps, the largest deflection and the posts' forces; and the wall time of OpenSees's run of
the rail alone against barrierjax's run of the whole impact (vehicle, contact, rail, after
compilation). Then, with the posts that never fail, OpenSees's explicit run against its
implicit Newmark (average acceleration) at 4, 16 and 64 times the stable step: the error
against barrierjax's explicit run, and the time. `--quick`: 0.2 s of impact. Writes `system_opensees.json` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

from pathlib import Path
from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from _opensees_guardrail import run_guardrail
from harness import argument_parser, steady, table, write_json

from barrierjax.system import stable_step, system_impact
from barrierjax.system.scene import load_system_scene
from barrierjax.system.vehicle import contact_stiffness_bound

SCENE = Path(__file__).resolve().parent.parent / "examples" / "mash_3_11.toml"
RECORD_EVERY = 20


class Recorded(NamedTuple):
    """barrierjax's run of the impact kept at every step: its step and options, the
    contact's forces on the rail, the rail's lateral displacements and the posts' forces."""

    dt: float
    options: dict
    forces: np.ndarray
    deflection: np.ndarray
    post_force: np.ndarray


def record(s, barrier, duration) -> Recorded:
    dt = stable_step(barrier, contact_stiffness_bound(s.vehicle))
    options = {"speed": s.speed, "angle_deg": s.angle_deg, "impact_point": s.impact_point,
               "duration": duration, "friction": s.friction, "dt": dt}  # fmt: skip
    h = system_impact(s.vehicle, barrier, save_every=1, **options).history
    return Recorded(dt, options, *(np.asarray(x) for x in (h.contact_on_rail,
                                                           h.rail_deflection, h.post_force)))  # fmt: skip


def compare(s, barrier, recorded: Recorded):
    """barrierjax's run of the impact, and OpenSees's of its rail under the run's contact
    forces: one table row."""
    dt, options, forces = recorded.dt, recorded.options, recorded.forces
    ours = recorded.deflection[::RECORD_EVERY]
    our_posts = recorded.post_force[::RECORD_EVERY]

    def run():
        return jax.block_until_ready(system_impact(s.vehicle, barrier, **options))

    run()
    barrierjax_s = steady(run, reps=3)
    reference = run_guardrail(barrier, forces, dt, RECORD_EVERY)
    n = min(len(ours), len(reference.lateral))
    theirs, their_posts = reference.lateral[:n], reference.post_force[:n]
    ours, our_posts = ours[:n], our_posts[:n]
    peak, post_peak = float(np.max(np.abs(ours))), float(np.max(np.abs(our_posts)))
    row = {
        "steps": forces.shape[0],
        "nodes": forces.shape[1],
        "dt": dt,
        "peak_barrierjax": peak,
        "peak_opensees": float(np.max(np.abs(theirs))),
        "largest_difference": float(np.max(np.abs(theirs - ours))) / peak,
        "post_difference": float(np.max(np.abs(their_posts - our_posts))) / post_peak,
        "barrierjax_s": barrierjax_s,
        "opensees_s": reference.analysis_seconds,
        "opensees_build_s": reference.build_seconds,
    }
    return row | {"speedup": row["opensees_s"] / row["barrierjax_s"]}


def main():
    args = argument_parser(__doc__).parse_args()
    s = load_system_scene(SCENE)
    duration = 0.2 if args.quick else 0.6
    lasting = eqx.tree_at(lambda g: g.posts.failure, s.barrier, jnp.asarray(10.0))
    lasting_run = record(s, lasting, duration)  # for the comparison and for the schemes
    rows = [
        {"posts": "MGS (fail at 0.4 m)"} | compare(s, s.barrier, record(s, s.barrier, duration)),
        {"posts": "never failing"} | compare(s, lasting, lasting_run),
    ]
    table(
        f"MASH 3-11 rail and posts, {duration} s: barrierjax (whole impact) against OpenSees "
        f"(rail and posts under barrierjax's contact forces, recorded every {RECORD_EVERY} "
        f"steps)",
        rows,
        [("posts", "posts", "s"), ("steps", "steps", "d"), ("nodes", "nodes", "d"),
         ("peak m", "peak_barrierjax", ".4f"), ("OpenSees peak m", "peak_opensees", ".4f"),
         ("largest diff / peak", "largest_difference", ".1e"),
         ("post force diff / peak", "post_difference", ".1e"),
         ("barrierjax s", "barrierjax_s", ".2f"), ("OpenSees s", "opensees_s", ".1f"),
         ("OpenSees / barrierjax", "speedup", ".1f")],
    )  # fmt: skip
    schemes = newmark_rows(lasting, lasting_run, (4, 16) if args.quick else (4, 16, 64))
    table(
        "Explicit central differences or implicit Newmark (OpenSees, posts that never fail): "
        "the rail's displacements against barrierjax's explicit run",
        schemes,
        [("scheme", "scheme", "s"), ("step s", "dt", ".3g"), ("steps", "steps", "d"),
         ("largest diff / peak", "difference", ".1e"), ("OpenSees s", "seconds", ".1f")],
    )  # fmt: skip
    write_json(args, "system_opensees", {"comparison": rows, "schemes": schemes})


def newmark_rows(barrier, recorded: Recorded, multiples):
    """OpenSees's explicit run and its Newmark runs at `multiples` of the stable step, under
    barrierjax's contact forces, against barrierjax's explicit run."""
    dt, forces = recorded.dt, recorded.forces
    every = 64  # a multiple of every Newmark step
    ours = recorded.deflection[::every]
    rows = []
    for k in (None, *multiples):
        r = run_guardrail(barrier, forces, dt, every, newmark_every=k)
        n = min(len(ours), len(r.lateral))
        difference = np.max(np.abs(r.lateral[:n] - ours[:n])) / np.max(np.abs(ours))
        rows.append({"scheme": "central differences" if k is None else "Newmark",
                     "dt": dt * (k or 1), "steps": forces.shape[0] // (k or 1),
                     "difference": float(difference), "seconds": r.analysis_seconds})  # fmt: skip
    return rows


if __name__ == "__main__":
    main()
