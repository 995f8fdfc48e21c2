"""The critical impact point: the place along the rail where an impact is worst for a
criterion (BARRIER VII's users sweep it by hand; MASH asks the test at the critical impact
point). The impact points are run as one `vmap` of `system_impact`."""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .assessment import summary
from .barrier import Guardrail
from .impact import system_impact

CRITERIA = ("dynamic_deflection", "working_width", "oiv", "ora", "asi", "thiv")


class ImpactPointSweep(eqx.Module):
    points: jnp.ndarray  # (n,) m along the rail
    values: jnp.ndarray  # (n,) the criterion at each
    critical: jnp.ndarray  # the point where it is largest
    numbers: dict  # every crash-test number of `assessment.summary` at each point, (n,)
    criterion: str = eqx.field(static=True)


def _criterion(numbers: dict, criterion: str):
    if criterion == "oiv":
        return jnp.hypot(numbers["oiv_x"], numbers["oiv_y"])
    if criterion == "ora":
        return jnp.maximum(jnp.abs(numbers["ora_x"]), jnp.abs(numbers["ora_y"]))
    return numbers[criterion]


def critical_impact_point(vehicle, barrier, points, *, speed, angle_deg, duration,
                          criterion="dynamic_deflection", **options) -> ImpactPointSweep:  # fmt: skip
    """`system_impact` at each of `points` (m along the rail; one `vmap`), and where
    `criterion` (one of `CRITERIA`; "oiv": the resultant, "ora": the larger component) is
    largest. `options` go to `system_impact` (dt, friction, save_every)."""
    if criterion not in CRITERIA:
        raise ValueError(f"criterion must be one of {CRITERIA}; got {criterion!r}")
    points = jnp.asarray(points, float)
    if points.ndim != 1 or points.shape[0] < 1:
        raise ValueError(f"points must be a 1-d array of impact points; got shape {points.shape}")
    if isinstance(barrier, Guardrail):
        length = float(np.asarray(barrier.rail.coords)[-1, 0])
        if not np.all((np.asarray(points) > 0) & (np.asarray(points) < length)):
            raise ValueError(f"points must lie on the rail, in (0, {length:g}) m; got {points}")

    def one(point):
        return system_impact(vehicle, barrier, speed=speed, angle_deg=angle_deg,
                             impact_point=point, duration=duration, **options)  # fmt: skip

    # The runs in one vmap; the occupant risk after it (its times must be concrete).
    numbers = summary(jax.jit(jax.vmap(one))(points))
    values = _criterion(numbers, criterion)
    return ImpactPointSweep(points, values, points[jnp.argmax(values)], numbers, criterion)
