"""What a crash test judges, from a `system_impact` result: the occupant risk of the
vehicle's c.g. accelerations and yaw rate (`barrierjax.assess.occupant_risk`), containment
and redirection, and the numbers a test report lists (`summary`)."""

import jax.numpy as jnp

from ..assess import OccupantRisk, occupant_risk
from .impact import SystemResult


def system_occupant_risk(result: SystemResult, **options) -> OccupantRisk:
    """`occupant_risk` of the vehicle's accelerations (its axes: x forward, y left) and yaw
    rate over the run; `options` go to `occupant_risk` (e.g. `asi_edition`)."""
    h = result.history
    return occupant_risk(h.time, h.acceleration[..., 0], h.acceleration[..., 1],
                         h.yaw_rate, **options)  # fmt: skip


def contained(result: SystemResult):
    """Contained and redirected: at the end the vehicle's c.g. is on the road side of the
    rail's line (y < 0) and moves away from it, or has come to rest."""
    h = result.history
    leaving = h.velocity[-1, 1] < 0.0
    at_rest = result.exit_speed < 0.5
    return (h.position[-1, 1] < 0.0) & (leaving | at_rest)


def summary(result: SystemResult) -> dict:
    """The crash-test numbers of a run, SI: contained, exit speed and angle (degrees, of the
    c.g.'s velocity to the rail; negative: towards the road), dynamic deflection, working
    width, and the occupant risk (OIV, ORA, ASI, THIV, PHD)."""
    risk = system_occupant_risk(result)
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
