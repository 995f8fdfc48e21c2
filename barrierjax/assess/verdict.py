"""The occupant-risk metrics judged against a standard's limits: `judge`.

MASH 2016 and NCHRP Report 350 judge |OIV| and ORA on each axis against a preferred and a
maximum value (criteria H and I); EN 1317-2:2010 classes the impact severity by ASI (A, B, C)
with THIV at most 33 km/h, and reports PHD for information (its 1998 edition's limit, 20 g).
The limits are `barrierjax.assess.matrices.OCCUPANT_LIMITS`, each with its source.
"""

from dataclasses import dataclass

import numpy as np

from .matrices import IMPACT_SEVERITY_CLASSES, OCCUPANT_LIMITS, STANDARDS

__all__ = ["Criterion", "judge", "standard_name"]


@dataclass(frozen=True)
class Criterion:
    """One metric against its limit: `value` and the limits in SI `unit`; `verdict` is
    "pass" (within the maximum; "pass (preferred)" within the preferred value too),
    "fail", a severity class ("class A") or "informative"."""

    name: str
    value: float
    unit: str
    preferred: float | None
    maximum: float | None
    verdict: str
    source: str

    @property
    def passed(self) -> bool:
        return self.verdict != "fail"


def _against(limit, name: str, value: float) -> Criterion:
    if limit.informative:
        verdict = "informative"
    elif value > limit.maximum:
        verdict = "fail"
    elif limit.preferred is not None and value <= limit.preferred:
        verdict = "pass (preferred)"
    else:
        verdict = "pass"
    source = f"{limit.source.document}, {limit.source.clause}"
    return Criterion(name, value, limit.unit, limit.preferred, limit.maximum, verdict, source)


def _severity_class(asi: float, limit) -> Criterion:
    classes = [c.name for c in IMPACT_SEVERITY_CLASSES if asi <= c.asi_max]
    verdict = f"pass (class {classes[0]})" if classes else "fail"
    source = f"{limit.source.document}, {limit.source.clause}"
    return Criterion("ASI", asi, "1", None, limit.maximum, verdict, source)


_JUDGED = ("oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi")


def judge(risk, standard: str = "mash") -> list[Criterion]:
    """The criteria of `standard` ("mash", "nchrp350", "en1317") on one `OccupantRisk`
    (of a batch, index it first: `jax.tree.map(lambda a: a[i], risk)`). A metric that is
    not finite is an error, never a verdict."""
    if standard not in OCCUPANT_LIMITS:
        raise ValueError(f"standard must be one of {', '.join(OCCUPANT_LIMITS)}; got {standard!r}")
    limits = OCCUPANT_LIMITS[standard]
    value = {name: np.asarray(getattr(risk, name)) for name in _JUDGED}
    for name, metric in value.items():
        if metric.ndim:
            raise ValueError(
                f"judge takes one record's OccupantRisk; {name} has shape {metric.shape} "
                "(index the batch first: jax.tree.map(lambda a: a[i], risk))"
            )
        if not np.isfinite(metric):
            raise ValueError(f"{name} must be finite to be judged; got {float(metric)}")
    value = {name: float(metric) for name, metric in value.items()}
    if standard in ("mash", "nchrp350"):
        return [
            _against(limits["OIV"], "OIV x", abs(value["oiv_x"])),
            _against(limits["OIV"], "OIV y", abs(value["oiv_y"])),
            _against(limits["ORA"], "ORA x", value["ora_x"]),
            _against(limits["ORA"], "ORA y", value["ora_y"]),
        ]
    return [
        _severity_class(value["asi"], limits["ASI"]),
        _against(limits["THIV"], "THIV", value["thiv"]),
        _against(limits["PHD"], "PHD", value["phd"]),
    ]


def standard_name(standard: str) -> str:
    """The printed name of a standard key ("mash" -> "MASH")."""
    return STANDARDS[standard]
