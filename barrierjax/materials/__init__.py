"""Constitutive laws of dynamic plasticity (report chapter 2).

Uniaxial laws, each an `equinox.Module` of its parameters with `init_state()` and the
per-step update `law.update(stress, state, d_strain, dt) -> (stress, state)`
(`update_with_tangent` adds the consistent tangent); `uniaxial_response` gives the stress
history for a prescribed strain history by backward Euler, the report's scheme
(4.2.8)-(4.2.11), forward Euler or a stiff diffrax solver. Delayed yield (2.3):
`delay_time`, `upper_yield_stress`.
"""

from .curves import Bilinear, ElasticPerfectlyPlastic, StaticCurve, Tabulated
from .delayed_yield import (
    constant_stress_delay_time,
    delay_rate,
    delay_time,
    delay_time_of,
    grain_diameter,
    upper_yield_stress,
)
from .hereditary import HereditaryLaw, HereditaryState
from .overstress import (
    CowperSymonds,
    GilmanJohnston,
    LinearOverstress,
    LogOverstress,
    OverstressLaw,
    OverstressState,
    QuadraticOverstress,
    SinhOverstress,
    StrainDependentOverstress,
)
from .plasticity import PlasticState, RateIndependentPlasticity
from .response import METHODS, UniaxialResponse, uniaxial_response, update_with_tangent

__all__ = [
    "METHODS",
    "Bilinear",
    "CowperSymonds",
    "ElasticPerfectlyPlastic",
    "GilmanJohnston",
    "HereditaryLaw",
    "HereditaryState",
    "LinearOverstress",
    "LogOverstress",
    "OverstressLaw",
    "OverstressState",
    "PlasticState",
    "QuadraticOverstress",
    "RateIndependentPlasticity",
    "SinhOverstress",
    "StaticCurve",
    "StrainDependentOverstress",
    "Tabulated",
    "UniaxialResponse",
    "constant_stress_delay_time",
    "delay_rate",
    "delay_time",
    "delay_time_of",
    "grain_diameter",
    "uniaxial_response",
    "update_with_tangent",
    "upper_yield_stress",
]
