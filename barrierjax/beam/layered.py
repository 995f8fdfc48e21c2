"""Incremental layered beam section, report 4.2 (ii), (4.2.14)-(4.2.19).

Plane sections remain plane (4.2.14)-(4.2.15): the strain increment of the fibre at height z
above the reference axis is

    d_eps(z) = d_eps_m - z d_kappa,

with d_eps_m the axial strain increment of the reference axis and d_kappa the curvature
increment (kappa = w'' of the transverse displacement w, positive sagging). Every fibre
(layer, or quadrature point through the depth) carries a uniaxial law of
`barrierjax.materials` and its own state; the section resultants are the integrals (4.2.16)

    N = int b sigma dz,        M = -int b sigma z dz,

so that M = EI kappa in the elastic range. The report writes M = int b sigma z dz and carries
the sign in its matrix [[EA', -ES'], [ES', -EI']] (4.2.17); here the sign is moved into M so
that the section tangent is symmetric and positive:

    [[EA_t, ES_t], [ES_t, EI_t]] = int b E_t [[1, -z], [-z, z^2]] dz,

with E_t the consistent tangent d sigma / d d_eps of the layer's discrete update. For the
report's scheme (4.2.8)-(4.2.11) E_t = alpha E and the right-hand side -{dN', dM'} of (4.2.17)
is the part of the update that does not depend on d_eps, so both schemes share one interface:
`scheme="report"` steps the layers with `law.report_update` (needs an overstress law),
`scheme="implicit"` with `law.update` (backward Euler, or the return map of a rate-independent
law).

Integration through the depth: `rule="midpoint"` is the report's equal layers (exact for N,
but the elastic EI is short by the factor 1 - 1/n^2); `"gauss"` and `"lobatto"` integrate the
elastic section exactly with 2 points or more; Lobatto samples the outer fibres, where yield
starts. A general section is a stack of rectangular layers of given thickness and width, each
integrated with its own rule, about its elastic centroid.
"""

from typing import Any, NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._checks import positive

RULES = ("midpoint", "gauss", "lobatto")
SCHEMES = ("implicit", "report")


def _unit_rule(rule: str, points: int):
    """Points and weights on [-1/2, 1/2] (weights sum to 1)."""
    if rule not in RULES:
        raise ValueError(f"rule must be one of {RULES}; got {rule!r}")
    points = int(points)
    if rule == "midpoint":
        if points < 1:
            raise ValueError(f"points must be a positive integer; got {points!r}")
        x = (np.arange(points) + 0.5) / points - 0.5
        return x, np.full(points, 1.0 / points)
    if rule == "gauss":
        if points < 1:
            raise ValueError(f"points must be a positive integer; got {points!r}")
        x, w = np.polynomial.legendre.leggauss(points)
        return x / 2, w / 2
    if points < 2:
        raise ValueError(f"points must be at least 2 for the Lobatto rule; got {points!r}")
    # Lobatto: the ends and the roots of P'_{n-1}; weights 2 / (n (n-1) P_{n-1}(x)^2).
    n = points
    p = np.polynomial.legendre.Legendre.basis(n - 1)
    interior = np.sort(np.real(p.deriv().roots())) if n > 2 else np.zeros(0)
    x = np.concatenate([[-1.0], interior, [1.0]])
    w = 2.0 / (n * (n - 1) * p(x) ** 2)
    return x / 2, w / 2


class LayeredSection(eqx.Module):
    """Fibres at heights `z` (from the elastic centroid, upwards) with areas `area`
    (width times quadrature weight times thickness), all of the uniaxial `law`."""

    z: jnp.ndarray
    area: jnp.ndarray
    law: Any

    @property
    def A(self):
        return jnp.sum(self.area)

    @property
    def I(self):
        return jnp.sum(self.area * self.z**2)

    def init(self):
        """Unstressed layers: (stress (n,), state with leaves of shape (n,))."""
        zero = jnp.zeros_like(self.z)
        state = jax.tree.map(lambda x: jnp.broadcast_to(x, self.z.shape), self.law.init_state())
        return zero, state


def layered_section(thicknesses, widths, law, *, points=3, rule="gauss"):
    """A stack of rectangular layers, bottom to top, of the given `thicknesses` and `widths`
    (sequences of equal length), each integrated with `points` of `rule`; heights are measured
    from the elastic centroid of the stack, so that ES = 0 in the elastic range."""
    t = np.atleast_1d(np.asarray(thicknesses, dtype=float))
    b = np.atleast_1d(np.asarray(widths, dtype=float))
    if t.shape != b.shape or t.ndim != 1:
        raise ValueError(
            f"widths must have the shape of thicknesses {t.shape}; got {np.shape(widths)}"
        )
    positive("thicknesses", t)
    positive("widths", b)
    x, w = _unit_rule(rule, points)
    tops = np.cumsum(t)
    mids = tops - t / 2
    centroid = np.sum(b * t * mids) / np.sum(b * t)
    z = ((mids - centroid)[:, None] + t[:, None] * x[None, :]).ravel()
    area = (b[:, None] * t[:, None] * w[None, :]).ravel()
    dtype = jnp.result_type(float)
    return LayeredSection(jnp.asarray(z, dtype), jnp.asarray(area, dtype), law)


def rectangular_section(width, height, law, *, points=9, rule="lobatto"):
    """A rectangle `width` x `height` about its centroid, `points` fibres through the depth.

    `width` and `height` may be traced (jit, grad, vmap): the fibres scale with them."""
    width = positive("width", width)
    height = positive("height", height)
    x, w = _unit_rule(rule, points)
    return LayeredSection(height * jnp.asarray(x, height.dtype), width * height * w, law)


class SectionUpdate(NamedTuple):
    N: jnp.ndarray
    M: jnp.ndarray
    stress: jnp.ndarray
    state: Any
    tangent: jnp.ndarray  # [[EA_t, ES_t], [ES_t, EI_t]]


def _layer_step(law, scheme, iterations):
    if scheme not in SCHEMES:
        raise ValueError(f"scheme must be one of {SCHEMES}; got {scheme!r}")
    if scheme == "implicit":
        return law.update
    if not hasattr(law, "report_update"):
        raise ValueError(
            f"scheme must be 'implicit' for {type(law).__name__} (no report_update); got 'report'"
        )
    return lambda *args: law.report_update(*args, iterations=iterations)


def resultants(section, stress):
    """(N, M) = (int b sigma dz, -int b sigma z dz) (4.2.16)."""
    return jnp.sum(section.area * stress), -jnp.sum(section.area * section.z * stress)


def section_stresses(
    section, stress, state, d_eps_m, d_kappa, dt, *, scheme="implicit", iterations=0
):
    """Layer stresses and states after the increment (4.2.14): d_eps = d_eps_m - z d_kappa."""
    step = _layer_step(section.law, scheme, iterations)
    d_strain = d_eps_m - section.z * d_kappa
    return step(stress, state, d_strain, dt)


def section_update(
    section, stress, state, d_eps_m, d_kappa, dt, *, scheme="implicit", iterations=0
):
    """One increment of the layered section: (4.2.14)-(4.2.19).

    Returns `SectionUpdate(N, M, stress, state, tangent)`: the resultants at the end of the
    increment, the layers' stresses and states, and the section tangent
    d(N, M)/d(d_eps_m, d_kappa) = int b E_t [[1, -z], [-z, z^2]] dz from the layers' consistent
    tangents (alpha E for the report's scheme, (4.2.19)). `scheme`: "implicit" (law.update)
    or "report" (law.report_update with `iterations` of (4.2.11))."""
    step = _layer_step(section.law, scheme, iterations)
    d_strain = d_eps_m - section.z * d_kappa
    (new_stress, new_state), (tangent, _) = jax.jvp(
        lambda de: step(stress, state, de, dt), (d_strain,), (jnp.ones_like(d_strain),)
    )
    N, M = resultants(section, new_stress)
    weight = section.area * tangent
    ea = jnp.sum(weight)
    es = -jnp.sum(weight * section.z)
    ei = jnp.sum(weight * section.z**2)
    matrix = jnp.stack([jnp.stack([ea, es]), jnp.stack([es, ei])])
    return SectionUpdate(N, M, new_stress, new_state, matrix)
