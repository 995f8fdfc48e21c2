"""The barrier of a system impact: a guardrail (a rail of the chapter 4 beam elements on
posts, with end anchors), or a rigid wall.

The rail runs along x through y = 0 from x = 0 to `length`, posts every `post_spacing`
(the first and last at the rail's ends), `elements_per_span` co-rotational elements of
`barrierjax.beam` between posts, each with its layered section and uniaxial law, so that
the report's rate laws (chapter 2) reach the system. The masses are lumped at the nodes
(explicit time integration: `impact.py`), with a rotary inertia per node of m times the
larger of dx^2 / 12 (the translational mass spread over its element) and 4 I / A: either
keeps the rotational modes below the axial ones, so that the stable step stays the axial
waves' (dx / c) on fine meshes, and adds a negligible kinetic energy (the rail's own is
m I / A).

A post is a pair of springs at its rail node, lateral (y) and longitudinal (x), each
elastic-perfectly plastic; a post whose lateral displacement passes `failure` is gone (it
carries nothing after). An end anchor is a linear spring in x and in y at an end node.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import non_negative, positive
from ..beam.layered import LayeredSection
from ..beam.model import BeamModel, beam_model, linear_matrices
from ..compilation_cache import run_compiled


class Posts(eqx.Module):
    """Every post's springs (SI): lateral stiffness and strength, the lateral displacement at
    which it fails, and longitudinal stiffness and strength."""

    stiffness: jnp.ndarray
    strength: jnp.ndarray
    failure: jnp.ndarray
    longitudinal_stiffness: jnp.ndarray
    longitudinal_strength: jnp.ndarray


def post_springs(
    stiffness, strength, failure, longitudinal_stiffness, longitudinal_strength
) -> Posts:
    """Checked `Posts`."""
    return Posts(
        positive("post stiffness", stiffness),
        positive("post strength", strength),
        positive("post failure", failure),
        positive("post longitudinal_stiffness", longitudinal_stiffness),
        positive("post longitudinal_strength", longitudinal_strength),
    )


class Guardrail(eqx.Module):
    rail: BeamModel  # nodes along x, no dof fixed
    node_mass: jnp.ndarray  # (n_nodes,) lumped translational mass
    posts: Posts
    anchor_stiffness: jnp.ndarray  # each end anchor's, in x and in y
    post_nodes: tuple = eqx.field(static=True)

    @property
    def n_nodes(self):
        return self.rail.n_nodes


class RigidWall(eqx.Module):
    """The line y = 0 from x = `start` to `end`, immovable."""

    start: jnp.ndarray
    end: jnp.ndarray


def rail_section(area, second_moment, law) -> LayeredSection:
    """A two-flange section with the rail's area and second moment of area about the
    vertical axis (its lateral bending): flanges of area A/2 at +-sqrt(I/A). Its plastic
    moment is A sigma0 sqrt(I/A), that of the rail only where the rail's shape factor is
    the two flanges' (1); the plastic axial force A sigma0 is exact."""
    area = positive("rail area", area)
    second_moment = positive("rail second_moment", second_moment)
    half = jnp.sqrt(second_moment / area)
    return LayeredSection(jnp.stack([-half, half]), jnp.stack([area, area]) / 2, law)


def guardrail(
    length,
    post_spacing,
    *,
    section: LayeredSection,
    density,
    posts: Posts,
    anchor_stiffness,
    elements_per_span: int = 8,
) -> Guardrail:
    """A rail of `length` (m) on posts every `post_spacing` (m; `length` must hold a whole
    number of spans, to 1e-6), `elements_per_span` elements between posts. The rail's
    deflection converges slowly with the mesh (the kink the vehicle's corner presses into
    it): on MASH 3-11 with the MGS, 2 / 4 / 8 / 16 / 32 elements per span give 0.90 / 1.07
    / 1.22 / 1.30 / 1.35 m (benchmarks/system_convergence.py); 8 costs twice 4."""
    if not (post_spacing > 0) or not np.isfinite(float(post_spacing)):
        raise ValueError(f"post_spacing must be positive and finite; got {post_spacing!r}")
    spans = float(length) / float(post_spacing)
    if not (length > 0) or abs(spans - round(spans)) > 1e-6 or round(spans) < 1:
        raise ValueError(
            f"length must be a positive whole number of post spacings; got {length!r} "
            f"for post_spacing {post_spacing!r}"
        )
    if int(elements_per_span) != elements_per_span or elements_per_span < 1:
        raise ValueError(f"elements_per_span must be a positive integer; got {elements_per_span!r}")
    n_elements = round(spans) * int(elements_per_span)
    spacing = positive("post_spacing", post_spacing)
    x = jnp.arange(n_elements + 1, dtype=spacing.dtype) * (spacing / elements_per_span)
    coords = jnp.stack([x, jnp.zeros_like(x)], -1)
    density = positive("density", density)
    dx = spacing / elements_per_span
    tributary = jnp.full(n_elements + 1, dx).at[0].set(dx / 2).at[-1].set(dx / 2)
    node_mass = density * section.A * tributary
    rail = beam_model(
        coords,
        [(i, i + 1) for i in range(n_elements)],
        section,
        density,
        point_inertia=node_mass * jnp.maximum(dx**2 / 12, 4 * section.I / section.A),
        quadrature="lobatto3",
        shallow=False,
    )
    # The element's consistent mass is not used: the lumped one is `node_mass`.
    return Guardrail(
        rail=rail,
        node_mass=node_mass,
        posts=posts,
        anchor_stiffness=non_negative("anchor_stiffness", anchor_stiffness),
        post_nodes=tuple(range(0, n_elements + 1, int(elements_per_span))),
    )


def lumped_mass(g: Guardrail):
    """The diagonal mass (3 n_nodes,): m, m, m dx^2 / 12 at each node."""
    return jnp.stack([g.node_mass, g.node_mass, g.rail.point_inertia], -1).ravel()


def stable_step(g: Guardrail, contact_stiffness=0.0, safety=0.8) -> float:
    """The central-difference step `safety` 2 / omega_max, omega_max from the rail's linear
    stiffness (and the posts', the anchors' and `contact_stiffness` on each node's lateral
    dof, a bound on what the vehicle's crush springs add) over the lumped mass (numpy:
    concrete data only)."""
    # Concrete data, even inside a caller's jit: the stiffness's program run on the rail
    # (under `ensure_compile_time_eval` its operations ran one by one, each compiled on
    # first use: 7.9 s for a new mesh, against 0.8 s).
    K = np.asarray(run_compiled(linear_matrices, g.rail)[0])
    with jax.ensure_compile_time_eval():
        mass = np.asarray(lumped_mass(g))
    diagonal = np.zeros(K.shape[0])
    for node in g.post_nodes:
        diagonal[3 * node] += float(g.posts.longitudinal_stiffness)
        diagonal[3 * node + 1] += float(g.posts.stiffness)
    for node in (0, g.n_nodes - 1):
        diagonal[3 * node : 3 * node + 2] += float(g.anchor_stiffness)
    diagonal[1::3] += float(contact_stiffness)
    K = K + np.diag(diagonal)
    scale = 1 / np.sqrt(mass)
    omega_max = np.sqrt(np.max(np.linalg.eigvalsh(scale[:, None] * K * scale[None, :])))
    return float(safety * 2.0 / omega_max)


def post_forces(g: Guardrail, u, plastic, failed):
    """The posts' forces on the rail (3 n_nodes,), their new plastic displacements (n_posts,
    2: lateral, longitudinal) and failures (n_posts,), from the rail's displacements u."""
    nodes = np.asarray(g.post_nodes)
    p = g.posts
    lateral, longitudinal = u[3 * nodes + 1], u[3 * nodes]
    failed = failed | (jnp.abs(lateral) > p.failure)
    stiffness = jnp.stack([p.stiffness, p.longitudinal_stiffness])
    strength = jnp.stack([p.strength, p.longitudinal_strength])
    trial = stiffness * (jnp.stack([lateral, longitudinal], -1) - plastic)
    force = jnp.clip(trial, -strength, strength)
    plastic = plastic + (trial - force) / stiffness
    force = jnp.where(failed[:, None], 0.0, force)
    f = jnp.zeros_like(u).at[3 * nodes + 1].add(force[:, 0]).at[3 * nodes].add(force[:, 1])
    return f, plastic, failed


def anchor_forces(g: Guardrail, u):
    """The end anchors' forces on the rail (3 n_nodes,)."""
    dofs = np.asarray([0, 1, 3 * (g.n_nodes - 1), 3 * (g.n_nodes - 1) + 1])
    return jnp.zeros_like(u).at[dofs].add(g.anchor_stiffness * u[dofs])
