"""Sweeps of a scene over ranges of its keys: scenarios drawn from a distribution, solved by
`barrierjax.simulate` in batches of one compiled shape, written as they finish.

A sweep varies dotted scene keys (`impact.speed`, `impact.angle`, `vehicle.mass`,
`barrier.backing_strength`, ...: any key of `scene_file.FIELDS`) between bounds written
as scene-file quantities ("30 km/h") or as bare numbers in the key's SI unit (degrees for
an angle). The scenarios (`draw`) are uniform, Latin hypercube (`lhs`: each of N equal
strata of every key drawn once) or normal (`normal`: mean at the middle of the range, the
half-range two standard deviations, clipped to the range), all from one seed, so that a
sweep is the same file whenever it runs. Each row of the result holds the varied inputs
(SI, named by their keys) and every scalar field of the `Result` (SI).

Rows are solved in chunks (at most `chunk` rows, as equal as the count allows; each padded
to one shape for the solve): on one device by `simulate` on the chunk's arrays, as a user's
call would (the models' own programs, kept on disk by the command line, in parts side by
side on a CPU); on several, sharded across them (`jax.sharding`: a multi-GPU host splits
each chunk's rows, and so do the hosts of `jax.distributed`, whose
process 0 writes the files), each written to its own Parquet
file in `OUT.parts/` beside a manifest of the sweep; at the end the chunks are joined into
`OUT` (Parquet, or CSV for a `.csv` name) and the folder removed. An interrupted sweep
leaves its finished chunks: `resume=True` with the same sweep solves only the rest.
"""

import dataclasses
import hashlib
import json
import math
import os
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from . import _checks, _xla_flags
from ._solve.phases import SolveError
from .scene import Scene
from .scene_file import FIELDS, Field, SceneFileError, parse_quantity
from .sharding import sharded_batch
from .simulate import Result, simulate

DISTRIBUTIONS = ("uniform", "lhs", "normal")


class SweepError(ValueError):
    """A sweep that cannot run, in one line naming what is wrong."""


@dataclass(frozen=True)
class Vary:
    """A scene key varied between `low` and `high` (in the key's unit, `field.unit`)."""

    key: str
    low: float
    high: float
    field: Field


def parse_vary(text: str, fields: dict = FIELDS) -> Vary:
    """`KEY=LOW:HIGH` (e.g. "impact.speed=30 km/h:60 km/h", "vehicle.mass=1000:2500"), a key
    of `fields` (a barrier-system scene's: `system.sweep.SWEEP_FIELDS`)."""
    key, equals, bounds = text.partition("=")
    key = key.strip()
    section, dot, name = key.partition(".")
    if not dot or section not in fields or name not in fields[section]:
        keys = ", ".join(f"{s}.{k}" for s, table in fields.items() for k in table)
        raise SweepError(f"--vary {key!r}: unknown key (expected one of {keys})")
    field = fields[section][name]
    low, colon, high = bounds.partition(":")
    if not equals or not colon:
        raise SweepError(f"--vary {key}: expected {key}=LOW:HIGH, got {text!r}")
    values = []
    for bound in (low.strip(), high.strip()):
        try:
            number = float(bound)
            bound = f"{number} {field.unit}" if field.dimension is not None else number
        except ValueError:
            pass
        try:
            values.append(parse_quantity(bound, field))
        except SceneFileError as error:
            message = str(error).split(": ", 1)[-1]
            raise SweepError(f"--vary {key}: {message}") from None
    if not values[0] < values[1]:
        raise SweepError(f"--vary {key}: empty range {values[0]:g} to {values[1]:g} "
                         f"{field.unit} (LOW must be below HIGH)")  # fmt: skip
    return Vary(key, values[0], values[1], field)


def draw(varies: list[Vary], n: int, seed: int, distribution: str = "uniform") -> np.ndarray:
    """`n` scenarios (n, len(varies)) in the keys' units."""
    if distribution not in DISTRIBUTIONS:
        raise SweepError(f"--distribution: unknown {distribution!r} (expected one of "
                         f"{', '.join(DISTRIBUTIONS)})")  # fmt: skip
    rng = np.random.default_rng(seed)
    k = len(varies)
    if distribution == "uniform":
        unit = rng.random((n, k))
    elif distribution == "lhs":
        strata = np.stack([rng.permutation(n) for _ in range(k)], 1)
        unit = (strata + rng.random((n, k))) / n
    else:
        unit = np.clip(0.5 + 0.25 * rng.standard_normal((n, k)), 0.0, 1.0)
    low = np.array([v.low for v in varies])
    high = np.array([v.high for v in varies])
    return low + unit * (high - low)


def _with_values(scene: Scene, varies: list[Vary], values) -> Scene:
    """`scene` with each varied key an array of `values`' column (one value each, of a
    1-D `values`)."""
    for v, column in zip(varies, values.T, strict=True):
        parameter = v.field.parameter
        scene = eqx.tree_at(lambda s, v=v, p=parameter: getattr(getattr(s, v.field.section), p),
                            scene, column, is_leaf=lambda x: x is None)  # fmt: skip
    return scene


def check_ranges(scene: Scene, varies: list[Vary]):
    """Each range's ends put through the scene's constructors, whose rules every value
    between them then meets (they are bounds: positive, non-negative, an angle in (0, 90]):
    the drawn values are set on the scene's leaves, past the constructors."""
    for v in varies:
        for end, value in (("LOW", v.low), ("HIGH", v.high)):
            section = getattr(_with_values(scene, [v], np.array([value])), v.field.section)
            try:
                type(section)(*(getattr(section, f.name) for f in dataclasses.fields(section)))
            except ValueError as error:
                shown = f"{value:g} {v.field.unit}".strip()
                raise SweepError(f"--vary {v.key}: {end} {shown}: {error}") from None


def result_columns(result: Result, n: int) -> dict[str, np.ndarray]:
    """Every scalar field of a batch's `Result`, one value for each of its `n` scenarios
    (a field the sweep does not vary, e.g. the peak force, repeated)."""
    columns = {}
    for name in result.__dataclass_fields__:
        value = getattr(result, name)
        if isinstance(value, jax.Array | np.ndarray) and value.ndim <= 1:
            columns[name] = np.broadcast_to(np.asarray(value), (n,))
    return columns


def _solver(scene: Scene, varies: list[Vary], rtol: float | None = None) -> Callable:
    """The batch's solve. On one device, `simulate` on the chunk's concrete arrays: the
    models' own entry points, whose programs the command line keeps on disk
    (`compilation_cache.stored_program`), run in parts on a CPU and grow a spent step
    budget. A `jit` around them would hold their run-time checks, host callbacks, and JAX's
    persistent cache keeps no program with those: every sweep of oblique impacts compiled
    its chunk again (21 s of the 27-30 s of 10^5 of them, 2026-11-28). On several devices,
    `sharded_batch` (`XLA_FLAGS=--xla_force_host_platform_device_count=N` emulates N on a
    CPU)."""
    oblique = any(v.key == "impact.angle" for v in varies) or float(scene.impact.angle_deg) < 90

    def solve(values):
        batch = _with_values(scene, varies, values)
        return simulate(batch, n_history=0, oblique=True if oblique else None, rtol=rtol)

    if jax.device_count() == 1:
        solved = lambda values: solve(jnp.asarray(values))  # (result_columns: to NumPy)
    else:
        # The oblique model's batch runs faster with its own XLA options (`_xla_flags`).
        options = _xla_flags.batched_step_options() if oblique else {}
        solved = sharded_batch(solve, compiler_options=options or None)
    return lambda values: result_columns(solved(values), len(values))


@dataclass(frozen=True)
class Sweep:
    """A sweep: what it varies, how many scenarios and how drawn, in chunks of `chunk`;
    with `skip_failures`, a scenario the model cannot solve is a row of nulls with its
    error in the column `failure` (else it ends the sweep); `rtol`, the impact models'
    relative tolerance (None: each model's default)."""

    varies: list[Vary]
    samples: int
    seed: int
    distribution: str = "uniform"
    chunk: int = 65536
    skip_failures: bool = False
    rtol: float | None = None

    def manifest(self, scene) -> dict:
        if isinstance(scene, Scene):
            numbers = jax.tree.leaves(scene)
        else:
            from .system.sweep import scene_numbers

            numbers = scene_numbers(scene)
        digest = hashlib.sha256()
        for x in numbers:
            digest.update(np.asarray(x, np.float64).tobytes())
        return {"vary": [[v.key, v.low, v.high] for v in self.varies], "samples": self.samples,
                "seed": self.seed, "distribution": self.distribution, "chunk": self.chunk,
                "skip_failures": self.skip_failures, "scene": digest.hexdigest()} | (
                {} if self.rtol is None else {"rtol": self.rtol})  # fmt: skip


def parts_folder(out: Path) -> Path:
    return out.with_name(out.name + ".parts")


def run_sweep(scene, sweep: Sweep, out, *, resume=False, progress=None) -> dict:
    """Solve `sweep` of `scene` (a `Scene`, or a barrier-system scene,
    `system.scene.SystemScene`: its crash-test numbers, `system.design.crash_numbers`) into
    the file `out` (see the module docstring); returns its columns. `progress(n)` is called
    with the rows of each finished chunk. Under `jax.distributed`, every process runs this
    with the same arguments; each computes its devices' share of every chunk, process 0
    writes the files and returns the columns, the others return {}."""
    out = Path(out)
    if sweep.samples < 1:
        raise SweepError(f"--samples must be a positive integer; got {sweep.samples}")
    if sweep.chunk < 1:
        raise SweepError(f"--chunk must be a positive integer; got {sweep.chunk}")
    if not sweep.varies:
        raise SweepError("nothing to vary: give at least one --vary KEY=LOW:HIGH")
    if out.suffix.lower() not in (".parquet", ".csv"):
        raise SweepError(f"--out {out}: name a .parquet or a .csv file (the rows' format)")
    keys = [v.key for v in sweep.varies]
    for key in keys:
        if keys.count(key) > 1:
            raise SweepError(f"--vary {key}: given twice (one range a key)")
    if isinstance(scene, Scene):
        check_ranges(scene, sweep.varies)
    if sweep.rtol is not None:
        if not isinstance(scene, Scene):
            raise SweepError(
                "--rtol: a barrier-system scene steps at its own fixed time step; the "
                "tolerance is the impact models' (report 3.2-3.4)"
            )
        try:
            _checks.tolerance("--rtol", sweep.rtol)
        except ValueError as error:
            raise SweepError(str(error)) from None
    values = draw(sweep.varies, sweep.samples, sweep.seed, sweep.distribution)
    parts = parts_folder(out)
    manifest = sweep.manifest(scene)
    lead = jax.process_index() == 0  # with jax.distributed, process 0 alone writes files
    if lead:
        _prepare(parts, out, manifest, resume)
    import pyarrow as pa
    import pyarrow.parquet as pq

    if isinstance(scene, Scene):
        solve = _solver(scene, sweep.varies, sweep.rtol)
    else:
        from .system.sweep import system_solver

        solve = system_solver(scene, sweep.varies)
    # Chunks as equal as the count allows, at most `chunk` (the files' layout, whatever the
    # devices), each padded for the solve to one shape, a multiple of the device count.
    n_chunks = math.ceil(sweep.samples / sweep.chunk)
    size = math.ceil(sweep.samples / n_chunks)
    devices = jax.device_count()
    shape = devices * math.ceil(size / devices)
    paths = [parts / f"part-{index:05d}.parquet" for index in range(n_chunks)]
    done = _agreed([lead and path.exists() for path in paths])
    for index, path in enumerate(paths):
        rows = values[index * size : (index + 1) * size]
        if done[index]:
            if progress:
                progress(len(rows))
            continue
        padded = np.concatenate([rows, np.repeat(rows[-1:], shape - len(rows), 0)])
        try:
            columns, failed = _solved(solve, padded, len(rows), sweep.skip_failures)
        except SolveError as error:
            raise _failed_row(error, sweep.varies, rows, index * size, parts) from None
        if lead:
            mask = np.isin(np.arange(len(rows)), list(failed))
            table = {v.key: rows[:, i] for i, v in enumerate(sweep.varies)}
            table |= {name: pa.array(column[: len(rows)], mask=mask if failed else None)
                      for name, column in columns.items()}  # fmt: skip
            if sweep.skip_failures:
                table["failure"] = pa.array([failed.get(k, "") for k in range(len(rows))])
            partial = path.with_suffix(".partial")
            pq.write_table(pa.table(table), partial)
            os.replace(partial, path)  # a chunk is there whole, or not at all
        if progress:
            progress(len(rows))
    if not lead:
        return {}
    joined = pa.concat_tables([pq.read_table(path) for path in paths])
    partial = out.with_name(out.name + ".partial")
    if out.suffix.lower() == ".csv":
        import pyarrow.csv

        pyarrow.csv.write_csv(joined, partial)
    else:
        pq.write_table(joined, partial)
    os.replace(partial, out)
    shutil.rmtree(parts)
    return {name: joined.column(name).to_numpy(zero_copy_only=False)
            for name in joined.column_names}  # fmt: skip


def _solved(solve, rows, n: int, skip_failures: bool):
    """(`solve(rows)`, {row: error} of the first `n` rows that it could not solve). With
    `skip_failures`, the rows whose solve failed (`SolveError.failures`) are taken from the
    error's result where the model solved the chunk before it raised (`SolveError.result`,
    a `Result`); else they are replaced by one that solved, whose results stand in for
    them, and the chunk solved again. Without, the error stands."""
    failed: dict[int, str] = {}
    while True:
        try:
            return solve(rows), failed
        except SolveError as error:
            new = _failed_rows(error, n)
            standing_in = [i for i in range(n) if i not in failed and i not in new]
            if not skip_failures or not new or set(new) & set(failed) or not standing_in:
                raise
            failed |= new
            if isinstance(error.result, Result):
                return result_columns(error.result, len(rows)), failed
            rows = rows.copy()
            rows[list(new)] = rows[standing_in[0]]
            if n - 1 in new:
                rows[n:] = rows[standing_in[0]]


def _failed_rows(error: SolveError, n: int) -> dict[int, str]:
    """`error.failures` by row of a chunk of `n` rows padded with copies of its last: a
    copy that failed is that row."""
    rows: dict[int, str] = {}
    for k, reason in sorted(error.failures.items()):
        rows.setdefault(min(k, n - 1), reason)
    return rows


def _failed_row(error: SolveError, varies: list[Vary], rows, start: int, parts: Path):
    """`error` of a chunk's solve, naming the sweep's first row that failed and its
    values; its `failures` by the sweep's rows."""
    failures = {start + k: reason for k, reason in _failed_rows(error, len(rows)).items()}
    where = f"rows {start}-{start + len(rows) - 1}"
    if failures:
        k = min(failures) - start
        values = ", ".join(f"{v.key}={x:.6g}" for v, x in zip(varies, rows[k], strict=True))
        where = f"row {start + k} ({values})"
    return SolveError(
        f"{where}: {error}; the finished chunks are in {parts}: --resume carries on", failures
    )


def _agreed(flags: list[bool]) -> list[bool]:
    """Process 0's `flags` in every process (`jax.distributed`): which chunks it already
    holds, so that every process skips the same ones."""
    if jax.process_count() == 1:
        return flags
    from jax.experimental import multihost_utils

    return [bool(f) for f in multihost_utils.broadcast_one_to_all(np.array(flags, dtype=bool))]


def _prepare(parts: Path, out: Path, manifest: dict, resume: bool):
    """The chunks' folder, new or (resuming) the same sweep's; refuses anything else in
    one line."""
    record = parts / "manifest.json"
    if parts.exists():
        if not resume:
            raise SweepError(f"{parts} holds an unfinished sweep: pass --resume to carry it "
                             f"on, or remove it")  # fmt: skip
        try:
            previous = json.loads(record.read_text())
        except (OSError, ValueError):
            raise SweepError(f"{parts}: no readable manifest.json; remove the folder") from None
        if previous != manifest:
            raise SweepError(f"{parts} holds a different sweep (another scene, keys, ranges, "
                             f"samples, seed, distribution, chunk or --skip-failures): remove "
                             f"it or match it")  # fmt: skip
        return
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        parts.mkdir()
        record.write_text(json.dumps(manifest))
    except OSError as error:
        raise SweepError(f"--out {out}: cannot write there ({error.strerror or error})") from None
