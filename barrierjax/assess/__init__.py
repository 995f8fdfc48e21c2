"""Crash-test assessment: the occupant-risk metrics of MASH 2016, NCHRP Report 350 and
EN 1317 on vehicle acceleration records (`occupant_risk`), the signal conditioning the
standards prescribe (`filters`), and the test matrices and limits as data (`matrices`)."""

from . import filters, matrices
from .occupant import OccupantRisk, occupant_risk

__all__ = ["OccupantRisk", "filters", "matrices", "occupant_risk"]
