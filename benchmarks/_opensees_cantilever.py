"""The report's Example 1 (4.3, the Bodner-Symonds cantilever with a tip mass) in OpenSees,
rate-independent: the reference that users would reach for, for the beam element of 4.2.

A module of the benchmarks (no command line of its own); openseespy is imported lazily
(`pip install barrierjax[opensees]`; on Linux it needs libblas3 and liblapack3).

The model: 2-D, the root clamped at x = 0, the tip at x = L, the impulse transverse (+y).
Displacement-based beam-column elements (`dispBeamColumn`) with a fibre section of
elastic-perfectly plastic fibres (`ElasticPP`, yield strain sigma0/E), the corotational
transformation (large rotations), consistent mass (`-cMass`, rho A per unit length) and the
tip mass as a nodal mass (translations only), Newmark's average acceleration
(gamma = 1/2, beta = 1/4), full Newton iterations to a displacement-increment norm, a
constant dt. The impulse is a rectangular force on the tip; its duration is rounded to a
whole number of steps and the force scaled so that the discrete impulse (the trapezoidal
rule of the average-acceleration scheme) is exactly I.

Example 1 (report lines 3300-3326): L = 14.0 in, H = 0.177 in, B = 0.644 in,
E = 30e6 psi, sigma0 = 29,000 psi, rho = 0.000736 lb s^2/in^4, tip mass 0.00381 lb s^2/in,
impulse 0.975 lb s over 0.001 s, 14 elements. The report's own law is viscoplastic
(4.3.1); this reference is rate-independent, to be compared with the rate-independent limit
of barrierjax's element and with Parkes (`barrierjax.beam.parkes`).
"""

import time
from typing import NamedTuple

import numpy as np

EXAMPLE_1 = {
    "length": 14.0,
    "height": 0.177,
    "width": 0.644,
    "E": 30e6,
    "sigma0": 29_000.0,
    "rho": 0.000736,
    "tip_mass": 0.00381,
    "impulse": 0.975,
    "pulse_duration": 0.001,
}


class OpenSeesRun(NamedTuple):
    """`times` (s, from 0), the tip's `axial` and `transverse` displacement (in) and
    `transverse_velocity` (in/s) at each step; `rest_time` and `rest_deflection`: the
    first time after the pulse at which the transverse tip velocity comes back to zero
    (linear interpolation between steps; nan if it never does) and the transverse and
    axial tip displacement then (`rest_axial`); `permanent_deflection`: the midpoint of
    the first elastic swing after that rest, (first maximum + next minimum) / 2, the
    permanent set if the swing is elastic (nan if the run ends before the minimum);
    `build_seconds` (model building) and
    `analysis_seconds` (the time stepping, including the per-step Python calls that read
    the tip state); `converged` (false if a step failed, the history then stops there);
    `parameters`: the data and the settings."""

    times: np.ndarray
    axial: np.ndarray
    transverse: np.ndarray
    transverse_velocity: np.ndarray
    rest_time: float
    rest_deflection: float
    rest_axial: float
    permanent_deflection: float
    build_seconds: float
    analysis_seconds: float
    converged: bool
    parameters: dict


def import_opensees():
    try:
        import openseespy.opensees as ops
    except Exception as error:  # ImportError, or RuntimeError on a missing BLAS
        raise ImportError(
            "the OpenSees reference needs openseespy: pip install 'barrierjax[opensees]' "
            f"(and libblas3, liblapack3 on Linux); {error}"
        ) from error
    return ops


def _retry(ops, dt, fallbacks) -> bool:
    """Redo a failed step with each fallback algorithm in turn; Newton again after."""
    ok = False
    for name in fallbacks:
        ops.algorithm(name)
        if ops.analyze(1, dt) == 0:
            ok = True
            break
    ops.algorithm("Newton")
    return ok


def _build(ops, p, *, n_elements, n_fibres, n_integration_points, integration):
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    L, H, B = p["length"], p["height"], p["width"]
    for i in range(n_elements + 1):
        ops.node(i + 1, L * i / n_elements, 0.0)
    ops.fix(1, 1, 1, 1)
    tip = n_elements + 1
    ops.mass(tip, p["tip_mass"], p["tip_mass"], 0.0)
    ops.uniaxialMaterial("ElasticPP", 1, p["E"], p["sigma0"] / p["E"])
    ops.section("Fiber", 1)
    # local y is the bending direction in 2-D: n_fibres layers through the depth
    ops.patch("rect", 1, n_fibres, 1, -H / 2, -B / 2, H / 2, B / 2)
    ops.beamIntegration(integration, 1, 1, n_integration_points)
    ops.geomTransf("Corotational", 1)
    mass_per_length = p["rho"] * B * H
    for e in range(n_elements):
        ops.element("dispBeamColumn", e + 1, e + 1, e + 2, 1, 1, "-cMass", "-mass", mass_per_length)
    return tip


def run_example_1(
    dt=1e-5,
    t_end=0.12,
    n_elements=14,
    n_fibres=20,
    n_integration_points=3,
    *,
    integration="Lobatto",
    tolerance=1e-10,
    max_iterations=50,
    stop_at_rest=False,
    fallbacks=("NewtonLineSearch", "KrylovNewton"),
    **overrides,
) -> OpenSeesRun:
    """Run Example 1 in OpenSees (see the module docstring) and return an `OpenSeesRun`.

    `dt`: the time step (s); `t_end`: the end of the run (s; the rigid-plastic motion
    stops at I L / M0 = 0.093 s); `n_elements`, `n_fibres` (layers through the depth),
    `n_integration_points` and `integration` (an OpenSees beamIntegration name) set the
    mesh and the section; `tolerance` and `max_iterations` Newton's NormDispIncr test;
    `stop_at_rest`: stop at the first rest of the tip; `fallbacks`: the OpenSees
    algorithms tried, in turn, on a step where Newton fails (Newton again on the next
    step; `parameters["retried_steps"]` counts them); `overrides`: any of `EXAMPLE_1`'s
    entries (e.g. E=30e9 for a stiffer beam)."""
    ops = import_opensees()
    unknown = set(overrides) - set(EXAMPLE_1)
    if unknown:
        raise ValueError(f"unknown Example 1 data: {sorted(unknown)}")
    p = {**EXAMPLE_1, **overrides}
    start = time.perf_counter()
    tip = _build(
        ops,
        p,
        n_elements=n_elements,
        n_fibres=n_fibres,
        n_integration_points=n_integration_points,
        integration=integration,
    )
    pulse_steps = max(1, round(p["pulse_duration"] / dt))
    force = p["impulse"] / (pulse_steps * dt)
    # factor 1 at the steps t = dt .. pulse_steps dt, 0 after (t = 0 is the initial state)
    ops.timeSeries("Rectangular", 1, 0.0, (pulse_steps + 0.5) * dt)
    ops.pattern("Plain", 1, 1)
    ops.load(tip, 0.0, force, 0.0)
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("BandGeneral")
    ops.test("NormDispIncr", tolerance, max_iterations)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")
    build_seconds = time.perf_counter() - start

    n_steps = round(t_end / dt)
    times = np.zeros(n_steps + 1)
    axial = np.zeros(n_steps + 1)
    transverse = np.zeros(n_steps + 1)
    velocity = np.zeros(n_steps + 1)
    converged = True
    retried = 0
    last = n_steps
    start = time.perf_counter()
    for k in range(1, n_steps + 1):
        if ops.analyze(1, dt) != 0:
            if not _retry(ops, dt, fallbacks):
                converged, last = False, k - 1
                break
            retried += 1
        times[k] = k * dt
        axial[k] = ops.nodeDisp(tip, 1)
        transverse[k] = ops.nodeDisp(tip, 2)
        velocity[k] = ops.nodeVel(tip, 2)
        if stop_at_rest and k > pulse_steps and velocity[k] <= 0.0:
            last = k
            break
    analysis_seconds = time.perf_counter() - start
    ops.wipe()
    times, axial, transverse, velocity = (
        a[: last + 1] for a in (times, axial, transverse, velocity)
    )

    rest_time = rest_deflection = rest_axial = permanent = float("nan")
    after = np.nonzero((np.arange(len(times)) > pulse_steps) & (velocity <= 0.0))[0]
    if len(after):
        k = after[0]
        v0, v1 = velocity[k - 1], velocity[k]
        s = v0 / (v0 - v1) if v0 != v1 else 1.0
        rest_time = float(times[k - 1] + s * dt)
        rest_deflection = float(transverse[k - 1] + s * (transverse[k] - transverse[k - 1]))
        rest_axial = float(axial[k - 1] + s * (axial[k] - axial[k - 1]))
        back = np.nonzero((np.arange(len(times)) > k) & (velocity > 0.0))[0]
        if len(back):
            permanent = float((np.max(transverse[k - 1 :]) + np.min(transverse[k : back[0]])) / 2)
    return OpenSeesRun(
        times=times,
        axial=axial,
        transverse=transverse,
        transverse_velocity=velocity,
        rest_time=rest_time,
        rest_deflection=rest_deflection,
        rest_axial=rest_axial,
        permanent_deflection=permanent,
        build_seconds=build_seconds,
        analysis_seconds=analysis_seconds,
        converged=converged,
        parameters=dict(
            p,
            dt=dt,
            t_end=t_end,
            n_elements=n_elements,
            n_fibres=n_fibres,
            n_integration_points=n_integration_points,
            integration=integration,
            tolerance=tolerance,
            pulse_steps=pulse_steps,
            pulse_force=force,
            retried_steps=retried,
        ),
    )


def parkes_estimate(**overrides) -> dict:
    """Parkes's rigid-plastic answer for Example 1's data (M0 = sigma0 B H^2 / 4,
    m = rho B H, V0 = I / M), for the impulse and for the rectangular pulse."""
    import jax

    from barrierjax.beam.parkes import parkes_cantilever

    jax.config.update("jax_enable_x64", True)  # as every benchmark script does
    p = {**EXAMPLE_1, **overrides}
    kwargs = {
        "plastic_moment": p["sigma0"] * p["width"] * p["height"] ** 2 / 4,
        "mass_per_length": p["rho"] * p["width"] * p["height"],
        "length": p["length"],
    }
    speed = p["impulse"] / p["tip_mass"]
    out = {}
    for name, tau in (("impulse", 0.0), ("pulse", p["pulse_duration"])):
        r = parkes_cantilever(p["tip_mass"], speed, pulse_duration=tau, **kwargs)
        out[name] = {
            "tip_deflection": float(r.tip_deflection),
            "root_rotation": float(r.root_rotation),
            "end_time": float(r.end_time),
            "root_time": float(r.root_time),
        }
    return out
