"""Constitutive laws of dynamic plasticity (report chapter 2).

Uniaxial laws, each an `equinox.Module` of its parameters with `init_state()` and the
per-step update `law.update(stress, state, d_strain, dt) -> (stress, state)`
(`update_with_tangent` adds the consistent tangent); `uniaxial_response` gives the stress
history for a prescribed strain history by backward Euler, the report's scheme
(4.2.8)-(4.2.11), forward Euler or a stiff diffrax solver. Delayed yield (2.3):
`delay_time`, `upper_yield_stress`. Multiaxial (3x3 tensors), in their modules: `j2`
(Prandtl-Reuss radial return with isotropic and kinematic hardening, consistent tangent),
`perzyna` (the viscoplastic forms (2.2.9)-(2.2.13), backward Euler), `shear_waves` (the
combined shear waves of a half-space (2.1.10)).
"""

from . import j2, perzyna, shear_waves
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
    "j2",
    "perzyna",
    "shear_waves",
    "uniaxial_response",
    "update_with_tangent",
    "upper_yield_stress",
]
