import os
import subprocess
import sys
from pathlib import Path

import jax
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
    first = subprocess.run([sys.executable, "-c", program], env=env, capture_output=True, text=True)
    assert first.returncode == 0, first.stderr
    entries = sorted(p.name for p in Path(tmp_path / "cache").iterdir())
    assert entries, "nothing was written to the cache"
    second = subprocess.run([sys.executable, "-c", program], env=env, capture_output=True, text=True)
    assert second.returncode == 0, second.stderr
    assert second.stdout == first.stdout
    assert sorted(p.name for p in Path(tmp_path / "cache").iterdir()) == entries
