"""A guardrail of `barrierjax.system` rebuilt in OpenSees and driven by a recorded history
of nodal forces: the general-purpose FE code a user would reach for, for the rail and
posts of a barrier-system run (OpenSees has no planar vehicle with a crushable outline, so
the contact forces come from barrierjax's run).

A module of the benchmarks (no command line of its own); openseespy is imported lazily
(`pip install barrierjax[opensees]`).

The same model as `barrierjax.system.barrier`, element for element: 2-D displacement-based
beam-columns (`dispBeamColumn`) with the corotational transformation and 3 Lobatto points,
each point a fibre section of the two flanges (area A/2 at +-sqrt(I/A), elastic-perfectly
plastic `ElasticPP` fibres), no element mass; the nodes' lumped masses and rotary inertias
(`mass`); each post a `zeroLength` element to the ground with an elastic-perfectly plastic
spring in x and in y, the lateral one wrapped in `MinMax` so that it carries nothing once
its displacement passes the failure displacement (barrierjax also drops the post's
longitudinal force then: OpenSees's springs fail one by one, a difference of the
longitudinal post forces only); the anchors elastic `zeroLength` springs. Explicit central
differences (`CentralDifference`, linear algorithm) at barrierjax's step; each node's force
history a `Path` time series at that step. Or Newmark's implicit average acceleration at a
multiple of the step (`newmark_every`), for the choice between the two schemes.
"""

import dataclasses
import time
from typing import NamedTuple

import numpy as np
from _opensees_cantilever import import_opensees


class OpenSeesGuardrailRun(NamedTuple):
    """`lateral`: every node's lateral displacement (m) every `record_every` steps, from
    the start; `post_force`: every post's lateral force (N) then; `build_seconds`,
    `analysis_seconds` (the stepping, with the reads of the records)."""

    lateral: np.ndarray
    post_force: np.ndarray
    build_seconds: float
    analysis_seconds: float


def _guardrail_data(g):
    section = g.rail.section
    law = section.law
    return {
        "x": np.asarray(g.rail.coords)[:, 0],
        "z": np.asarray(section.z),
        "area": np.asarray(section.area),
        "E": float(law.E),
        "sigma0": float(law.sigma0),
        "mass": np.asarray(g.node_mass),
        "inertia": np.asarray(g.rail.point_inertia),
        "posts": list(g.post_nodes),
        "post": {f.name: float(getattr(g.posts, f.name)) for f in dataclasses.fields(g.posts)},
        "anchor": float(g.anchor_stiffness),
    }


def run_guardrail(g, forces, dt, record_every=20, newmark_every=None) -> OpenSeesGuardrailRun:
    """Drive the guardrail `g` (a `barrierjax.system.Guardrail` with a rate-independent
    rail) by `forces` (n_steps, n_nodes, 2): each node's x and y force at each step of dt.

    `newmark_every` = k: Newmark's average acceleration instead (implicit, Newton's
    iterations to a displacement increment of 1e-9 m) at steps of k dt, the forces
    averaged over each k steps (their impulse kept) and placed at the windows' middles;
    `record_every` must then be a multiple of k."""
    k = newmark_every or 1
    if record_every % k:
        raise ValueError(f"record_every ({record_every}) must be a multiple of {k}")
    windows = forces.shape[0] // k
    forces = forces[: windows * k].reshape(windows, k, *forces.shape[1:]).mean(1)
    times = (np.arange(windows) + (0.5 if newmark_every else 0.0)) * k * dt
    ops = import_opensees()
    d = _guardrail_data(g)
    start = time.perf_counter()
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    n = len(d["x"])
    for i, x in enumerate(d["x"]):
        ops.node(i + 1, float(x), 0.0)
        ops.mass(i + 1, float(d["mass"][i]), float(d["mass"][i]), float(d["inertia"][i]))
    ops.uniaxialMaterial("ElasticPP", 1, d["E"], d["sigma0"] / d["E"])
    ops.section("Fiber", 1)
    for z, a in zip(d["z"], d["area"], strict=True):
        ops.fiber(float(z), 0.0, float(a), 1)
    ops.beamIntegration("Lobatto", 1, 1, 3)
    ops.geomTransf("Corotational", 1)
    for e in range(n - 1):
        ops.element("dispBeamColumn", e + 1, e + 1, e + 2, 1, 1)
    p = d["post"]
    ops.uniaxialMaterial("ElasticPP", 2, p["stiffness"], p["strength"] / p["stiffness"])
    ops.uniaxialMaterial("MinMax", 3, 2, "-min", -p["failure"], "-max", p["failure"])
    ops.uniaxialMaterial("ElasticPP", 4, p["longitudinal_stiffness"],
                         p["longitudinal_strength"] / p["longitudinal_stiffness"])  # fmt: skip
    ops.uniaxialMaterial("Elastic", 5, d["anchor"])
    ground = n + 1
    springs = []
    for k, node in enumerate(d["posts"]):
        ops.node(ground + k, float(d["x"][node]), 0.0)
        ops.fix(ground + k, 1, 1, 1)
        ops.element("zeroLength", n + k, ground + k, node + 1, "-mat", 4, 3, "-dir", 1, 2)
        springs.append(n + k)
    for k, node in enumerate((0, n - 1)):
        tag = ground + len(d["posts"]) + k
        ops.node(tag, float(d["x"][node]), 0.0)
        ops.fix(tag, 1, 1, 1)
        ops.element("zeroLength", n + len(d["posts"]) + k, tag, node + 1, "-mat", 5, 5,
                    "-dir", 1, 2)  # fmt: skip
    loaded = np.argwhere(np.any(forces != 0.0, axis=0))  # (node, direction) pairs
    for tag, (node, direction) in enumerate(loaded, start=1):
        values = [float(v) for v in forces[:, node, direction]]
        ops.timeSeries("Path", tag, "-time", *map(float, times), "-values", *values)
        ops.pattern("Plain", tag, tag)
        load = [0.0, 0.0, 0.0]
        load[direction] = 1.0
        ops.load(int(node) + 1, *load)
    ops.constraints("Plain")
    ops.numberer("RCM")
    ops.system("BandGeneral")
    if newmark_every:
        ops.test("NormDispIncr", 1e-9, 50)
        ops.algorithm("Newton")
        ops.integrator("Newmark", 0.5, 0.25)
    else:
        ops.algorithm("Linear")
        ops.integrator("CentralDifference")
    ops.analysis("Transient")
    build = time.perf_counter() - start

    def record():
        lateral = [ops.nodeDisp(i + 1, 2) for i in range(n)]
        post = [ops.eleResponse(tag, "force")[4] for tag in springs]
        return lateral, post

    start = time.perf_counter()
    lateral, post = [], []
    for _ in range(windows * k // record_every):
        a, b = record()
        lateral.append(a)
        post.append(b)
        if ops.analyze(record_every // k, k * dt) != 0:
            raise RuntimeError("OpenSees failed to step the guardrail")
    analysis = time.perf_counter() - start
    return OpenSeesGuardrailRun(np.asarray(lateral), np.asarray(post), build, analysis)
