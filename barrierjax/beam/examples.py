"""The cantilever examples of report 4.3 (Bodner and Symonds's tests, and one without a tip mass).

A cantilever, clamped at its root, carries a tip mass and is struck at the tip by a transverse
rectangular force pulse (force = impulse / duration over the duration). The material is the
Cowper-Symonds law (4.3.1), eps_p' = D <|sigma|/sigma0 - 1>^q, D = 40 1/s, q = 5, or, with
`rate_dependent=False`, elastic-perfectly plastic at the static yield stress (radial return).
Units: inch, pound force, second.

Schemes (`scheme`):
- "damped-newmark" (default): Newmark gamma = 0.6, beta = 0.3025, unconditionally stable with a
  little high-frequency dissipation (damping ratio about (gamma - 1/2) omega dt / 2, 0.3 % for
  Example 1's first mode at 1e-4 s). Average acceleration (beta = 1/4) is stable for linear
  problems only: with the co-rotational beam at the report's steps its energy grows and Newton
  fails (measured: Example 1 elastic at 1e-3 s blows up after about 10 steps);
- "newmark": average acceleration;
- "report": the report's linear acceleration with its alpha scheme for the fibres (4.2.8)-
  (4.2.45). It is unstable at the report's steps (the stable step of the axial modes of 1 in
  steel elements is a few microseconds; see `integrate.stable_step`) and returns NaN there;
  it is kept to show that (docs/errata.md, 4.2.41).
For the implicit schemes the report's steps are divided into `substeps` equal sub-steps
(default: the fewest giving sub-steps <= 1e-4 s for Example 1, <= 2.5e-5 s for Examples 2 and
3, measured: Example 2 diverges at 8.25e-5 s, Example 3 leaves a step unconverged at 1e-4 s),
which Newton needs to converge on the viscoplastic hinge (see `integrate.integrate`), on
a finer mesh scaled by the square of the element length (see `_scheme_substeps`); the
history keeps the report's steps. `CantileverResult.residual` holds Newton's residual of
every step: check it when you choose `dt` or `substeps` yourself.

Default end times, from a rigid-plastic estimate (the tip mass's kinetic energy
I^2 / (2 m) absorbed at the root's plastic moment M0 = sigma0 B H^2 / 4 at the tip speed
I / m): Example 1 rotates about 0.85 rad in about 2 theta L / v = 90 ms; the computed tip
comes to rest at 72 ms under (4.3.1), at 99 ms rate-independent (101 ms on 28 elements):
t_end = 0.12 s. Example 2: about 1 rad in 13 ms: t_end = 0.02 s.
Example 3 (no tip mass) stays nearly elastic (kinetic energy ~7 in lb against M0 = 146 in lb);
its first elastic period is 34 ms: t_end = 0.03 s covers the first maximum and the return.
"""

import math
from typing import NamedTuple

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from ..compilation_cache import stored_program
from ..materials.overstress import CowperSymonds
from ..materials.plasticity import RateIndependentPlasticity
from .integrate import SCHEME_PARAMETERS, BeamHistory, integrate, step_sizes
from .layered import rectangular_section
from .model import cantilever

# Report 4.3, lines 3300-3370: L, H, B (in), E, sigma0 (psi), rho (lb s^2/in^4), tip mass
# (lb s^2/in), impulse (lb s), duration (s), increments in the pulse, dt after it (s),
# elements; and the default end time (s, see the module docstring). Examples 1 and 3 strike
# the same beam (L to rho): Example 3 is Example 1's cantilever without the tip mass.
_BEAM_1_AND_3 = {"L": 14.0, "H": 0.177, "B": 0.644, "E": 30e6, "sigma0": 29000.0, "rho": 0.000736}
EXAMPLES = {
    1: {
        **_BEAM_1_AND_3,
        "tip_mass": 0.00381,
        "impulse": 0.975,
        "duration": 0.001,
        "pulse_steps": 10,
        "dt": 0.001,
        "n_elements": 14,
        "t_end": 0.12,
        "max_substep": 1e-4,
    },
    2: {
        "L": 4.34,
        "H": 0.053,
        "B": 0.312,
        "E": 30e6,
        "sigma0": 44000.0,
        "rho": 0.000736,
        "tip_mass": 0.000030,
        "impulse": 0.031,
        "duration": 0.0001,
        "pulse_steps": 10,
        "dt": 0.0002475,
        "n_elements": 10,
        "t_end": 0.02,
        "max_substep": 2.5e-5,
    },
    3: {
        **_BEAM_1_AND_3,
        "tip_mass": 0.0,
        "impulse": 0.075,
        "duration": 0.001,
        "pulse_steps": 10,
        "dt": 0.0001,
        "n_elements": 14,
        "t_end": 0.03,
        "max_substep": 2.5e-5,
    },
}
D_COWPER_SYMONDS = 40.0  # 1/s, (4.3.1)
Q_COWPER_SYMONDS = 5.0


def plastic_moment(n, sigma0=None):
    """The static plastic moment sigma0 B H^2 / 4 (lb in) of Example `n`'s section."""
    data = EXAMPLES[n]
    return (data["sigma0"] if sigma0 is None else sigma0) * data["B"] * data["H"] ** 2 / 4


class CantileverResult(eqx.Module):
    """One row per saved time (the report's steps; the initial state first)."""

    times: jnp.ndarray  # (n,)
    tip_displacement: jnp.ndarray  # (n, 2): axial (along the beam), transverse
    tip_rotation: jnp.ndarray  # (n,)
    tip_velocity: jnp.ndarray  # (n, 2): axial, transverse
    node_coordinates: jnp.ndarray  # (n, n_nodes, 2): deformed shapes
    root_moment: jnp.ndarray  # (n,) at the clamped end
    root_axial_force: jnp.ndarray  # (n,)
    root_curvature: jnp.ndarray  # (n,)
    root_plastic_strain: jnp.ndarray  # (n, n_fibres) through the depth at the root
    root_rotation: jnp.ndarray  # (n,) rotation of the first element's chord
    residual: jnp.ndarray  # (n,) Newton's relative residual, largest over the sub-steps
    history: BeamHistory


def _example_data(n):
    """`EXAMPLES[n]`, the report's data of Example `n`; a ValueError for any other `n`."""
    if n not in EXAMPLES:
        raise ValueError(f"n must be one of {tuple(EXAMPLES)}; got {n!r}")
    return EXAMPLES[n]


def example_model(
    n,
    *,
    rate_dependent=True,
    n_elements=None,
    sigma0=None,
    tip_mass=None,
    impulse=None,
    D=D_COWPER_SYMONDS,
    q=Q_COWPER_SYMONDS,
    points=9,
):
    """The `BeamModel` of the report's Example `n`; `sigma0`, `tip_mass`, `impulse`, `D`, `q`
    override the report's data (and may be traced: jit, grad, vmap)."""
    data = _example_data(n)
    sigma0 = data["sigma0"] if sigma0 is None else sigma0
    tip_mass = data["tip_mass"] if tip_mass is None else tip_mass
    impulse = data["impulse"] if impulse is None else impulse
    n_elements = data["n_elements"] if n_elements is None else int(n_elements)
    if rate_dependent:
        law = CowperSymonds(data["E"], sigma0, D, q)
    else:
        law = RateIndependentPlasticity(data["E"], sigma0)
    section = rectangular_section(data["B"], data["H"], law, points=points)
    return cantilever(
        data["L"],
        n_elements,
        section,
        data["rho"],
        tip_mass=tip_mass,
        tip_impulse=impulse,
        duration=data["duration"],
    )


def _scheme_substeps(scheme, dt, substeps, data, n_elements):
    """The stated `substeps`, else 1 for the report's scheme, else the fewest sub-steps no
    longer than the example's `max_substep` scaled by the square of the element length
    against the report's mesh (like the elements' bending periods): Newton fails at the
    report's mesh's sub-step on a finer mesh (measured, rate-independent: Example 2 on 14
    and 20 elements, Example 1 on 28 elements with 6 iterations)."""
    if substeps is not None:
        return int(substeps)
    if scheme == "report":
        return 1
    n_elements = data["n_elements"] if n_elements is None else int(n_elements)
    max_substep = data["max_substep"] * min(1.0, (data["n_elements"] / n_elements) ** 2)
    return max(1, math.ceil(dt / max_substep - 1e-9))


def cantilever_result(model, history):
    """Tip and root histories of a cantilever clamped at node 0 along +X."""
    u = history.displacement
    coords = model.coords[None] + u.reshape(u.shape[0], -1, 3)[:, :, :2]
    chord = coords[:, 1] - coords[:, 0]
    plastic = history.plastic_strain
    return CantileverResult(
        times=history.times,
        tip_displacement=u[:, -3:-1],
        tip_rotation=u[:, -1],
        tip_velocity=history.velocity[:, -3:-1],
        node_coordinates=coords,
        root_moment=history.M[:, 0, 0],
        root_axial_force=history.N[:, 0, 0],
        root_curvature=history.strains[:, 0, 0, 1],
        root_plastic_strain=plastic[:, 0, 0] if plastic is not None else jnp.zeros_like(u[:, :0]),
        root_rotation=jnp.arctan2(chord[:, 1], chord[:, 0]),
        residual=history.residual,
        history=history,
    )


def report_example(
    n,
    *,
    rate_dependent=True,
    scheme="damped-newmark",
    dt=None,
    t_end=None,
    n_elements=None,
    substeps=None,
    iterations=6,
    pulse_steps=None,
    **overrides,
):
    """Example `n` (1, 2 or 3) of report 4.3 with its stated data.

    rate_dependent: Cowper-Symonds (4.3.1), else elastic-perfectly plastic at sigma0.
    scheme: "damped-newmark" (default), "newmark" or "report" (see the module docstring).
    dt: the step after the pulse (default the report's); the pulse takes `pulse_steps`
    (default the report's 10) equal steps. t_end: default as in the module docstring.
    n_elements: default the report's (14, 10, 14). substeps: sub-steps per step (default:
    see the module docstring; 1 for "report"). `overrides` (sigma0,
    tip_mass, impulse, D, q, points) go to `example_model`. Returns a `CantileverResult`."""
    data = _example_data(n)
    if scheme not in SCHEME_PARAMETERS:
        raise ValueError(f"scheme must be one of {tuple(SCHEME_PARAMETERS)}; got {scheme!r}")
    dt = data["dt"] if dt is None else dt
    t_end = data["t_end"] if t_end is None else t_end
    pulse_steps = data["pulse_steps"] if pulse_steps is None else pulse_steps
    model = example_model(n, rate_dependent=rate_dependent, n_elements=n_elements, **overrides)
    dts = step_sizes(t_end, dt, pulse=min(data["duration"], float(t_end)), pulse_steps=pulse_steps)
    history = _run(
        model,
        dts=tuple(float(d) for d in dts),
        scheme=scheme,
        substeps=_scheme_substeps(scheme, float(dt), substeps, data, n_elements),
        iterations=int(iterations),
    )
    return cantilever_result(model, history)


@stored_program
@eqx.filter_jit
def _run(model, *, dts, scheme, substeps, iterations):
    """The run. Its steps `dts` (a tuple) are constants of the program, checked as it is
    traced: the program then holds no run-time check (a host callback, which neither JAX's
    persistent cache nor `stored_program` keeps), and a later process loads it."""
    return integrate(
        model, np.asarray(dts), scheme=scheme, substeps=substeps, iterations=iterations
    )


class TipRest(NamedTuple):
    """The tip at rest at its largest transverse deflection (the report's "final
    configuration corresponding to zero velocity of the tip"): where the transverse velocity
    crosses zero at the largest saved deflection, linearly interpolated between the saved
    times `index - 1` and `index`; all nan (index -1) if the deflection still grows at the
    end of the run."""

    time: float
    index: int
    tip_displacement: np.ndarray  # (2,) axial, transverse
    root_rotation: float


def tip_rest(result) -> TipRest:
    """The tip's rest at its largest deflection in `result` (a `CantileverResult`), as numpy."""
    velocity = np.asarray(result.tip_velocity[:, 1])
    peak = int(np.argmax(np.asarray(result.tip_displacement[:, 1])))
    if peak == len(velocity) - 1 or peak == 0:
        return TipRest(math.nan, -1, np.full(2, math.nan), math.nan)
    k = peak + 1 if velocity[peak] > 0 else peak
    v0, v1 = velocity[k - 1], velocity[k]
    s = v0 / (v0 - v1) if v0 != v1 else 1.0

    def at(values):
        values = np.asarray(values)
        return values[k - 1] + s * (values[k] - values[k - 1])

    return TipRest(
        float(at(result.times)),
        k,
        at(result.tip_displacement),
        float(at(result.root_rotation)),
    )


def final_state(result):
    """(final tip displacement (2,), final tip rotation, final root rotation) as numpy."""
    return (
        np.asarray(result.tip_displacement[-1]),
        float(result.tip_rotation[-1]),
        float(result.root_rotation[-1]),
    )
