"""`barrierjax optimize`: size the default barrier (`barrierjax.design.optimize_default`), or
with `--level` the scene's barrier for the least expected damage over real-world impacts
under every crash test of a MASH level (`barrierjax.design.optimize_robust`)."""

from __future__ import annotations

import json

from .output import EXIT_FAILED, EXIT_OK, EXIT_USAGE, CommandError, progress

__all__ = ["optimize_command"]


def _json_default(value):
    """Arrays and numpy scalars (as a design report may hold) as JSON numbers or lists."""
    import numpy as np

    array = np.asarray(value)
    if array.dtype.kind in "biuf":
        return array.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _deflection_limit_field():
    from ..scene_file import Field

    return Field(None, "--deflection-limit", "deflection_limit", "a length", "[length]", "m",
                 "0.6 m")  # fmt: skip


def _robust_report(args):
    """The robust sizing of the scene (the default scene without one) for `args.level`."""
    from .. import scene_file
    from ..design import RobustSizing, optimize_robust

    if args.scene is None:
        scene, name = scene_file.default_scene(), "default scene"
    else:
        scene, name = scene_file.load_scene(args.scene), args.scene.stem
    limit = scene_file.parse_quantity(args.deflection_limit, _deflection_limit_field())
    try:
        problem = RobustSizing(
            args.level,
            deflection_limit=limit,
            crush_per_mass=float(scene.vehicle.crush_force) / float(scene.vehicle.mass),
            road_class=args.road_class,
        )
    except ValueError as error:
        raise CommandError(" ".join(str(error).split()), EXIT_USAGE) from None
    import equinox as eqx
    import jax

    try:
        return optimize_robust(problem, scene.barrier, baseline_name=name, progress=progress)
    except (jax.errors.JaxRuntimeError, eqx.EquinoxRuntimeError) as error:  # a model's check
        from .run import model_error

        raise CommandError(model_error(error), EXIT_FAILED) from None


def optimize_command(args) -> int:
    """`barrierjax optimize [SCENE.toml] [--level LEVEL] [--json]`: returns the exit status."""
    if args.level is None:
        if args.scene is not None:
            raise CommandError(
                "optimize: a scene is sized for a test level: pass --level (e.g. MASH-TL3)",
                EXIT_USAGE,
            )
        import importlib

        optimize_default = getattr(
            importlib.import_module("barrierjax.design"), "optimize_default", None
        )
        if optimize_default is None:
            raise CommandError(
                "optimize: barrierjax.design.optimize_default is not available in this version",
                EXIT_FAILED,
            )
        progress("optimizing the default design (compiling the model and its gradient)...")
        report = optimize_default()
    else:
        report = _robust_report(args)
    if args.json:
        print(json.dumps(report.as_dict(), indent=2, default=_json_default))
    else:
        print(report.summary())
    return EXIT_OK
