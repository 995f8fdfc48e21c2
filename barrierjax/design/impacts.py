r"""Real-world impact conditions as data with sources, and the representative impacts
(`real_world_impacts`) that a robust design averages over.

What is measured, and where:

- Impact severity, IS = M (v sin theta)^2 / 2, the kinetic energy of the impact velocity's
  component normal to the barrier: NCHRP Report 665 (Sicking, Lechtenberg and Peterson,
  "Identification of Vehicular Impact Conditions Associated with Serious Ran-off-Road
  Crashes", TRB 2010), Table 78 (p. 48): 868 reconstructed serious or fatal ran-off-road
  crashes (NASS-CDS), by road class: mean, median, standard deviation, 90th and 95th
  percentiles (`IMPACT_SEVERITY`). The report's text notes that the Interstate 95th
  percentile, 160 kJ, is close to the 156 kJ of MASH test 3-11 (2270 kg at 100 km/h and
  25 degrees: 156.4 kJ). The report models speed and angle separately too, but their
  parameters are not held here; IS is the quantity the report's normal-impact model
  (3.2) takes, so the robust design of `barrierjax.design.robust` uses it directly.
- Vehicle mass: Stolle, Ronspies, Bielenberg and Faller, "Evaluation and Update of MASH
  Test Vehicles", NCHRP 20-07 Task 372 (MwRSF, 2021): US new-vehicle sales, 5th
  percentile 2,800 lb (1,270 kg), 92.5th 5,400 lb (2,449 kg), 95th 5,850 lb (2,654 kg)
  (`VEHICLE_MASS`). New-vehicle sales, not the crash-involved fleet.

The fits are this project's, not the sources': each quantity is taken as lognormal, fitted
exactly to two published percentiles (IS: the median and the 95th percentile, the tail
that sizes a barrier; mass: the 5th and 95th), and the other published numbers are
compared openly (`Lognormal.check`): Interstate IS, mean 51.7 kJ against 51.06 kJ
published (+1.3 %), 90th percentile 112 kJ against 123 kJ (-9 %); mass, 92.5th
percentile 2,536 kg against 2,449 kg (+3.5 %). IS and mass are taken as independent (the
sources give no joint distribution).
"""

import dataclasses
import math
from statistics import NormalDist

import numpy as np

KJ = 1e3  # J
_STANDARD = NormalDist()
LB = 0.45359237  # kg


@dataclasses.dataclass(frozen=True)
class SeverityStatistics:
    """One road class's row of NCHRP Report 665 Table 78: the number of crashes `n` and the
    impact severity's `mean`, `median`, `std`, `p90` and `p95`, in J."""

    road_class: str
    n: int
    mean: float
    median: float
    std: float
    p90: float
    p95: float


_NCHRP_665 = "NCHRP Report 665 (2010), Table 78, p. 48"

# NCHRP Report 665 Table 78 (kJ): N, mean, median, standard deviation, 90th and 95th
# percentiles, by road class.
# fmt: off
IMPACT_SEVERITY = {
    row[0]: SeverityStatistics(row[0], row[1], *(KJ * v for v in row[2:]))
    for row in (
        ("all", 868, 38.91, 18.46, 57.34, 98.54, 143.31),
        ("Interstate", 194, 51.06, 32.13, 66.70, 123.15, 159.89),
        ("US Route", 157, 32.63, 14.52, 43.60, 80.41, 121.74),
        ("State Route", 159, 43.66, 19.92, 61.53, 113.65, 180.34),
        ("County Road", 273, 28.68, 14.78, 42.52, 69.45, 100.90),
        ("City Street", 42, 23.15, 15.83, 24.70, 48.95, 62.04),
    )
}
# fmt: on

# Stolle et al., NCHRP 20-07 Task 372 (2021): percentiles of US new-vehicle sales' weights.
VEHICLE_MASS = {0.05: 2800 * LB, 0.925: 5400 * LB, 0.95: 5850 * LB}
_STOLLE = "Stolle et al., NCHRP 20-07 Task 372 (2021), new-vehicle sales"


@dataclasses.dataclass(frozen=True)
class Lognormal:
    """ln X normal with mean `log_median` and standard deviation `sigma`, fitted to two
    published percentiles; `source` says which, and `published` holds the others
    ({name: (value, quantile or None for the mean)}) for `check`."""

    log_median: float
    sigma: float
    source: str
    published: tuple[tuple[str, float, float | None], ...] = ()

    @classmethod
    def through(cls, p1, x1, p2, x2, source, published=()):
        """The lognormal whose p1 and p2 quantiles are x1 and x2 (0 < p1 < p2 < 1 and
        0 < x1 < x2, else `ValueError`)."""
        if not (0.0 < p1 < p2 < 1.0 and 0.0 < x1 < x2 < math.inf):
            raise ValueError(
                "Lognormal.through needs 0 < p1 < p2 < 1 and 0 < x1 < x2 (finite); got "
                f"p1={p1!r}, x1={x1!r}, p2={p2!r}, x2={x2!r}"
            )
        z1, z2 = _STANDARD.inv_cdf(p1), _STANDARD.inv_cdf(p2)
        sigma = math.log(x2 / x1) / (z2 - z1)
        return cls(math.log(x1) - sigma * z1, sigma, source, tuple(published))

    def quantile(self, p):
        z = np.vectorize(_STANDARD.inv_cdf)(np.asarray(p, dtype=float))
        return np.exp(self.log_median + self.sigma * z)

    @property
    def mean(self) -> float:
        return math.exp(self.log_median + 0.5 * self.sigma**2)

    def check(self) -> list[tuple[str, float, float]]:
        """(name, published, this fit's) for every published number the fit was not
        fitted to."""
        fitted = lambda q: self.mean if q is None else float(self.quantile(q))
        return [(name, value, fitted(q)) for name, value, q in self.published]

    def nodes(self, n: int) -> np.ndarray:
        """`n` equally probable representative values: the mean of X within each of n
        slices of equal probability, E[X | q_k < X < q_k+1] with q_k the k/n quantile,
        so that the nodes' average is the distribution's mean exactly (a midpoint
        quantile per slice would miss the tail: -3 % of the Interstate mean at n = 32).
        For ln X normal, E[X; a < Z < b] = e^(mu + sigma^2/2) (Phi(b - s) - Phi(a - s))."""
        z = [_STANDARD.inv_cdf(k / n) for k in range(1, n)]
        edges = np.array([-np.inf, *z, np.inf])
        cdf = np.vectorize(_STANDARD.cdf)
        share = np.diff(cdf(edges - self.sigma))
        return self.mean * share * n


def impact_severity(road_class: str = "Interstate") -> Lognormal:
    """The impact severity (J) of `road_class` (a key of `IMPACT_SEVERITY`), lognormal
    through its published median and 95th percentile."""
    if road_class not in IMPACT_SEVERITY:
        raise ValueError(
            f"road_class must be one of {', '.join(map(repr, IMPACT_SEVERITY))}; got {road_class!r}"
        )
    row = IMPACT_SEVERITY[road_class]
    return Lognormal.through(
        0.5, row.median, 0.95, row.p95,
        f"{_NCHRP_665}, {road_class}: median and 95th percentile",
        (("mean", row.mean, None), ("90th percentile", row.p90, 0.90)),
    )  # fmt: skip


def vehicle_mass() -> Lognormal:
    """The vehicle mass (kg), lognormal through the published 5th and 95th percentiles."""
    (p1, x1), (p_mid, x_mid), (p2, x2) = sorted(VEHICLE_MASS.items())
    return Lognormal.through(
        p1, x1, p2, x2, f"{_STOLLE}: 5th and 95th percentiles",
        (("92.5th percentile", x_mid, p_mid),),
    )  # fmt: skip


@dataclasses.dataclass(frozen=True)
class Impacts:
    """Representative impacts, each equally probable: vehicle `mass` (kg), impact
    `severity` (J) and the `normal_speed` sqrt(2 IS / M) (m/s) it implies; with the
    distributions they were drawn from."""

    mass: np.ndarray
    severity: np.ndarray
    normal_speed: np.ndarray
    severity_distribution: Lognormal
    mass_distribution: Lognormal


def real_world_impacts(
    road_class: str = "Interstate", n_severity: int = 32, n_mass: int = 8
) -> Impacts:
    """`n_severity` x `n_mass` equally probable impacts: every pair of the severity's and
    the mass's `Lognormal.nodes` (independent)."""
    for name, n in (("n_severity", n_severity), ("n_mass", n_mass)):
        if int(n) != n or n < 1:
            raise ValueError(f"{name} must be a positive integer; got {n!r}")
    severity_distribution, mass_distribution = impact_severity(road_class), vehicle_mass()
    severity, mass = np.meshgrid(
        severity_distribution.nodes(int(n_severity)), mass_distribution.nodes(int(n_mass))
    )
    mass, severity = mass.ravel(), severity.ravel()
    return Impacts(
        mass, severity, np.sqrt(2.0 * severity / mass), severity_distribution, mass_distribution
    )
