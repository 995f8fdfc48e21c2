"""JAX's persistent compilation cache, on by default for the command line.

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
line). JAX's cache keeps no program with a host callback, and a model called on traced
values (under the caller's `jit`, `grad` or `vmap`) checks them with `equinox.error_if`,
one: such a program compiles in every process, unless `EQX_ON_ERROR=nan` turns the checks
into NaN outputs (a bad input or a failed solve then shows as NaN, not as an error).

The persistent cache still traces and lowers a model before it finds the executable (its
key is the lowered program): half a second for the oblique model, on every run of the
command line. Within `keeping_programs()`, as the command line runs, the models' entry
points (`stored_program`) also keep their compiled executables in `programs/` beside the
cache, keyed by the arguments' tree, shapes and types, the static options, the
versions of jax, jaxlib, equinox and diffrax, the jax settings that change a trace, and a
digest of barrierjax's own source: a later process that calls the same entry point with
concrete arrays (or pytrees of them: a scene, a model's result) of the same shapes loads
the executable and runs it, with no tracing or lowering at all. Calls under a caller's
`jit`, `vmap` or `grad` (traced arguments) go through `jax.jit` as always.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import math
import os
import pickle
import platform
import tempfile
import threading
import warnings
from importlib import metadata
from pathlib import Path

__all__ = ["cache_dir", "enable", "keeping_programs", "run_compiled", "stored_program"]

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


@contextlib.contextmanager
def keeping_programs():
    """Within it, `stored_program` entry points keep their compiled executables in
    `programs/` of the cache folder (`enable()`'s, which it calls), and load them from
    there; nothing is kept where the cache is off."""
    global _programs
    folder = enable()
    before = _programs
    _programs = None if folder is None else folder / "programs"
    try:
        yield _programs
    finally:
        _programs = before


# Where `stored_program` keeps executables (None: it is off), and those of this process
# (by folder and key).
_programs: Path | None = None
_loaded: dict = {}
# One load or compilation at a time: batches solved in parts call an entry point from
# several threads at once (`_solve.batching`), and a compilation here sets a global option.
_loading = threading.Lock()


def stored_program(jitted, *, compiler_options: dict | None = None):
    """`jitted` (a `jax.jit` or `equinox.filter_jit` function whose static arguments are
    keywords), whose compiled executable is kept on disk and loaded by later processes,
    within `keeping_programs()` and where the positional arguments are pytrees of concrete
    arrays (equinox modules, None, tuples: every leaf an array). `compiler_options`: the
    XLA options `jitted` was made with (`jax.jit`'s): the program kept is then compiled
    from the function it wraps, with them (XLA refuses options on a jit inside another)."""

    @functools.wraps(jitted)
    def call(*args, **static):
        stored = _stored(jitted, args, static, compiler_options)
        return jitted(*args, **static) if stored is None else stored(*args)

    return call


def run_compiled(jitted, *args):
    """`jitted` (a `jax.jit` function) run now on `args`, concrete data, as a compiled
    program: its result is concrete even inside a caller's `jit`. Within
    `keeping_programs()` the executable is `stored_program`'s (no tracing in a later
    process), else it is compiled ahead of time here."""
    stored = _stored(jitted, args, {}, None)
    return jitted.lower(*args).compile()(*args) if stored is None else stored(*args)


def _stored(jitted, args, static, compiler_options):
    """The stored program of `jitted` at `args` and `static` as a function of the positional
    arguments (loaded, or compiled and stored), or None where nothing is kept (outside
    `keeping_programs()`, traced arguments, a key with no stable text)."""
    import jax

    concrete = all(
        isinstance(a, jax.Array) and not isinstance(a, jax.core.Tracer)
        for a in jax.tree.leaves(args)
    )
    if _programs is None or not concrete:
        return None
    key = _key(jitted, args, static, compiler_options)
    if key is None:
        return None
    with _loading:
        # Keyed by the folder too: a process that moves to another folder keeps its
        # programs there as well.
        stored = (
            _loaded.get((_programs, key))
            or _load(key)
            or _compile_and_store(jitted, key, args, static, compiler_options)
        )
        _loaded[_programs, key] = stored
    executable, outputs = stored
    return lambda *args: jax.tree.unflatten(outputs, executable(*args))


def _key(jitted, args, static, compiler_options) -> str | None:
    """What the program depends on, hashed; None where a static option or the arguments'
    tree has no stable text (an object printed with its address)."""
    import jax

    leaves, tree = jax.tree.flatten(args)
    options = repr((sorted(static.items()), tree, sorted((compiler_options or {}).items())))
    if " at 0x" in options:
        return None
    avals = [(a.shape, str(a.dtype), a.weak_type) for a in leaves]
    settings = [jax.config.jax_enable_x64, jax.config.jax_numpy_dtype_promotion,
                jax.config.jax_default_matmul_precision, os.environ.get("XLA_FLAGS", ""),
                str(jax.devices()[0]), jax.device_count(), jax.process_count(),
                _machine()]  # fmt: skip
    versions = [metadata.version(name) for name in ("jax", "jaxlib", "equinox", "diffrax")]
    name = f"{jitted.__module__}.{jitted.__qualname__}"
    text = repr((name, options, avals, settings, versions, _source_digest()))
    return f"{jitted.__name__.strip('_')}-{hashlib.sha256(text.encode()).hexdigest()[:32]}"


@functools.cache
def _machine() -> str:
    """The processor's features (an executable is compiled for them): a cache folder shared
    between machines keeps each one's apart."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith(("flags", "Features")):
                return line
    except OSError:
        pass
    return f"{platform.machine()} {platform.processor()}"


@functools.cache
def _source_digest() -> str:
    """A digest of every Python file of the package: any change to the code is a new key."""
    root = Path(__file__).parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        digest.update(str(path.relative_to(root)).encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()


def _load(key):
    """(the executable stored under `key`, its output tree), or None where there is none or
    it does not load (a damaged file, another jax's: it is compiled again)."""
    import jax
    from jax.experimental import serialize_executable

    try:
        payload, inputs, outputs, factorises = pickle.loads((_programs / key).read_bytes())
        if factorises:
            _lapack_ready()
        # The trees are rebuilt here from skeletons (their leaves numbered): a pickled
        # tree of equinox modules does not unflatten in another process. The executable
        # returns the output's leaves.
        outputs = jax.tree.structure(outputs)
        leaves = jax.tree.structure(list(range(outputs.num_leaves)))
        executable = serialize_executable.deserialize_and_load(
            payload, jax.tree.structure(inputs), leaves
        )
        return executable, outputs
    except (OSError, EOFError, pickle.UnpicklingError, ValueError, TypeError, RuntimeError):
        return None


# The prefix of XLA's calls to LAPACK on a CPU (`lapack_dgetrf_ffi`, ...).
_LAPACK = "@lapack_"


@functools.cache
def _lapack_ready():
    """Point XLA's LAPACK calls (an LU factorisation, say) at their routines. JAX does it as
    it lowers such an operation, which a process that loads a stored program never does:
    its executable would call through an unset pointer (a segmentation fault). (About 0.1 s:
    the routines are SciPy's, imported then.)"""
    import numpy as np
    from jaxlib import lapack

    lapack.prepare_lapack_call("getrf_ffi", np.float64)


def _compile_and_store(jitted, key, args, static, compiler_options):
    """Compile `jitted` at `args` (its output leaves, under a name of its own; with
    `compiler_options`, the function it wraps) and store the executable; returns (the
    executable, its output tree)."""
    import jax
    from jax.experimental import serialize_executable

    trees = []
    inner = jitted.__wrapped__ if compiler_options else jitted

    def stored(*args):
        leaves, tree = jax.tree.flatten(inner(*args, **static))
        trees.append(tree)
        return leaves

    stored.__name__ = f"stored_{jitted.__name__.strip('_')}"
    lowered = jax.jit(stored, compiler_options=compiler_options).lower(*args)
    # An executable that JAX's cache loaded serializes without its code: this program is
    # compiled anew and never written there (its name keeps it apart from `jitted`'s).
    shortest = jax.config.jax_persistent_cache_min_compile_time_secs
    jax.config.update("jax_persistent_cache_min_compile_time_secs", math.inf)
    try:
        executable = lowered.compile()
    finally:
        jax.config.update("jax_persistent_cache_min_compile_time_secs", shortest)
    (outputs,) = trees
    try:
        payload, in_tree, _ = serialize_executable.serialize(executable)
        numbered = lambda tree: jax.tree.unflatten(tree, list(range(tree.num_leaves)))
        _programs.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=_programs, delete=False) as file:
            factorises = _LAPACK in lowered.as_text()
            pickle.dump((payload, numbered(in_tree), numbered(outputs), factorises), file)
        os.replace(file.name, _programs / key)  # whole, or not at all
    except (
        OSError,
        pickle.PicklingError,
        AttributeError,
        ValueError,
        TypeError,
        RuntimeError,
    ) as error:
        # Not storable (a full disk; host callbacks, e.g. `equinox.error_if`, which the
        # pickler meets as a local function: AttributeError): only slower.
        warnings.warn(f"not kept in {_programs} ({error})", stacklevel=3)
    return executable, outputs
