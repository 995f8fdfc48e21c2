"""`barrierjax optimize`: size the default barrier (`barrierjax.design.optimize_default`)."""

from __future__ import annotations

import json

from .output import EXIT_FAILED, EXIT_OK, CommandError, progress

__all__ = ["optimize_command"]


def _json_default(value):
    """Arrays and numpy scalars (as a design report may hold) as JSON numbers or lists."""
    import numpy as np

    array = np.asarray(value)
    if array.dtype.kind in "biuf":
        return array.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def optimize_command(args) -> int:
    """`barrierjax optimize [--json]`: returns the exit status."""
    import importlib

    try:
        design = importlib.import_module("barrierjax.design")
    except ModuleNotFoundError as error:
        if error.name not in ("barrierjax.design",):
            raise
        design = None
    optimize_default = getattr(design, "optimize_default", None)
    if optimize_default is None:
        raise CommandError(
            "optimize: barrierjax.design.optimize_default is not available in this version",
            EXIT_FAILED,
        )
    progress("optimizing the default design (compiling the model and its gradient)...")
    report = optimize_default()
    if args.json:
        print(json.dumps(report.as_dict(), indent=2, default=_json_default))
    else:
        print(report.summary())
    return EXIT_OK
