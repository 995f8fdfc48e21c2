"""The harness every benchmark script uses (public JAX API only).

- `first_call`: a model's first call in a FRESH Python process (`sys.executable` on a
  snippet): wall time of the imports and of the first call (tracing and compilation, mostly)
  apart, and the child's peak resident memory, which the child prints as JSON (its
  `/proc/self/status` VmHWM where there is one: on Linux `ru_maxrss` keeps, across the
  exec, the resident size of the parent at the fork; `ru_maxrss` elsewhere).
  Compile time and memory are part of a model's cost.
- `steady`: the steady-state time of a call in this process: one warm-up call, then the best
  (or the median) of N calls, each waited for with `jax.block_until_ready`.
- `table`, `write_json`, `save_figure`: markdown-style tables on stdout, and JSON (with a
  `meta` block: date, machine, versions, `--quick`) and PNG plots in `--out`.
- `argument_parser`: `--quick`, `--out` (default `benchmarks/results/`), `--seed`,
  `--no-plots`.
"""

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import textwrap
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
LOAD_AT_START = os.getloadavg()


def argument_parser(doc: str) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        description=doc.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--quick", action="store_true", help="tiny sizes: a smoke run")
    parser.add_argument("--out", type=Path, default=HERE / "results", help="results folder")
    parser.add_argument("--seed", type=int, default=20261122, help="scenario seed")
    parser.add_argument("--no-plots", action="store_true", help="write no PNG")
    return parser


# --------------------------------------------------------------------------------------
# Timing.


def steady(fn, *args, reps=5, stat="best", slow=1.0) -> float:
    """Seconds of `fn(*args)` after one warm-up call: the best (`stat="median"`: the median)
    of `reps` calls; a single timed call when the warm-up took over `slow` seconds."""
    import jax

    start = time.perf_counter()
    jax.block_until_ready(fn(*args))
    reps = 1 if time.perf_counter() - start > slow else reps
    times = []
    for _ in range(reps):
        start = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - start)
    return min(times) if stat == "best" else statistics.median(times)


_CHILD = """\
import json, resource, sys, time
sys.path.insert(0, {here!r})
_t0 = time.perf_counter()
{setup}
import jax
_t1 = time.perf_counter()
jax.block_until_ready({call})
_t2 = time.perf_counter()
_peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
try:  # ru_maxrss carries the parent's resident size at fork over exec; VmHWM starts afresh
    _peak = [int(x.split()[1]) / 1024 for x in open("/proc/self/status") if x.startswith("VmHWM:")][0]
except (OSError, IndexError):
    pass
_steady = []
for _ in range({steady_reps}):
    _t = time.perf_counter()
    jax.block_until_ready({call})
    _steady.append(time.perf_counter() - _t)
print("FIRST_CALL " + json.dumps(dict(import_s=_t1 - _t0, first_call_s=_t2 - _t1, peak_rss_mb=_peak,
                                      steady_s=min(_steady) if _steady else None, steady_runs_s=_steady)))
"""


def _rss_mb(pid: int) -> float:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def first_call(
    setup: str, call: str, *, x64=True, timeout=600.0, rss_limit_gb=None, steady_reps=0,
    package=None, env=None,
) -> dict:
    """Run `setup` (imports and inputs: timed as `import_s`) then the expression `call`
    (waited for: `first_call_s`) in a fresh `sys.executable` with `JAX_ENABLE_X64` set to
    `x64`, and then `steady_reps` more times (the best: `steady_s`; each: `steady_runs_s`).
    The child is killed
    after `timeout` s or above `rss_limit_gb` resident. `package`: a folder holding another
    checkout's `barrierjax`, imported in its place (to measure a commit against another).
    `env`: environment variables set in the child."""
    code = _CHILD.format(
        here=str(HERE), setup=textwrap.dedent(setup).strip(), call=call, steady_reps=steady_reps
    )
    if package is not None:
        code = f"import sys; sys.path.insert(0, {str(package)!r})\n" + code
    env = dict(os.environ, **(env or {}), JAX_ENABLE_X64="1" if x64 else "0")
    start = time.perf_counter()
    child = subprocess.Popen(
        [sys.executable, "-c", code], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
        text=True,
    )
    killed = None
    while child.poll() is None:
        if time.perf_counter() - start > timeout:
            killed = f"killed after {timeout:.0f} s"
        elif rss_limit_gb and _rss_mb(child.pid) > rss_limit_gb * 1024:
            killed = f"killed above {rss_limit_gb:g} GB resident"
        if killed:
            child.kill()
            break
        time.sleep(0.1)
    stdout, stderr = child.communicate()
    for line in stdout.splitlines():
        if line.startswith("FIRST_CALL "):
            return dict(ok=True, **json.loads(line[len("FIRST_CALL ") :]))
    lines = [x for x in stderr.strip().splitlines() if x.strip()]
    return {"ok": False, "failure": killed or (lines[-1][:200] if lines else f"exit {child.returncode}")}


def first_calls(cases: dict, title="First call in a fresh process", **options) -> list:
    """`first_call` of each {label: (setup, call)} or {label: (setup, call, options)} (which
    update `options`), printed as one table; the rows."""
    rows = []
    for label, (setup, call, *own) in cases.items():
        rows.append(dict(case=label, **first_call(setup, call, **{**options, **(own[0] if own else {})})))
    first_call_table(rows, title)
    return rows


def first_call_table(rows: list, title="First call in a fresh process"):
    """`first_call` rows, each with its `case`, as one table."""
    table(
        title + " (imports, then the first call: tracing + compilation + one run)",
        rows,
        [("case", "case", "s"), ("import s", "import_s", ".1f"),
         ("first call s", "first_call_s", ".1f"), ("peak RSS MB", "peak_rss_mb", ".0f")],
    )


def drain():
    """Wait for a failed solve's pending runtime error, so that the next call starts clean."""
    import jax

    try:
        jax.effects_barrier()
    except Exception:  # noqa: BLE001, S110 - the failure was recorded by the caller
        pass


def failure(exc: BaseException) -> str:
    """The line of an exception's message that says what went wrong."""
    lines = [x.strip() for x in str(exc).strip().splitlines() if x.strip()]
    keys = ("EquinoxRuntimeError", "max_steps", "maximum", "must", "Error:")
    reason = [x for x in lines if any(k in x for k in keys)] or lines or [type(exc).__name__]
    return reason[0].split("EquinoxRuntimeError:", 1)[-1].strip()[:160]


# --------------------------------------------------------------------------------------
# Output.


def _cell(row: dict, key: str, fmt: str) -> str:
    value = row.get(key)
    if value is None:
        return "-"
    if isinstance(value, str) or fmt == "s":
        return str(value)
    try:
        return format(value, fmt)
    except (TypeError, ValueError):
        return str(value)


def table(title: str, rows: list, columns: list):
    """Print `rows` (dicts) under `title` as a markdown table; `columns` are (header, key,
    format spec). A failed row (`ok` False) shows its `failure` in its first empty cell."""
    cells = [[h for h, _, _ in columns]]
    for row in rows:
        line = [_cell(row, k, f) for _, k, f in columns]
        if row.get("ok", True) is False and "-" in line:
            line[line.index("-")] = "FAILED: " + str(row.get("failure"))[:70]
        cells.append(line)
    widths = [max(len(c[i]) for c in cells) for i in range(len(columns))]
    print(f"\n{title}\n")
    for i, line in enumerate(cells):
        print("| " + " | ".join(c.rjust(w) for c, w in zip(line, widths)) + " |")
        if i == 0:
            print("|" + "|".join("-" * (w + 2) for w in widths) + "|")
    sys.stdout.flush()


def meta(args, **extra) -> dict:
    import diffrax
    import jax
    import numpy as np

    import barrierjax

    return dict(
        date=datetime.datetime.now().isoformat(timespec="seconds"),
        quick=bool(args.quick),
        seed=args.seed,
        machine={
            "cpu_count": os.cpu_count(),
            "load_average_start": LOAD_AT_START,
            "load_average_end": os.getloadavg(),
            "platform": platform.platform(),
            "python": platform.python_version(),
            "device": jax.devices()[0].platform,
        },
        versions={
            "jax": jax.__version__,
            "diffrax": diffrax.__version__,
            "barrierjax": getattr(barrierjax, "__version__", "?"),
            "numpy": np.__version__,
        },
        **extra,
    )


def write_json(args, name: str, data: dict, **extra) -> Path:
    """`data` with a `meta` block first, as `<out>/<name>.json`."""
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / f"{name}.json"
    path.write_text(json.dumps(dict(meta=meta(args, **extra), **data), indent=1, default=float))
    print(f"\nwrote {path}")
    return path


def pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, args, name: str) -> Path:
    args.out.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    path = args.out / f"{name}.png"
    fig.savefig(path, dpi=120)
    pyplot().close(fig)
    return path
