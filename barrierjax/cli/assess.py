"""`barrierjax assess RECORD.csv`: the occupant-risk metrics of a crash-test record
(`barrierjax.assess.read_record`, `occupant_risk`) against a standard's limits
(`barrierjax.assess.verdict.judge`): a table, or one JSON object in SI, and plots."""

from __future__ import annotations

import dataclasses

import jax
import numpy as np

from ..assess import filters
from ..assess.matrices import G
from .output import EXIT_FAILED, EXIT_OK, CommandError, print_result

__all__ = ["assess_command", "assessment_dict", "format_assessment"]

_METRICS = ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "t_head", "thiv", "phd", "asi")
_UNITS = {"t_impact": "s", "t_head": "s", "oiv_x": "m/s", "oiv_y": "m/s", "thiv": "m/s",
          "ora_x": "m/s^2", "ora_y": "m/s^2", "phd": "m/s^2", "asi": "1"}  # fmt: skip

# The channels filtered together, one program (operation by operation, some twenty small
# programs to compile in each new process).
_cfc_filtered = jax.jit(filters.cfc_filter, static_argnums=(1, 2))


def conditioned(record, cfc):
    """The record with its acceleration channels through SAE J211 CFC `cfc` (None: as read)."""
    if cfc is None:
        return record
    names = [name for name in ("ax", "ay", "az") if getattr(record, name) is not None]
    channels = np.stack([getattr(record, name) for name in names])
    through = np.asarray(_cfc_filtered(channels, record.dt, cfc))
    return dataclasses.replace(record, **dict(zip(names, through)))


def assessment_dict(path, record, risk, criteria, *, standard, cfc, asi_edition) -> dict:
    """The assessment as a JSON-ready dict, SI: every metric under its name, the criteria."""
    from ..assess.verdict import standard_name

    return {
        "record": str(path),
        "samples": int(record.t.size),
        "sampling_rate_Hz": 1.0 / record.dt,
        "units_read": record.units,
        "filter": f"SAE J211 CFC {cfc}" if cfc is not None else "none",
        "asi_edition": asi_edition,
        **{name: float(np.asarray(getattr(risk, name))) for name in _METRICS},
        "units": _UNITS,
        "impact_in_record": bool(risk.impact_in_record),
        "standard": standard_name(standard),
        "criteria": [dataclasses.asdict(c) | {"passed": c.passed} for c in criteria],
        "passed": all(c.passed for c in criteria),
    }


def _limit(value, unit):
    if value is None:
        return "-"
    return f"{value / G:.2f} g" if unit == "m/s^2" else f"{value:.2f} {unit}".replace(" 1", "")


def format_assessment(data: dict) -> str:
    """A readable table of `assessment_dict(...)`: every metric, then the criteria."""
    g = G
    lines = [
        (
            f"Record: {data['record']} ({data['samples']} samples at "
            f"{data['sampling_rate_Hz']:.0f} Hz, accelerations {data['filter']})"
        ),
        "",
        "Occupant risk",
        f"  occupant impact (flail space)   {data['t_impact'] * 1e3:9.1f} ms"
        + (
            ""
            if data["impact_in_record"]
            else "   (after the record: the vehicle taken unaccelerated)"
        ),
        f"  OIV x, y                        {data['oiv_x']:9.2f} {data['oiv_y']:9.2f} m/s",
        f"  ORA x, y                        {data['ora_x'] / g:9.2f} {data['ora_y'] / g:9.2f} g",
        f"  head impact                     {data['t_head'] * 1e3:9.1f} ms",
        f"  THIV                            {data['thiv']:9.2f} m/s ({data['thiv'] * 3.6:.1f} km/h)",
        f"  PHD                             {data['phd'] / g:9.2f} g",
        f"  ASI (EN 1317-1:{data['asi_edition']})            {data['asi']:9.2f}",
        "",
        f"{data['standard']}: {'PASS' if data['passed'] else 'FAIL'}",
        f"  {'criterion':<8} {'value':>12} {'preferred':>12} {'maximum':>12}   verdict",
    ]
    for c in data["criteria"]:
        lines.append(
            f"  {c['name']:<8} {_limit(c['value'], c['unit']):>12} {_limit(c['preferred'], c['unit']):>12} "
            f"{_limit(c['maximum'], c['unit']):>12}   {c['verdict']}   ({c['source']})"
        )
    return "\n".join(lines)


def assess_command(args) -> int:
    """`barrierjax assess RECORD.csv [--standard S] [--json] [--out DIR]`: the exit status
    (0 the record passes, 1 it fails a criterion, 2 a bad record)."""
    from ..assess import occupant_risk
    from ..assess.plots import write_assessment_plots
    from ..assess.record import RecordError, read_record
    from ..assess.verdict import judge

    try:
        record = read_record(args.record)
    except RecordError as error:
        raise CommandError(str(error)) from None
    cfc = None if args.cfc == 0 else args.cfc
    if cfc is not None and record.dt * cfc * filters.J211_DESIGN_FACTOR >= 0.5:
        raise CommandError(
            f"--cfc {cfc}: the record's {1 / record.dt:g} Hz sampling is too slow for it"
        )
    record = conditioned(record, cfc)
    risk = occupant_risk(
        record.t, record.ax, record.ay, record.yaw_rate, record.az, asi_edition=args.asi_edition
    )
    if not bool(risk.impact_in_record):
        raise CommandError(
            f"{args.record}: OIV undefined: the occupant does not reach the flail space "
            f"(0.6 m forward, 0.3 m sideways) within the record, which ends at "
            f"{record.t[-1] * 1e3:g} ms; a record must run past the occupant impact"
        )
    criteria = judge(risk, args.standard)
    data = assessment_dict(
        args.record,
        record,
        risk,
        criteria,
        standard=args.standard,
        cfc=cfc,
        asi_edition=args.asi_edition,
    )
    plots = (
        [] if args.no_plots else write_assessment_plots(record, risk, args.out, args.asi_edition)
    )
    print_result(args, data, plots, format_assessment)
    return EXIT_OK if data["passed"] else EXIT_FAILED
