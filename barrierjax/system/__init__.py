"""A vehicle redirected by a barrier (BARRIER VII's problem, Powell 1973): a planar vehicle
with a crushable periphery and tyres (`vehicle`), a guardrail of the chapter 4 beam elements
on posts with end anchors, or a rigid wall (`barrier`), their contact (`contact`), and the
impact integrated by explicit central differences (`impact.system_impact`)."""

from .barrier import Guardrail, Posts, RigidWall, guardrail, post_springs, rail_section, stable_step
from .impact import SystemHistory, SystemResult, system_impact
from .static import StaticPushover, static_pushover
from .vehicle import Vehicle, vehicle

__all__ = [
    "Guardrail",
    "Posts",
    "RigidWall",
    "StaticPushover",
    "SystemHistory",
    "SystemResult",
    "Vehicle",
    "guardrail",
    "post_springs",
    "rail_section",
    "stable_step",
    "static_pushover",
    "system_impact",
    "vehicle",
]
