"""What a crash test judges, from a `system_impact` result: the occupant risk of the
vehicle's c.g. accelerations and yaw rate (`barrierjax.assess.occupant_risk`), containment
and redirection, and the numbers a test report lists (`summary`)."""

import jax.numpy as jnp
import numpy as np

from ..assess import ExitBoxCheck, OccupantRisk, exit_box_check, occupant_risk
from ..assess.matrices import cen_exit_box, mash_exit_box
from .impact import SystemResult
from .vehicle import Vehicle, outline, rotation


def system_occupant_risk(result: SystemResult, times=None, **options) -> OccupantRisk:
    """`occupant_risk` of the vehicle's accelerations (its axes: x forward, y left) and yaw
    rate over the run (or each run of a batch); `times`: the samples' times where the
    result is traced (under a caller's jit, vmap or grad: `impact.time_grid`); `options` go
    to `occupant_risk` (e.g. `asi_edition`)."""
    h = result.history
    # A batch of runs (a vmap of `system_impact`) shares its times: the first row's.
    t = h.time[(0,) * (h.time.ndim - 1)] if times is None else times
    return occupant_risk(t, h.acceleration[..., 0], h.acceleration[..., 1], h.yaw_rate,
                         **options)  # fmt: skip


def contained(result: SystemResult):
    """Contained and redirected: at the end the vehicle's c.g. is on the road side of the
    rail's line (y < 0) and moves away from it, or has come to rest."""
    h = result.history
    leaving = h.velocity[..., -1, 1] < 0.0
    at_rest = result.exit_speed < 0.5
    return (h.position[..., -1, 1] < 0.0) & (leaving | at_rest)


def summary(result: SystemResult, risk: OccupantRisk | None = None) -> dict:
    """The crash-test numbers of a run, SI: contained, exit speed and angle (degrees, of the
    c.g.'s velocity to the rail; negative: towards the road), dynamic deflection, working
    width, and the occupant risk (OIV, ORA, ASI, THIV, PHD; `risk`, where the caller has
    it already: `system_occupant_risk(result)`)."""
    risk = system_occupant_risk(result) if risk is None else risk
    values = {
        "contained": contained(result),
        "exit_speed": result.exit_speed,
        "exit_angle": result.exit_angle_deg,
        "dynamic_deflection": result.dynamic_deflection,
        "working_width": result.working_width,
        "oiv_x": risk.oiv_x,
        "oiv_y": risk.oiv_y,
        "ora_x": risk.ora_x,
        "ora_y": risk.ora_y,
        "asi": risk.asi,
        "thiv": risk.thiv,
        "phd": risk.phd,
    }
    return {key: jnp.asarray(value) for key, value in values.items()}


def system_exit_box(
    result: SystemResult, vehicle: Vehicle, box: str = "MASH"
) -> ExitBoxCheck | None:
    """The exit-box check (`assess.exit_box_check`; MASH's box, or EN 1317's "CEN car" or
    "CEN heavy") of the vehicle's outline after it loses contact with the barrier: its
    furthest point towards the road at each saved time, from the last saved contact on
    (extended along its last direction where the run ends short of the box's length).
    None where the vehicle is still in contact at the end of the run. Concrete results
    only (the loss of contact is found in numpy)."""
    h = result.history
    in_contact = np.flatnonzero(np.asarray(h.contact_force) > 0.0)
    if in_contact.size == 0 or in_contact[-1] >= h.time.shape[0] - 2:
        return None
    start = in_contact[-1] + 1
    corners = np.asarray(outline(vehicle))
    positions, yaws = np.asarray(h.position)[start:], np.asarray(h.yaw)[start:]
    nearest_road = np.array([np.min((corners @ np.asarray(rotation(p)).T + x)[:, 1])
                             for x, p in zip(positions, yaws)])  # fmt: skip
    L, width = float(np.asarray(vehicle.length)), float(np.asarray(vehicle.width))
    if box == "MASH":
        width_a, length_b = mash_exit_box(L, width)
    else:
        width_a, length_b = cen_exit_box(L, width, heavy=box == "CEN heavy")
    return exit_box_check(positions[:, 0], -nearest_road, width_a, length_b)
