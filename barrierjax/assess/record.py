"""Crash-test accelerometer records as test houses export them: `read_record`.

A record is a CSV file with one header row of column names and one row per sample:

    t [ms], ax [g], ay [g], yaw_rate [deg/s]
    0.0, 0.01, -0.02, 0.0
    0.1, -0.35, 0.04, 0.1
    ...

`t`, `ax` and `ay` are required; `az` and `yaw_rate` are read where present; any other
column is ignored (records carry many channels). Each name may carry its unit in brackets,
parsed by pint (`barrierjax.units`): any unit of time for `t`, of acceleration for `ax`,
`ay`, `az` (where `g` and `G` mean standard gravity, 9.80665 m/s^2, as crash-test records
use them, not gram or gauss), of angular velocity for `yaw_rate`; without one, SI (s, m/s^2,
rad/s). The samples must be finite, and the times strictly increasing and uniformly spaced
(within 0.1 % of the mean step, the rounding of printed times; they are then taken exactly
uniform). A malformed record raises `RecordError`, one line naming the column (or row) and
the rule.
"""

import csv
import io
import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import units

__all__ = ["COLUMNS", "Record", "RecordError", "read_record"]

# Column -> (its kind of unit in pint's dimensions, its SI unit, what it is).
COLUMNS = {
    "t": ("[time]", "s", "time"),
    "ax": ("[length] / [time] ** 2", "m/s^2", "acceleration"),
    "ay": ("[length] / [time] ** 2", "m/s^2", "acceleration"),
    "az": ("[length] / [time] ** 2", "m/s^2", "acceleration"),
    "yaw_rate": ("1 / [time]", "rad/s", "angular velocity"),
}
REQUIRED = ("t", "ax", "ay")
_GRAVITY = {"g", "G", "gs", "g's"}  # test houses' "g": standard gravity
_HEADER = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:\[\s*([^\]]*?)\s*\])?\s*$")
UNIFORM_TOLERANCE = 1e-3  # relative spread of the time steps accepted as uniform


class RecordError(ValueError):
    """A record that cannot be read, with one line that says where and why."""

    def __init__(self, message: str):
        super().__init__(" ".join(str(message).split()))


@dataclass(frozen=True)
class Record:
    """A record in SI: times `t` (s, uniform), accelerations `ax`, `ay` (m/s^2), and
    `az` (m/s^2) and `yaw_rate` (rad/s) or None; `units` as the header gave them."""

    t: np.ndarray
    ax: np.ndarray
    ay: np.ndarray
    az: np.ndarray | None
    yaw_rate: np.ndarray | None
    units: dict

    @property
    def dt(self) -> float:
        return float(self.t[1] - self.t[0])


def _text(path: Path) -> str:
    try:
        data = path.read_bytes()
    except OSError as error:
        raise RecordError(f"{path}: cannot be read ({error.strerror or error})") from None
    if not data.strip():
        raise RecordError(f"{path}: the file is empty")
    if b"\x00" in data:
        raise RecordError(f"{path}: not a text CSV file (it holds binary data)")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        raise RecordError(f"{path}: not a text CSV file (not UTF-8 text)") from None


def _unit_factor(column: str, unit: str | None) -> float:
    """The factor from the header's unit of `column` to its SI unit."""
    dimension, si, kind = COLUMNS[column]
    if not unit:
        return 1.0
    registry = units.registry()
    name = "standard_gravity" if unit in _GRAVITY and kind == "acceleration" else unit
    try:
        quantity = registry.Quantity(1.0, name)
    except Exception:  # noqa: BLE001 - pint raises several types for a string it cannot parse
        raise RecordError(f"column '{column}': unknown unit '{unit}'") from None
    if not quantity.check(dimension):
        raise RecordError(f"column '{column}': unit '{unit}' is not a unit of {kind} (e.g. {si})")
    return float(quantity.to(si.replace("^", "**")).magnitude)


def _header(row: list[str]) -> dict[str, tuple[int, str | None]]:
    """Column name -> (position, unit string) of the known columns of the header row."""
    found = {}
    for position, cell in enumerate(row):
        match = _HEADER.match(cell)
        if match is None:
            if not cell.strip():
                raise RecordError(f"header: column {position + 1} has no name")
            if "[" in cell and "]" not in cell:
                raise RecordError(
                    f"header: column '{cell.strip()}' has an unclosed '[' in its unit"
                )
            continue  # a channel of another name style: not one of ours
        name, unit = match.group(1), match.group(2)
        if name in COLUMNS:
            if name in found:
                raise RecordError(f"header: column '{name}' appears twice")
            found[name] = (position, unit)
    missing = [name for name in REQUIRED if name not in found]
    if missing:
        raise RecordError(
            f"missing column '{missing[0]}' (required: t, ax, ay; the header has: "
            f"{', '.join(cell.strip() for cell in row) or 'nothing'})"
        )
    return found


def _values(rows: list[list[str]], name: str, position: int) -> np.ndarray:
    values = np.empty(len(rows))
    for i, row in enumerate(rows):
        line = i + 2  # the file's line: after the header, counting from 1
        if position >= len(row):
            raise RecordError(f"row {line}: {len(row)} fields, no value for column '{name}'")
        try:
            values[i] = float(row[position])
        except ValueError:
            raise RecordError(
                f"row {line}, column '{name}': {row[position].strip()!r} is not a number"
            ) from None
        if not math.isfinite(values[i]):
            raise RecordError(f"row {line}, column '{name}': {row[position].strip()} is not finite")
    return values


def _uniform_times(t: np.ndarray) -> np.ndarray:
    if t.size < 3:
        raise RecordError(f"column 't': {t.size} samples; a record needs at least 3")
    steps = np.diff(t)
    if np.any(steps <= 0):
        row = int(np.argmax(steps <= 0)) + 3
        raise RecordError(f"column 't': times must be strictly increasing (row {row})")
    dt = (t[-1] - t[0]) / (t.size - 1)
    spread = np.abs(steps - dt) / dt
    if np.max(spread) > UNIFORM_TOLERANCE:
        row = int(np.argmax(spread)) + 3
        raise RecordError(
            f"column 't': times must be uniformly sampled (step {steps[row - 3]:g} at row "
            f"{row} against the mean {dt:g})"
        )
    return t[0] + dt * np.arange(t.size)


def read_record(path) -> Record:
    """Read a crash-test record (the CSV format in the module docstring) into SI."""
    path = Path(path)
    try:
        rows = [row for row in csv.reader(io.StringIO(_text(path))) if any(c.strip() for c in row)]
    except csv.Error as error:
        raise RecordError(f"{path}: not a readable CSV file ({error})") from None
    if not rows:
        raise RecordError(f"{path}: the file holds no values")
    columns = _header(rows[0])
    for line, row in enumerate(rows[1:], start=2):
        if len(row) > len(rows[0]):
            raise RecordError(f"row {line}: {len(row)} fields under a header of {len(rows[0])}")
    data = {}
    for name, (position, unit) in columns.items():
        factor = _unit_factor(name, unit)
        with np.errstate(over="ignore"):
            data[name] = _values(rows[1:], name, position) * factor
        if not np.all(np.isfinite(data[name])):
            line = int(np.argmin(np.isfinite(data[name]))) + 2
            raise RecordError(f"row {line}, column '{name}': too large once in SI units")
    return Record(
        t=_uniform_times(data["t"]),
        ax=data["ax"],
        ay=data["ay"],
        az=data.get("az"),
        yaw_rate=data.get("yaw_rate"),
        units={name: unit or COLUMNS[name][1] for name, (_, unit) in columns.items()},
    )
