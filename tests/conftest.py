import contextlib
import gc
import logging
import os

import jax
import jax.extend.core
import pytest

from barrierjax import compilation_cache

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_numpy_dtype_promotion", "strict")
# The persistent compilation cache is off for the suite (and the processes it starts) unless
# BARRIERJAX_CACHE_DIR names a folder: in a cold run its only effect is that processes load
# each other's executables, and a deserialized executable once took a CI worker down
# (a segmentation fault in jaxlib 0.10.2's CPU `deserialize_executable`). The tests of the
# cache itself give it folders of their own.
os.environ.setdefault("BARRIERJAX_CACHE_DIR", "off")
compilation_cache.enable()


def _jax_arrays_in(expected):
    if isinstance(expected, jax.Array):
        return True
    if isinstance(expected, dict):
        return any(_jax_arrays_in(v) for v in expected.values())
    if isinstance(expected, (list, tuple)):
        return any(_jax_arrays_in(v) for v in expected)
    return False


_pytest_approx = pytest.approx


def _approx_of_plain_values(expected, *args, **kwargs):
    """`pytest.approx`, refusing a JAX array on the expected side.

    pytest reads numpy's protocol (`.flat`, `__array__`) on the expected value, and what it
    reads changes between releases: pytest 9.2 reads `.flat`, which JAX arrays do not have.
    Refusing them here makes the pinned test environment fail the way the newest would.
    """
    if _jax_arrays_in(expected):
        raise TypeError(
            "pytest.approx: the expected value is (or holds) a JAX array; pass float(x) or "
            "np.asarray(x) instead (pytest reads numpy's protocol on it, e.g. `.flat` in "
            "pytest>=9.2, which JAX arrays do not implement)"
        )
    return _pytest_approx(expected, *args, **kwargs)


pytest.approx = _approx_of_plain_values


# The files that take longest, heaviest first (seconds in `python -m pytest -q
# --durations=0`, 2026-11-26 evening, summed per file).
_HEAVIEST = (
    "tests/test_oblique_impact.py",  # 135
    "tests/test_design_robust.py",  # 117
    "tests/test_normal_impact.py",  # 72
    "tests/test_cli.py",  # 67
    "tests/test_benchmark_smoke.py",  # 62
    "tests/test_beam_fe.py",  # 62
    "tests/test_materials_uniaxial.py",  # 53
    "tests/test_plastic_string.py",  # 49
    "tests/test_sweep.py",  # 49
)


def pytest_collection_modifyitems(items):
    """The heaviest files first, the rest in their order. With one file per worker
    (`--dist loadfile`), each worker taking the next file as it frees, the suite ends when
    its last file does: started last, a heavy file keeps one worker busy while the other
    waits (xdist's own order, most tests first, left 70 s between the two workers' ends)."""
    rank = {name: k for k, name in enumerate(_HEAVIEST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))


@pytest.hookimpl(tryfirst=True)
def pytest_sessionfinish(session):
    """Free JAX's caches and collect before a worker reports its end, and freeze what is
    left out of later collections. Once told to stop, a worker (execnet) that has not
    finished within 5 s sends itself SIGINT. Its last collections (pytest's check for
    unraisable exceptions runs one) went over everything the caches held: 1.9 million
    objects and 1.0 s after `tests/test_oblique_impact.py` alone, more after a worker's
    share of the suite. In most CI runs the KeyboardInterrupt then landed in hypothesis's
    gc callback and was printed as a `PytestUnraisableExceptionWarning` at the end of the
    output."""
    jax.clear_caches()
    gc.collect()
    gc.freeze()


@pytest.fixture
def compilations(caplog):
    """`with compilations() as programs:` gives, once the block has run, the messages of the
    programs XLA compiled within it ("Finished XLA compilation of jit(name) ...")."""

    @contextlib.contextmanager
    def watch():
        programs = []
        caplog.clear()
        with caplog.at_level(logging.WARNING), jax.log_compiles():
            yield programs
        programs += [r.getMessage() for r in caplog.records if "XLA compilation" in r.getMessage()]

    return watch


def _id_arrays(jaxpr, shape):
    found = []
    for eqn in jaxpr.eqns:
        found += [v for v in eqn.outvars if v.aval.dtype == "uint32" and v.aval.shape == shape]
        for param in eqn.params.values():
            for sub in param if isinstance(param, (tuple, list)) else (param,):
                if isinstance(sub, jax.extend.core.ClosedJaxpr):
                    sub = sub.jaxpr
                if isinstance(sub, jax.extend.core.Jaxpr):
                    found += _id_arrays(sub, shape)
    return found


@pytest.fixture
def id_arrays():
    """`id_arrays(closed_jaxpr, shape)`: the uint32 arrays of `shape` anywhere in a jaxpr
    (its loops' and branches' too). JAX differentiates a scatter whose indices may repeat
    by scattering such ids over the whole operand and selecting by them: a pass over all
    of it, where the scatter itself writes a row."""
    return lambda closed, shape: _id_arrays(closed.jaxpr, tuple(shape))
