"""Assembly of a plane beam structure from the element of `barrierjax.beam.element`
(report 4.2 (iii), the direct stiffness assembly (4.2.39)).

A `BeamModel` holds any layout of nodes and two-node elements, the boundary conditions (fixed
degrees of freedom), concentrated masses and rotary inertias at nodes, and rectangular nodal
load pulses. Node i owns the degrees of freedom 3 i + (0, 1, 2) = (u, w, theta). All arrays have
static sizes; the layout (connectivity, fixed dofs, loaded dofs, quadrature) is static, the
physical data are leaves, so a model jits, vmaps over its leaves and differentiates.

All elements share one layered section (and its law) and one density. Loads enter the time
integration as their average over each step (exact impulse for any step; see
`barrierjax.beam.integrate`).
"""

import functools
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import non_negative, positive
from .element import QUADRATURES, element_mass, element_response, length_points
from .layered import SCHEMES


class BeamModel(eqx.Module):
    coords: jnp.ndarray  # (n_nodes, 2) initial positions
    section: Any  # LayeredSection
    rho: jnp.ndarray  # mass per unit volume
    point_mass: jnp.ndarray  # (n_nodes,)
    point_inertia: jnp.ndarray  # (n_nodes,)
    load_force: jnp.ndarray  # (n_loads,) force (or moment) during each pulse
    load_start: jnp.ndarray  # (n_loads,)
    load_duration: jnp.ndarray  # (n_loads,)
    connectivity: tuple = eqx.field(static=True)  # ((i, j), ...)
    fixed: tuple = eqx.field(static=True)  # bool per dof
    load_dofs: tuple = eqx.field(static=True)  # dof index per load
    quadrature: str = eqx.field(static=True)
    shallow: bool = eqx.field(static=True)

    @property
    def n_nodes(self):
        return self.coords.shape[0]

    @property
    def n_dofs(self):
        return 3 * self.coords.shape[0]

    @property
    def n_points(self):
        return len(length_points(self.quadrature)[0])

    def element_dofs(self):
        c = np.asarray(self.connectivity, dtype=int).reshape(-1, 2)
        return np.concatenate([3 * c[:, :1] + np.arange(3), 3 * c[:, 1:] + np.arange(3)], 1)

    def free(self):
        return ~np.asarray(self.fixed, dtype=bool)


def beam_model(
    coords,
    connectivity,
    section,
    rho,
    *,
    fixed=(),
    point_mass=None,
    point_inertia=None,
    loads=(),
    quadrature="lobatto3",
    shallow=True,
):
    """Build a `BeamModel`.

    coords: (n_nodes, 2); connectivity: pairs of node indices; fixed: dof indices held at
    zero (3 i + 0/1/2 for u/w/theta of node i: a clamped node fixes all three, a pin the first
    two); point_mass, point_inertia: per node (default 0); loads: tuples (dof, impulse,
    duration[, start]) of rectangular pulses of force impulse/duration on [start,
    start + duration) (a moment on a rotation dof); quadrature: "gauss2", "gauss3" or
    "lobatto3" along each element (Lobatto samples the element ends, where a cantilever's
    moment peaks)."""
    coords = jnp.asarray(coords)
    if coords.ndim != 2 or coords.shape[1] != 2 or coords.shape[0] < 2:
        raise ValueError(f"coords must have shape (n_nodes >= 2, 2); got {coords.shape}")
    n = coords.shape[0]
    conn = tuple((int(i), int(j)) for i, j in connectivity)
    if len(conn) == 0 or any(not (0 <= i < n and 0 <= j < n and i != j) for i, j in conn):
        raise ValueError(f"connectivity must be pairs of distinct node indices < {n}; got {conn}")
    traced = isinstance(coords, jax.core.Tracer)
    lengths = None if traced else np.linalg.norm([coords[j] - coords[i] for i, j in conn], axis=1)
    if not traced and not np.all(lengths > 0):
        raise ValueError(f"connectivity must join nodes at distinct positions; got {conn}")
    fixed_set = {int(d) for d in fixed}
    if any(not 0 <= d < 3 * n for d in fixed_set):
        raise ValueError(f"fixed must be dof indices in [0, {3 * n}); got {sorted(fixed_set)}")
    if quadrature not in QUADRATURES:
        raise ValueError(f"quadrature must be one of {QUADRATURES}; got {quadrature!r}")
    dtype = coords.dtype
    zeros = jnp.zeros(n, dtype)
    point_mass = zeros if point_mass is None else non_negative("point_mass", point_mass)
    point_inertia = zeros if point_inertia is None else non_negative("point_inertia", point_inertia)
    point_mass = jnp.broadcast_to(point_mass, (n,))
    point_inertia = jnp.broadcast_to(point_inertia, (n,))
    dofs, force, start, duration = [], [], [], []
    for load in loads:
        dof, impulse, dur = load[:3]
        begin = load[3] if len(load) > 3 else 0.0
        if not 0 <= int(dof) < 3 * n or int(dof) in fixed_set:
            raise ValueError(f"load dof must be a free dof index in [0, {3 * n}); got {dof!r}")
        dur = positive("duration", dur)
        dofs.append(int(dof))
        force.append(jnp.asarray(impulse, dtype) / dur)
        start.append(non_negative("start", begin))
        duration.append(dur)
    stack = (lambda xs: jnp.stack(xs).astype(dtype)) if loads else (lambda xs: jnp.zeros(0, dtype))
    return BeamModel(
        coords=coords,
        section=section,
        rho=positive("rho", rho),
        point_mass=point_mass,
        point_inertia=point_inertia,
        load_force=stack(force),
        load_start=stack(start),
        load_duration=stack(duration),
        connectivity=conn,
        fixed=tuple(d in fixed_set for d in range(3 * n)),
        load_dofs=tuple(dofs),
        quadrature=quadrature,
        shallow=bool(shallow),
    )


def cantilever(
    length,
    n_elements,
    section,
    rho,
    *,
    tip_mass=0.0,
    tip_inertia=0.0,
    tip_impulse=None,
    duration=None,
    angle=0.0,
    quadrature="lobatto3",
):
    """A cantilever clamped at node 0 along the direction `angle` (rad), `n_elements` equal
    elements, a concentrated mass and rotary inertia at the tip, and (optional) a transverse
    rectangular tip force pulse of `tip_impulse` over `duration` (perpendicular to the beam,
    positive to its left)."""
    length = positive("length", length)
    n_elements = int(n_elements)
    if n_elements < 1:
        raise ValueError(f"n_elements must be a positive integer; got {n_elements!r}")
    s = jnp.linspace(0.0, 1.0, n_elements + 1, dtype=length.dtype) * length
    angle_in = angle
    angle = jnp.asarray(angle, length.dtype)
    coords = jnp.stack([s * jnp.cos(angle), s * jnp.sin(angle)], axis=-1)
    n = n_elements + 1
    masses = jnp.zeros(n, length.dtype).at[-1].set(non_negative("tip_mass", tip_mass))
    inertias = jnp.zeros(n, length.dtype).at[-1].set(non_negative("tip_inertia", tip_inertia))
    loads = ()
    if tip_impulse is not None:
        if isinstance(angle_in, jax.core.Tracer) or float(np.cos(float(angle_in))) != 1.0:
            raise ValueError("angle must be 0 for a tip pulse (loads are along global dofs)")
        loads = ((3 * n_elements + 1, tip_impulse, duration),)
    return beam_model(
        coords,
        [(i, i + 1) for i in range(n_elements)],
        section,
        rho,
        fixed=(0, 1, 2),
        point_mass=masses,
        point_inertia=inertias,
        loads=loads,
        quadrature=quadrature,
    )


def load_average(model, t0, t1):
    """The nodal load vector averaged over [t0, t1] (exact impulse of the pulses)."""
    dtype = model.coords.dtype
    f = jnp.zeros(model.n_dofs, dtype)
    if not model.load_dofs:
        return f
    end = model.load_start + model.load_duration
    overlap = jnp.clip(jnp.minimum(end, t1) - jnp.maximum(model.load_start, t0), 0, None)
    return f.at[jnp.asarray(model.load_dofs)].add(model.load_force * overlap / (t1 - t0))


def load_at(model, t):
    """The nodal load vector at time t (right-continuous pulses)."""
    f = jnp.zeros(model.n_dofs, model.coords.dtype)
    if not model.load_dofs:
        return f
    on = (t >= model.load_start) & (t < model.load_start + model.load_duration)
    return f.at[jnp.asarray(model.load_dofs)].add(jnp.where(on, model.load_force, 0.0))


def init_sections(model):
    """Unstressed fibres of every element and point: leaves of shape (n_el, n_pts, n_fib)."""
    stress, state = model.section.init()
    shape = (len(model.connectivity), model.n_points)
    grow = lambda x: jnp.broadcast_to(x, shape + x.shape)
    return grow(stress), jax.tree.map(grow, state)


def _elements(model, dt, scheme, iterations):
    """Each element's dofs and end coordinates, and its response (forces, stepped
    sections) as a function of them, its displacements at both times and its sections."""
    idx = model.element_dofs()
    conn = np.asarray(model.connectivity).reshape(-1, 2)
    xi, weights = length_points(model.quadrature)
    response = functools.partial(
        element_response,
        model.section,
        dt=dt,
        xi=xi,
        weights=weights,
        scheme=scheme,
        iterations=iterations,
        shallow=model.shallow,
    )
    return idx, model.coords[conn[:, 0]], model.coords[conn[:, 1]], response


def internal_forces(model, u_new, u_old, stress, state, dt, *, scheme="implicit", iterations=0):
    """Assembled internal forces (n_dofs,) at u_new, the sections stepped from u_old.

    Returns (f, (stress, state, N, M, strains)) with per-element leaves."""
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {SCHEMES}; got {scheme!r}")
    idx, X1, X2, response = _elements(model, dt, scheme, iterations)
    f_el, out = jax.vmap(response)(X1, X2, u_new[idx], u_old[idx], stress, state)
    f = jnp.zeros(model.n_dofs, u_new.dtype).at[idx].add(f_el)
    return f, out


def tangent_stiffness(model, u_new, u_old, stress, state, dt, *, scheme="implicit", iterations=0):
    """Assembled tangent stiffness [K1] + [K2] (4.2.36)-(4.2.37) at u_new: the consistent
    material tangent and the co-rotational geometric stiffness (`element._stiffness`).
    Returns (K, f, out)."""
    idx, X1, X2, response = _elements(model, dt, scheme, iterations)
    response = functools.partial(response, tangent=True)
    f_el, out, k_el = jax.vmap(response)(X1, X2, u_new[idx], u_old[idx], stress, state)
    n = model.n_dofs
    f = jnp.zeros(n, u_new.dtype).at[idx].add(f_el)
    K = jnp.zeros((n, n), u_new.dtype).at[idx[:, :, None], idx[:, None, :]].add(k_el)
    return K, f, out


def mass_matrix(model, u):
    """Assembled consistent mass (4.2.35) in the chord frames at u, with the concentrated
    masses and rotary inertias."""
    idx = model.element_dofs()
    conn = np.asarray(model.connectivity).reshape(-1, 2)
    X1, X2 = model.coords[conn[:, 0]], model.coords[conn[:, 1]]
    A, I = model.section.A, model.section.I
    m_el = jax.vmap(lambda a, b, q: element_mass(model.rho, A, I, a, b, q))(X1, X2, u[idx])
    n = model.n_dofs
    M = jnp.zeros((n, n), u.dtype).at[idx[:, :, None], idx[:, None, :]].add(m_el)
    diag = jnp.stack([model.point_mass, model.point_mass, model.point_inertia], -1).ravel()
    return M + jnp.diag(diag.astype(u.dtype))


@jax.jit
def linear_matrices(model, dt=None):
    """(K, M) of the unstressed, undeformed structure (all dofs; restrict with
    `model.free()`): the elastic stiffness and the consistent mass, e.g. for natural
    frequencies. dt (default 0) is the step of the material update (irrelevant elastically).

    One program per mesh: run op by op, its few hundred operations, each compiled on
    first use, took 7.9 s for a new mesh of a 16-span guardrail (0.8 s compiled whole)."""
    u = jnp.zeros(model.n_dofs, model.coords.dtype)
    stress, state = init_sections(model)
    dt = jnp.zeros((), u.dtype) if dt is None else dt
    K, _, _ = tangent_stiffness(model, u, u, stress, state, dt)
    return K, mass_matrix(model, u)
