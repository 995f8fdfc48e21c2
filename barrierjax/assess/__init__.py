"""Crash-test assessment: the occupant-risk metrics of MASH 2016, NCHRP Report 350 and
EN 1317 on vehicle acceleration records (`occupant_risk`), the signal conditioning the
standards prescribe (`filters`), the test matrices and limits as data (`matrices`) and the
verdict against them (`judge`); crash-test records read with their units (`read_record`) and
the project's own impact results (`assess`); exit boxes (`exit_box_check`,
`result_exit_box`)."""

from . import filters, matrices
from .exit_box import ExitBoxCheck, exit_box_check, result_exit_box
from .occupant import OccupantRisk, occupant_risk
from .record import Record, RecordError, read_record
from .results import assess, vehicle_record
from .verdict import Criterion, judge

__all__ = [
    "Criterion",
    "ExitBoxCheck",
    "OccupantRisk",
    "Record",
    "RecordError",
    "assess",
    "exit_box_check",
    "filters",
    "judge",
    "matrices",
    "occupant_risk",
    "read_record",
    "result_exit_box",
    "vehicle_record",
]
