"""`simulate(scene)`: the response of a scene in the scene's own units.

The scene is reduced to the report's groups once (`scene.dimensionless`), the model that
the scene's physics calls for is run in dimensionless form, and its result, in the one
vocabulary of `barrierjax.hinge.response`, is scaled back once, field by field. Dispatch
is static: a normal impact without axial force compiles only the model of report 3.2.
"""

from typing import Literal

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jax.core import Tracer
from jaxtyping import Array, Float

from . import _checks
from ._custom_types import Batchable
from ._solve.phases import SolveError
from .compilation_cache import stored_program
from .hinge.axial import axial_impact
from .hinge.normal import NormalImpact, normal_impact
from .hinge.oblique import ObliqueImpact, oblique_impact
from .hinge.response import HISTORY_UNITS, RESULT_UNITS, ImpactHistory, ImpactResult
from .scene import Dimensionless, Scene, dimensionless

Series = Float[Array, " n"]


class History(ImpactHistory):
    """Time histories in the scene's units: the fields of
    `barrierjax.hinge.response.ImpactHistory`, scaled.

    A normal impact has `n_history` samples per phase of its mechanism, and its vehicle
    stays at the impact point (no tangential velocity or position); an oblique one
    `n_history` in all, equally spaced in time. `x` is, in a normal impact, the distance
    from the impact point (the shape is symmetric about it); in an oblique one, the
    position along the barrier from the impact point, in the vehicle's direction of
    travel."""


class Result(ImpactResult):
    """The response of a scene, in the scene's units: the fields of
    `barrierjax.hinge.response.ImpactResult` (every impact model's), scaled, and

    - `kinetic_energy`: the vehicle's initial kinetic energy;
    - `peak_force`, `peak_deceleration`: largest contact force and vehicle deceleration;
    - `groups`: the scene's dimensionless groups and scales;
    - `model`: the dimensionless model result;
    - `history`: a `History`, or None when `n_history=0`.

    A normal impact's vehicle comes to rest with the barrier (`exit_speed` and
    `exit_angle_deg` zero) and nothing slides (`friction_work`, `slope_work` zero);
    `string_work` is nonzero with `Barrier.axial_capacity` alone (report 3.4.45).
    """

    kinetic_energy: Batchable
    peak_force: Batchable
    peak_deceleration: Batchable
    groups: Dimensionless
    model: NormalImpact | ObliqueImpact
    history: History | None


def _is_normal(scene: Scene, oblique: bool | None) -> bool:
    """Static dispatch. With `oblique=None`, a concrete angle below 90 degrees takes the
    oblique model; a traced angle (under `jit` or `vmap`) takes the normal one and must
    be 90 degrees at run time, so that a normal sweep never pays for the oblique model.
    `oblique=True` forces the oblique model (which also covers 90 degrees)."""
    if oblique is not None:
        normal = not oblique
    else:
        angle = scene.impact.angle_deg
        normal = isinstance(angle, Tracer) or bool(np.all(np.asarray(angle) == 90.0))
    if scene.barrier.axial_capacity is not None and not normal:
        raise NotImplementedError(
            "Barrier.axial_capacity is set for an oblique impact: the axial-force model of "
            "report 3.4 is a normal impact's; leave axial_capacity=None or strike at 90 degrees"
        )
    return normal


def _require_normal_angle(scene: Scene) -> Scene:
    message = (
        "Impact.angle_deg must be 90 for the normal-impact model; under jit or vmap pass "
        "simulate(..., oblique=True) to sweep oblique angles"
    )
    angle = scene.impact.angle_deg
    if isinstance(angle, Tracer):
        checked = eqx.error_if(angle, jnp.any(angle != 90.0), message)
        return eqx.tree_at(lambda s: s.impact.angle_deg, scene, checked)
    if not np.all(np.asarray(angle) == 90.0):
        raise ValueError(message)
    return scene


def simulate(
    scene: Scene,
    *,
    method: Literal["closed_form", "ode"] = "closed_form",
    rtol: float | None = None,
    n_history: int = 200,
    oblique: bool | None = None,
    max_steps: int | None = None,
) -> Result:
    """The response of `scene` in its own units; `n_history=0` skips the histories, and
    `rtol=None` takes each model's default tolerance.

    - Normal impact (angle 90 degrees, no axial capacity): report 3.2 by
      `barrierjax.hinge.normal_impact` with `method` and `rtol`. Friction plays no part
      in a normal impact (nothing slides).
    - Oblique impact (a concrete angle below 90 degrees, or `oblique=True`, which a
      `vmap` over angles needs): report 3.3 by `barrierjax.hinge.oblique_impact` with
      `rtol` and `max_steps` (`method` does not apply).
    - With `Barrier.axial_capacity` (a normal impact only): the beam stage of report 3.4,
      integrated in time whatever `method` (it has no closed form), and where N reaches
      N0 the plastic-string stage (3.4.45) to rest, by `barrierjax.hinge.axial_impact`.
    """
    # (Checked here too: not every model reads them.)
    _checks.solve_method(method)
    _checks.step_budget(max_steps)
    normal = _is_normal(scene, oblique)
    if normal:
        scene = _require_normal_angle(scene)
    groups = dimensionless(scene)
    inputs = (groups.mass_ratio, groups.force_ratio, groups.normal_speed)
    tolerance = {} if rtol is None else {"rtol": rtol}

    def solved():
        if not normal:
            return oblique_impact(
                *inputs,
                groups.tangential_speed,
                friction=groups.friction,
                n_history=n_history,
                max_steps=max_steps,
                **tolerance,
            )
        if groups.axial_ratio is None:
            return normal_impact(*inputs, method=method, n_history=n_history, **tolerance)
        return axial_impact(*inputs, groups.axial_ratio, n_history=n_history, **tolerance)

    try:
        model = solved()
    except SolveError as error:
        if error.result is None:
            raise
        # The batch's other scenarios, solved before the error, in the scene's units.
        result = _in_units(scene, groups, error.result)
        raise SolveError(str(error), error.failures, result) from None
    return _in_units(scene, groups, model)


def _scaled(units, scales, quantities):
    """Each of `units`' fields of `quantities` times its scale (a field of `Scales`; a
    batch's scales meet a history's samples on the batch axes)."""

    def scaled(value, unit):
        if unit is None:
            return value
        scale = jnp.asarray(getattr(scales, unit))
        return value * scale.reshape(scale.shape + (1,) * (jnp.ndim(value) - scale.ndim))

    return {name: scaled(getattr(quantities, name), unit) for name, unit in units.items()}


# (One compiled function, not a dozen small ones: each eager operation is an executable
# of its own, to compile or to load from the persistent cache, in every new process.)
@stored_program
@eqx.filter_jit
def _in_units(scene, groups, model) -> Result:
    """The `Result` of a model's dimensionless result: its shared fields scaled, and what
    the scene alone fixes."""
    vehicle, scales = scene.vehicle, groups.scales
    history = None
    if model.history is not None:
        history = History(**_scaled(HISTORY_UNITS, scales, model.history))
    return Result(
        **_scaled(RESULT_UNITS, scales, model),
        kinetic_energy=0.5 * vehicle.mass * scene.impact.speed**2,
        peak_force=vehicle.crush_force,
        peak_deceleration=vehicle.crush_force / vehicle.mass,
        groups=groups,
        model=model,
        history=history,
    )
