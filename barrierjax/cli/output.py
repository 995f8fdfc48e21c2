"""What the commands share: exit statuses, `CommandError` (a failure reported in one line),
progress messages on stderr, double precision, and printing a run's results (a summary or
one JSON object) on stdout."""

from __future__ import annotations

import contextlib
import json
import os
import sys
import threading
from pathlib import Path

__all__ = [
    "EXIT_FAILED",
    "EXIT_OK",
    "EXIT_USAGE",
    "CommandError",
    "as_float",
    "check_out_folder",
    "enable_x64",
    "print_result",
    "progress",
    "progress_after",
]

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


class CommandError(Exception):
    """A failure to report in one line (`error: ...`) with an exit status, no traceback."""

    def __init__(self, message: str, status: int = EXIT_USAGE):
        super().__init__(" ".join(str(message).split()))
        self.status = status


def check_out_folder(path: Path) -> None:
    """`--out DIR` checked before the command's work: a folder, or one that can be made
    where it is asked for (its first existing parent a folder this process may write)."""
    existing = path
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if existing == path and not path.is_dir():
        raise CommandError(f"--out {path}: not a folder")
    if not existing.is_dir() or not os.access(existing, os.W_OK):
        raise CommandError(f"--out {path}: cannot make or write a folder there")


def progress(message: str) -> None:
    """Print a progress `message` to stderr (stdout is for results)."""
    print(message, file=sys.stderr, flush=True)


@contextlib.contextmanager
def progress_after(message: str, delay: float = 0.2):
    """Print `message` to stderr if the block is still running after `delay` seconds, so
    that a scene refused at once ends with its one error line and nothing else."""
    timer = threading.Timer(delay, progress, (message,))
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        timer.cancel()


def enable_x64() -> None:
    """Run the models in double precision (`main` does this before any command)."""
    import jax

    jax.config.update("jax_enable_x64", True)


def as_float(value) -> float:
    """A (JAX or numpy) scalar as a Python float, for a JSON-ready result dict."""
    return float(value)


def print_result(args, data: dict, plots: list, summary) -> int:
    """Print a run's `data` (with its `plots`) as JSON, or as `summary(data)` and the plots."""
    data["plots"] = [str(p) for p in plots]
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        print(summary(data))
        if plots:
            print("\nPlots: " + ", ".join(str(p) for p in plots))
    return EXIT_OK
