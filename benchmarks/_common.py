"""What every benchmark script shares: collecting a failed solve's error, saving figures,
describing the machine, and noticing a model edited on disk while a run was going."""

import argparse
import datetime
import hashlib
import os
import platform
from pathlib import Path

import jax

import barrierjax


def drain():
    """Collect a failed solve's pending runtime error, so that it is not raised again at exit."""
    try:
        jax.effects_barrier()
    except Exception:  # noqa: BLE001
        try:  # the failed token stays in jax's token set (a private API; best effort)
            from jax._src import dispatch

            dispatch.runtime_tokens.clear()
        except Exception:  # noqa: BLE001, S110
            pass


def save(fig, path: Path) -> Path:
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def meta(args, load_start, sources_start, changed, **versions) -> dict:
    """What every results file says of its run: when, how, on what, with which code."""
    import diffrax
    import numpy as np

    return dict(
        date=datetime.date.today().isoformat(),
        quick=args.quick,
        seed=args.seed,
        machine=machine(load_start),
        versions=dict(
            jax=jax.__version__,
            diffrax=diffrax.__version__,
            barrierjax=getattr(barrierjax, "__version__", "?"),
            numpy=np.__version__,
            **versions,
        ),
        barrierjax_sources=sources_start,
        sources_changed_during_run=changed,
    )


def machine(load_start) -> dict:
    return dict(
        cpu_count=os.cpu_count(),
        platform=platform.platform(),
        processor=platform.processor(),
        python=platform.python_version(),
        load_average_start=load_start,
        load_average_end=os.getloadavg(),
    )


def source_fingerprint() -> dict:
    """sha256 of every barrierjax source file, to detect a model edited during a run."""
    root = Path(barrierjax.__file__).resolve().parent
    return {
        str(p.relative_to(root.parent)): hashlib.sha256(p.read_bytes()).hexdigest()[:16]
        for p in sorted(root.rglob("*.py"))
    }


def sources_changed(start: dict) -> str | None:
    """A line for the run's surprises if the sources differ from `start`, else None."""
    end = source_fingerprint()
    changed = sorted(k for k in set(start) | set(end) if start.get(k) != end.get(k))
    if not changed:
        return None
    return (
        "barrierjax sources changed on disk during this run: "
        + ", ".join(changed)
        + "; the run used the versions imported at its start (meta.barrierjax_sources)"
    )


def argument_parser(doc: str) -> argparse.ArgumentParser:
    """The options every benchmark script takes: --quick, --out, --seed, --no-plots."""
    parser = argparse.ArgumentParser(description=doc.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="tiny smoke run")
    parser.add_argument(
        "--out",
        type=Path,
        default=Path(__file__).resolve().parent / "results",
        help="results folder (default benchmarks/results)",
    )
    parser.add_argument("--seed", type=int, default=20261122)
    parser.add_argument("--no-plots", action="store_true")
    return parser
