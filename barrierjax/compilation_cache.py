"""JAX's persistent compilation cache, on by default for the command line and the tests.

A model's first call in a fresh process is mostly XLA compiling it (seconds); the
persistent cache keeps every compiled executable on disk, keyed by the program, the
shapes, the jax version and the machine, so that the next process that calls the same
model loads it instead (milliseconds). It is JAX's own (`jax_compilation_cache_dir`);
this module only picks the folder and the thresholds.

- The folder: `$BARRIERJAX_CACHE_DIR` if set, else `barrierjax/jax` under the user's
  cache folder (`$XDG_CACHE_HOME`, else `~/.cache`).
- `BARRIERJAX_CACHE_DIR=off` (or `0`, `false`, `no`, or empty) switches it off.
- Every executable is kept, however quick to compile (JAX keeps only those above a second
  by default): the command line's first answer is the sum of dozens of small ones.

A library import does not turn it on: a user's program decides (`enable()` does it in one
line).
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cache_dir", "enable"]

_OFF = {"off", "0", "false", "no", ""}


def cache_dir() -> Path | None:
    """The folder the cache lives in, or None where `BARRIERJAX_CACHE_DIR` switches it off."""
    chosen = os.environ.get("BARRIERJAX_CACHE_DIR")
    if chosen is not None:
        return None if chosen.strip().lower() in _OFF else Path(chosen).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "barrierjax" / "jax"


def enable() -> Path | None:
    """Turn JAX's persistent compilation cache on in `cache_dir()` (created if missing);
    returns the folder, or None where it is switched off or the folder cannot be made
    (a read-only home, say: then every process compiles anew, as without it)."""
    folder = cache_dir()
    if folder is None:
        return None
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    import jax

    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.0)
    return folder
