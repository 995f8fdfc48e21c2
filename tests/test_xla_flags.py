"""The XLA options barrierjax sets on import: only those the installed jaxlib knows (XLA
aborts the process on an unknown one), and never over the user's own setting."""

import importlib.metadata
import os
import subprocess
import sys

import pytest

from barrierjax import _xla_flags


@pytest.mark.parametrize(
    "jaxlib, fusion_emitters",
    [("0.10.1", True), ("0.10.2", True), ("0.11.2", False), ("1.0.0", False), ("dev", False)],
)
def test_the_fusion_emitters_option_only_on_the_jaxlib_that_has_it(
    monkeypatch, jaxlib, fusion_emitters
):
    monkeypatch.setattr(importlib.metadata, "version", lambda name: jaxlib)
    flags = _xla_flags.default_flags()
    assert ("xla_cpu_use_fusion_emitters" in flags) == fusion_emitters
    assert flags["xla_cpu_enable_concurrency_optimized_scheduler"] == "false"
    # The oblique batch's own options: the MLIR emitters only where the option exists.
    expected = {"xla_cpu_prefer_vector_width": 512}
    if fusion_emitters:
        expected["xla_cpu_use_fusion_emitters"] = True
    assert _xla_flags.batched_step_options() == expected


def test_no_jaxlib_metadata_sets_only_the_scheduler(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(importlib.metadata, "version", missing)
    assert list(_xla_flags.default_flags()) == ["xla_cpu_enable_concurrency_optimized_scheduler"]


def test_the_users_own_setting_is_kept(monkeypatch):
    monkeypatch.setattr(importlib.metadata, "version", lambda name: "0.10.2")
    monkeypatch.setenv("XLA_FLAGS", "--xla_cpu_use_fusion_emitters=true")
    _xla_flags.set_default_flags()
    flags = os.environ["XLA_FLAGS"].split()
    assert "--xla_cpu_use_fusion_emitters=true" in flags
    assert "--xla_cpu_use_fusion_emitters=false" not in flags
    assert "--xla_cpu_enable_concurrency_optimized_scheduler=false" in flags


def test_the_installed_xla_accepts_every_option_set():
    """A fresh process with no XLA_FLAGS of its own: XLA reads the options barrierjax sets
    when its CPU backend starts, and aborts on any it does not know."""
    env = {k: v for k, v in os.environ.items() if k != "XLA_FLAGS"}
    code = (
        "import os, barrierjax, jax.numpy as jnp\n"
        "print(os.environ['XLA_FLAGS']); print(float(jnp.arange(4.0).sum()))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", code], check=False, env=env, capture_output=True, text=True,
        timeout=120,
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    flags, total = proc.stdout.split("\n")[:2]
    assert set(flags.split()) == {f"--{k}={v}" for k, v in _xla_flags.default_flags().items()}
    assert float(total) == 6.0
