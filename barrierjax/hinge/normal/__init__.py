r"""Normal impact of a rigid-plastic vehicle on a rigid-plastic beam on a rigid-plastic backing.

Report section 3.2. A beam of mass m per unit length and plastic moment M0 rests on a
backing that yields at q0 per unit length; a vehicle of mass M that crushes at the force
P0 strikes it at speed v. Dimensionless variables (after 3.2.8; docs/errata.md, 3.3.14):

    length L = 2 (M0/q0)^(1/2),  force P_b = 4 (M0 q0)^(1/2),
    time t0 = m^(1/2) M0^(1/4) / q0^(3/4),  velocity L/t0,  energy P_b L,
    mass ratio mu = M / (m L),  force ratio phi = P0 / P_b.

Equations of motion of the deforming half-beam 0 < x < xi(t), with its velocity field
v = v0 (1 - x/xi) (3.2.1), re-derived from (3.2.3)-(3.2.4) (docs/errata.md, 3.2.8):

    a        = 2P/(m xi) - 12 M0/(m xi^2) - q0/m                    (3.2.7)
    v0 dxi/dt = 12 M0/(m xi) - q0 xi/m - P/m                          (3.2.8, corrected)

Accelerative phase (P = P0, xi fixed): q0 xi^2 + P0 xi - 12 M0 = 0 (docs/errata.md, 3.2.10), so

    S* = (phi^2 + 3)^(1/2) - phi,   V' = (phi - S*)/S*,   vehicle V_v' = -phi/mu,   (3.2.11)-(3.2.12)

until the velocities meet at T* = mu V0 S* / (phi S* + mu (phi - S*)) (3.2.14), with
V* = (phi - S*) T* / S* (3.2.13) and W* = (phi - S*) T*^2 / (2 S*).

Decelerative phase (vehicle and beam move together, P = -M a):

    V'  = -(S^2 + 3) / (2 S (S + 2 mu))                               (3.2.15)
    V S' = -p(S) / (2 S (S + 2 mu)),  p(S) = S^3 + 3 mu S^2 - 3 S - 3 mu     (3.2.16)
         = -(S - alpha)(S + beta)(S + gamma) ...                      (3.2.17)

whose quotient integrates to V(S) (3.2.18)-(3.2.19) and gives T(S) by quadrature
(3.2.20). The motion stops when S reaches alpha, the positive root of p, at T**.

Vehicle damage (crush) is D = V0 T* / 2, so D / V0^2 = T* / (2 V0): the printed closed
form for D / V0^2 lacks this factor 1/2 (docs/errata.md, 3.2 damage).

Energy (in units of P_b L): the vehicle's kinetic energy mu V0^2 / 2 equals the crush
work phi D, the backing work (1/2) integral V S dT, the hinge work (1/2) integral V/S dT
(four hinges dissipate 4 M0 v0/xi) and the beam's kinetic energy V^2 S / 3.

Both methods work in the speed-free variables tau = T/V0, v = V/V0, w = W/V0^2 (the
report's own observation after 3.2.20: for fixed S, T and V are proportional to V0 and
W to V0^2), so the speed only rescales the answer and every member of a batch costs the
same whatever its speed.

The package reads as the section does:

- `phases`: the accelerative phase (3.2.9)-(3.2.14) and the decelerative phase's
  constants (3.2.15)-(3.2.19);
- `closed_form`: `method="closed_form"`, the quadratures of (3.2.18)-(3.2.20);
- `ode`: `method="ode"`, the same phases integrated in time with diffrax;
- `results`: `NormalImpact`, its histories, and the rigid barrier (phi <= 1);
- `api`: `normal_impact`.

With axial force (report 3.4) the model is `barrierjax.hinge.axial_impact`
(`barrierjax/hinge/axial.py`), which returns the same `NormalImpact`.
"""

from .api import normal_impact
from .results import NormalImpact, NormalImpactHistory

__all__ = ["NormalImpact", "NormalImpactHistory", "normal_impact"]
