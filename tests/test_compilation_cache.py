import os
import subprocess
import sys
import warnings
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from barrierjax import compilation_cache


@pytest.mark.parametrize("value", ["off", "OFF", "0", "false", "no", ""])
def test_the_switch_turns_it_off(monkeypatch, value):
    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", value)
    assert compilation_cache.cache_dir() is None
    assert compilation_cache.enable() is None


def test_the_folder_is_the_variable_or_under_the_user_cache(monkeypatch, tmp_path):
    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", str(tmp_path / "here"))
    assert compilation_cache.cache_dir() == tmp_path / "here"
    monkeypatch.delenv("BARRIERJAX_CACHE_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert compilation_cache.cache_dir() == tmp_path / "xdg" / "barrierjax" / "jax"


def test_an_unwritable_folder_leaves_it_off(monkeypatch, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", str(blocker / "cache"))
    before = jax.config.jax_compilation_cache_dir
    assert compilation_cache.enable() is None
    assert jax.config.jax_compilation_cache_dir == before


def test_a_second_process_loads_what_the_first_compiled(tmp_path):
    # A fresh process compiles a model into an empty cache; the next one finds it there.
    program = (
        "import jax; jax.config.update('jax_enable_x64', True);"
        "from barrierjax import compilation_cache; compilation_cache.enable();"
        "from barrierjax.hinge import normal_impact;"
        "print(float(normal_impact(2.0, 3.0, 0.5).damage))"
    )
    env = {**os.environ, "BARRIERJAX_CACHE_DIR": str(tmp_path / "cache")}
    first = subprocess.run([sys.executable, "-c", program], env=env, capture_output=True, text=True,
                           timeout=300)
    assert first.returncode == 0, first.stderr
    entries = sorted(p.name for p in Path(tmp_path / "cache").iterdir())
    assert entries, "nothing was written to the cache"
    second = subprocess.run([sys.executable, "-c", program], env=env, capture_output=True, text=True,
                           timeout=300)
    assert second.returncode == 0, second.stderr
    assert second.stdout == first.stdout
    assert sorted(p.name for p in Path(tmp_path / "cache").iterdir()) == entries


# A jitted function that counts its traces, kept by `stored_program`, run in a fresh
# process: the second process must load its program without tracing it.
_TRACED_PROGRAM = """
import functools, jax, jax.numpy as jnp, equinox as eqx
jax.config.update("jax_enable_x64", True)
from barrierjax import compilation_cache
traces = []

class Pair(eqx.Module):  # an argument that is a pytree, with a static field
    y: jax.Array
    label: str = eqx.field(static=True)

@compilation_cache.stored_program
@functools.partial(jax.jit, static_argnames=("power",))
def f(x, pair, *, power):
    traces.append(1)
    return {"value": jnp.sum(x**power) + pair.y, "parts": (x * pair.y, None)}

with compilation_cache.keeping_programs():
    out = f(jnp.arange(4.0), Pair(jnp.asarray(2.0), "y"), power=3)
    again = f(jnp.arange(4.0), Pair(jnp.asarray(2.0), "y"), power=3)
print(len(traces), float(out["value"]), out["parts"][0].tolist(), out["parts"][1],
      float(again["value"]))
"""


def _run(program, cache):
    env = {**os.environ, "BARRIERJAX_CACHE_DIR": str(cache)}
    done = subprocess.run([sys.executable, "-c", program], env=env, capture_output=True, text=True,
                           timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout.split()


def test_a_stored_program_is_loaded_by_the_next_process_without_tracing(tmp_path):
    first = _run(_TRACED_PROGRAM, tmp_path / "cache")
    assert first == ["1", "38.0", "[0.0,", "2.0,", "4.0,", "6.0]", "None", "38.0"]
    stored = list((tmp_path / "cache" / "programs").iterdir())
    assert len(stored) == 1 and stored[0].name.startswith("f-")
    second = _run(_TRACED_PROGRAM, tmp_path / "cache")
    assert second == ["0"] + first[1:]
    # Another static option or shape is another program.
    other = _run(_TRACED_PROGRAM.replace("power=3", "power=2"), tmp_path / "cache")
    assert other[:2] == ["1", "16.0"]
    assert len(list((tmp_path / "cache" / "programs").iterdir())) == 2


# A stored program that factorises (LAPACK's LU through XLA): JAX points those calls at
# their routines as it lowers a program, which a process loading the program never does.
_SOLVING_PROGRAM = """
import jax, jax.numpy as jnp
jax.config.update("jax_enable_x64", True)
from barrierjax import compilation_cache

@compilation_cache.stored_program
@jax.jit
def solve(a, b):
    return jnp.linalg.solve(a, b)

with compilation_cache.keeping_programs():
    x = solve(jnp.array([[4.0, 1.0], [2.0, 3.0]]), jnp.array([1.0, 2.0]))
print(*x.tolist())
"""


def test_a_stored_program_that_factorises_runs_in_the_next_process(tmp_path):
    first = _run(_SOLVING_PROGRAM, tmp_path / "cache")
    assert [float(v) for v in first] == pytest.approx([0.1, 0.6], rel=1e-14)
    assert len(list((tmp_path / "cache" / "programs").iterdir())) == 1
    assert _run(_SOLVING_PROGRAM, tmp_path / "cache") == first  # loaded: it crashed here


# `run_compiled` within `keeping_programs()`: stored by the first process, loaded by the next
# without a trace, and concrete inside a caller's jit either way.
_RUN_COMPILED_PROGRAM = """
import jax, jax.numpy as jnp, numpy as np
jax.config.update("jax_enable_x64", True)
from barrierjax import compilation_cache
traces = []

@jax.jit
def double(x):
    traces.append(1)
    return 2.0 * x

data = jnp.arange(3.0)  # concrete, closed over by the caller's jit

@jax.jit
def outer(y):
    concrete = np.asarray(compilation_cache.run_compiled(double, data))
    return y + concrete.sum()

with compilation_cache.keeping_programs():
    value = float(outer(1.0))
print(len(traces), value)
"""


def test_run_compiled_is_concrete_in_a_callers_jit_and_stored_within_keeping_programs(tmp_path):
    double, data = jax.jit(lambda x: 2.0 * x), jnp.arange(3.0)
    concrete = jax.jit(
        lambda y: y + np.asarray(compilation_cache.run_compiled(double, data)).sum()
    )
    assert float(concrete(1.0)) == 7.0  # not stored: compiled ahead of time
    assert _run(_RUN_COMPILED_PROGRAM, tmp_path / "cache") == ["1", "7.0"]
    (stored,) = (tmp_path / "cache" / "programs").iterdir()
    assert stored.name.startswith("double-")
    assert _run(_RUN_COMPILED_PROGRAM, tmp_path / "cache") == ["0", "7.0"]


def test_a_damaged_stored_program_is_compiled_again(tmp_path):
    _run(_TRACED_PROGRAM, tmp_path / "cache")
    (stored,) = (tmp_path / "cache" / "programs").iterdir()
    stored.write_bytes(b"not a program")
    again = _run(_TRACED_PROGRAM, tmp_path / "cache")
    assert again[:2] == ["1", "38.0"]
    assert _run(_TRACED_PROGRAM, tmp_path / "cache")[0] == "0"  # mended


def test_a_process_that_moves_to_another_folder_keeps_its_programs_there(monkeypatch, tmp_path):
    # The process's own executables were once keyed by the program alone: after a move to
    # another folder (BARRIERJAX_CACHE_DIR changed), nothing was kept in the new one.
    triple = compilation_cache.stored_program(jax.jit(lambda x: 3.0 * x))
    for name in ("first", "second"):
        monkeypatch.setenv("BARRIERJAX_CACHE_DIR", str(tmp_path / name))
        with compilation_cache.keeping_programs() as folder:
            assert float(triple(jnp.asarray(2.0))) == 6.0
        assert [p.name.split("-")[0] for p in folder.iterdir()] == ["<lambda>"]


def test_models_under_a_stored_program_give_what_jit_gives(monkeypatch, tmp_path):
    # The normal model through its stored program (twice: stored, then loaded in this
    # process), under jax.grad (traced: plain jit), and without the store; and `simulate`,
    # whose scene and result conversions take equinox modules.
    from barrierjax import scene_file, simulate
    from barrierjax.hinge import normal_impact

    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", str(tmp_path / "cache"))
    args = (jnp.asarray(2.0), jnp.asarray(3.0), jnp.asarray(0.5))
    damage = lambda *a: normal_impact(*a, n_history=8).damage
    scene = scene_file.default_scene()
    plain, plain_grad = damage(*args), jax.grad(damage)(*args)
    plain_result = simulate(scene, n_history=8)
    with compilation_cache.keeping_programs() as folder:
        kept = [damage(*args) for _ in range(2)]
        kept_grad = jax.grad(damage)(*args)
        kept_results = [simulate(scene, n_history=8) for _ in range(2)]
    assert {p.name.split("-")[0] for p in folder.iterdir()} == {
        "normal_impact", "dimensionless", "in_units"
    }
    assert all(float(k) == float(plain) for k in kept)
    assert float(kept_grad) == float(plain_grad)
    for result in kept_results:
        assert jax.tree.structure(result) == jax.tree.structure(plain_result)
        for a, b in zip(jax.tree.leaves(result), jax.tree.leaves(plain_result)):
            np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize("model", ["normal ODE", "axial"])
def test_the_solved_models_are_kept_and_a_new_tolerance_runs_the_same_program(
    monkeypatch, tmp_path, model
):
    # Their failed solves are outputs raised outside the program (`_solve.phases`): a
    # run-time check inside it, a host callback, would keep it out of both caches.
    from barrierjax.hinge import axial_impact, normal_impact

    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", str(tmp_path / "cache"))
    solve = {
        "normal ODE": lambda rtol: normal_impact(1.0, 2.0, 0.7, method="ode", rtol=rtol),
        "axial": lambda rtol: axial_impact(0.5, 2.0, 1.0, 0.5, rtol=rtol),
    }[model]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with compilation_cache.keeping_programs() as folder:
            loose, tight = solve(1e-4), solve(1e-10)
    assert not [w for w in caught if "not kept" in str(w.message)]
    (kept,) = folder.iterdir()
    assert kept.name.startswith("normal_impact-" if model == "normal ODE" else "axial_impact-")
    assert float(loose.duration) != float(tight.duration)


def test_a_program_with_a_host_callback_runs_unkept_with_a_warning(monkeypatch, tmp_path):
    # `equinox.error_if` is a host callback on a CPU: such a program cannot be serialized
    # (the pickler fails on a local function); it runs, its check raises, nothing is kept.
    import equinox as eqx

    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", str(tmp_path / "cache"))
    checked = compilation_cache.stored_program(
        jax.jit(lambda x: eqx.error_if(2.0 * x, x < 0.0, "x must be non-negative"))
    )
    with compilation_cache.keeping_programs() as folder:
        with pytest.warns(UserWarning, match="not kept in"):
            assert float(checked(jnp.asarray(1.5))) == 3.0
        with pytest.raises(Exception, match="x must be non-negative"):
            jax.block_until_ready(checked(jnp.asarray(-1.0)))
    assert not folder.exists() or not any(folder.iterdir())


def test_nothing_is_kept_where_the_cache_is_off(monkeypatch):
    monkeypatch.setenv("BARRIERJAX_CACHE_DIR", "off")
    with compilation_cache.keeping_programs() as folder:
        assert folder is None
