"""Oblique impact of a rigid-plastic vehicle on a rigid-plastic beam on a rigid-plastic
backing (report section 3.3), and the moving constant load of its accelerative phase.

The model reads top to bottom as the report's section does:

- `mechanism`: the dimensionless variables and the equations of motion (3.3.16), the
  velocity field (3.3.2) and the start at T = 0;
- `memory`: the slope the right hinge leaves behind, (3.3.4)-(3.3.6) and (3.3.21)'s R, as
  a recorded trace rather than a solved delay;
- `phases`: the state machine's stages (crushing, contact, free), their vector field and
  what each step records;
- `transitions`: where each stage ends and what follows it, the step loop built from them,
  and its failures;
- `results`: the results at rest and the histories;
- `api`: `oblique_impact` and `moving_load`.

Phases, all run by one step loop (`barrierjax._solve.recorded_rk`: under `vmap` a loop per
phase would wait, phase by phase, for the batch's slowest member).
1. Crushing (accelerative, in time T): the vehicle crushes at constant force phi; its
   normal velocity U falls at phi/mu. At T = 0, V0 = 0 and S' = g/V0 is 0/0; its limit
   is the antisymmetric mode S1' = -S2' = -3/2 a V_H / (a + 1/2 + phi/S*) with
   a = V0'(0) (linearise the second and third lines about S1 = S2 = S*). The steps start
   at T = 1e-2 rtol^1/2 T_scale from this expansion (`mechanism.start_series`): from
   T = 0 itself no explicit step is stable when phi is near 1. The phase ends where the
   vehicle stops crushing: U = V0 + theta V_H.
2. Contact (decelerative): the vehicle is rigid and follows the contact point, so
   g = -mu d/dT (V0 + theta V_H), which with the first line gives (3.3.22)'s form

       g (1 - f theta + 4 mu / (S1 + S2))
           = mu (S1 S2 + 3) / (2 S1 S2) + mu V_H V0 / S1 - mu V_H^2 Psi'(F),

   f being the friction coefficient. V0 -> 0 at the end, where S' = g_i/V0 is 0/0
   again; the phase is integrated in s, dT/ds = V0, in which every rate is regular, with
   ln V0 as state; it ends at V0 = V0* rtol^1/2 e^-1, and the run-out to rest is added
   in closed form, to second order in that speed (`results.run_out_to_rest`: the
   deceleration held; the hinges meet at rest, on a cubic, `phases.at_rest`).
3. Free (only after separation): where g would fall below zero the vehicle leaves; the
   beam moves on alone (g = 0, the central hinge where the load left it) to rest. The
   report keeps contact to the end; this phase is where the model departs from it.

Derivatives: the contact phase runs in segments between the breakpoints of Psi' (see
`transitions.transition`), so that they match finite differences.

Arrays of scenarios run in lanes refilled from a queue (`barrierjax._solve.queue`): under
a plain `vmap`, every member would step until the slowest is done. The heaviest vehicles
(the longest solves) start first, so that the queue ends on short ones.
"""

from .api import moving_load, oblique_impact
from .results import MovingLoad, ObliqueImpact, ObliqueImpactHistory

__all__ = ["MovingLoad", "ObliqueImpact", "ObliqueImpactHistory", "moving_load", "oblique_impact"]
