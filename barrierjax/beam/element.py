"""The two-node plane beam element of report 4.2 (iii), in a co-rotational frame.

Degrees of freedom per node, global frame X_0: (u, w, theta) = (displacement along X,
displacement along Y, rotation, counter-clockwise). The element's local frame X follows the
chord between its two nodes (the report's updated frame (4.2.20), with the rotation psi of the
chord): the rigid motion of the chord is removed exactly, and what is left is small,

    u_l = l - L0                      (axial stretch of the chord),
    theta_1 = theta_1 - psi,  theta_2 = theta_2 - psi    (end rotations from the chord),

with psi the chord's rotation from its initial direction. In the local frame the fields are
interpolated as in (4.2.28): linear axial displacement and the cubic Hermite transverse
displacement w(x) = L0 [(xi - 2 xi^2 + xi^3) theta_1 + (xi^3 - xi^2) theta_2], xi = x / L0
(w = 0 at both ends of the chord), so that

    eps_m = u_l / L0 + (2 theta_1^2 - theta_1 theta_2 + 2 theta_2^2) / 30,
    kappa(xi) = w'' = [(6 xi - 4) theta_1 + (6 xi - 2) theta_2] / L0.

The second term of eps_m is the element average of w'^2 / 2: it is the report's geometric
stiffness [K2] (4.2.37) within the element, (N - dN') int phi_w'^T phi_w' dx, the part of the
geometric stiffness that the chord rotation does not carry (`shallow=False` drops it). The
internal nodal forces are the virtual work of the section resultants (4.2.30)-(4.2.32),

    f = int_0^L0 (d e / d q)^T {N, M} dx,   e = (eps_m, kappa),

integrated at 2-3 points along the element, each point a layered section
(`barrierjax.beam.layered`). The tangent stiffness [K1] + [K2] (4.2.36)-(4.2.37), with the
consistent material tangent, is the forward-mode derivative of f: exact, and symmetric where
the material update is.

The consistent mass (4.2.35) with rotary inertia is integrated from the same shape functions
(linear axial, Hermite transverse, and rho I w'^2 for the rotary part) in the chord frame at the
start of the step; its length is L0 (the mass of the element is conserved).
"""

import jax
import jax.numpy as jnp
import numpy as np

from .layered import section_update

QUADRATURES = ("gauss2", "gauss3", "lobatto3")


def length_points(quadrature: str):
    """Points xi in [0, 1] along the element and their weights (sum 1)."""
    if quadrature == "gauss2":
        x, w = np.polynomial.legendre.leggauss(2)
    elif quadrature == "gauss3":
        x, w = np.polynomial.legendre.leggauss(3)
    elif quadrature == "lobatto3":
        x, w = np.array([-1.0, 0.0, 1.0]), np.array([1.0, 4.0, 1.0]) / 3
    else:
        raise ValueError(f"quadrature must be one of {QUADRATURES}; got {quadrature!r}")
    return (x + 1) / 2, w / 2


def _atan2_safe(y, x):
    return jnp.arctan2(y, x)


def local_deformation(X1, X2, q):
    """(u_l, theta_1, theta_2) of the chord frame, from the initial nodes X1, X2 (2,) and the
    element's global displacements q (6,) = (u1, w1, th1, u2, w2, th2)."""
    d0 = X2 - X1
    L0 = jnp.sqrt(jnp.sum(d0**2))
    c0, s0 = d0[0] / L0, d0[1] / L0
    d = d0 + q[3:5] - q[0:2]
    # psi: rotation of the chord from its initial direction (atan2 of cross and dot products).
    psi = _atan2_safe(c0 * d[1] - s0 * d[0], c0 * d[0] + s0 * d[1])
    l2 = jnp.sum(d**2)
    stretch = (l2 - L0**2) / (jnp.sqrt(l2) + L0)  # l - L0 without cancellation
    return stretch, q[2] - psi, q[5] - psi, L0


def generalised_strains(X1, X2, q, xi, shallow=True):
    """(eps_m, kappa) at the points xi (n,): shape (n, 2)."""
    stretch, t1, t2, L0 = local_deformation(X1, X2, q)
    eps = stretch / L0
    if shallow:
        eps = eps + (2 * t1**2 - t1 * t2 + 2 * t2**2) / 30
    kappa = ((6 * xi - 4) * t1 + (6 * xi - 2) * t2) / L0
    return jnp.stack([jnp.broadcast_to(eps, kappa.shape), kappa], axis=-1)


def element_response(
    section,
    X1,
    X2,
    q_new,
    q_old,
    stress,
    state,
    dt,
    xi,
    weights,
    *,
    scheme="implicit",
    iterations=0,
    shallow=True,
    tangent=False,
):
    """Internal nodal forces (6,) of one element at q_new, stepping its sections from the
    converged q_old (stresses and states of shape (n_points, n_fibres)) over dt.

    Returns (f, (stress, state, N, M, strains)), and with `tangent` the element's tangent
    stiffness (6, 6) after them (`_stiffness`)."""
    xi = jnp.asarray(xi, dtype=q_new.dtype)
    weights = jnp.asarray(weights, dtype=q_new.dtype)

    def strains(q):
        return generalised_strains(X1, X2, q, xi, shallow)

    e_new, pullback = jax.vjp(strains, q_new)
    d_e = e_new - strains(q_old)

    def point(stress_p, state_p, de):
        out = section_update(
            section, stress_p, state_p, de[0], de[1], dt, scheme=scheme, iterations=iterations
        )
        return out.N, out.M, out.stress, out.state, out.tangent

    N, M, new_stress, new_state, D = jax.vmap(point)(stress, state, d_e)
    length_weights = weights * jnp.sqrt(jnp.sum((X2 - X1) ** 2))
    resultant = length_weights[:, None] * jnp.stack([N, M], axis=-1)
    (f,) = pullback(resultant)
    out = (new_stress, new_state, N, M, e_new)
    if not tangent:
        return f, out
    return f, out, _stiffness(strains, q_new, resultant, length_weights[:, None, None] * D)


def _stiffness(strains, q, resultant, D):
    """The tangent stiffness [K1] + [K2] (4.2.36)-(4.2.37) of f = B^T r, B = de/dq the
    strains' derivative at the points and r the resultants (weighted by the points' lengths):
    B^T D B with D the sections' consistent tangents d r / d e (`section_update`), plus the
    geometric stiffness sum r . d^2 e / dq^2 (the co-rotational frame's and the shallow
    term's). The sections' laws are differentiated once, along d e, not along each of the
    six dofs."""
    B = jax.jacfwd(strains)(q)  # (n_points, 2, 6)
    material = jnp.einsum("pai,pab,pbj->ij", B, D, B)
    geometric = jax.hessian(lambda x: jnp.sum(resultant * strains(x)))(q)
    return material + geometric


def hermite_shape(xi, L):
    """Transverse shape functions (4,) for (w1, th1, w2, th2) and their x-derivatives."""
    n = jnp.stack(
        [
            1 - 3 * xi**2 + 2 * xi**3,
            L * (xi - 2 * xi**2 + xi**3),
            3 * xi**2 - 2 * xi**3,
            L * (xi**3 - xi**2),
        ]
    )
    dn = jnp.stack(
        [
            (-6 * xi + 6 * xi**2) / L,
            1 - 4 * xi + 3 * xi**2,
            (6 * xi - 6 * xi**2) / L,
            3 * xi**2 - 2 * xi,
        ]
    )
    return n, dn


def local_mass(rho, A, I, L):
    """Consistent mass (4.2.35) in the chord frame, dofs (u1, w1, th1, u2, w2, th2): rho A
    int (phi_u^T phi_u + phi_w^T phi_w) + rho I int phi_w'^T phi_w', by 4-point Gauss (exact
    for the degree-6 integrands)."""
    x, w = np.polynomial.legendre.leggauss(4)
    dtype = jnp.result_type(L)
    xi = jnp.asarray((x + 1) / 2, dtype)
    w = jnp.asarray(w / 2, dtype)
    zero = jnp.zeros_like(xi)
    n, dn = jax.vmap(lambda s: hermite_shape(s, L))(xi)
    pu = jnp.stack([1 - xi, zero, zero, xi, zero, zero], axis=-1)
    pw = jnp.stack([zero, n[:, 0], n[:, 1], zero, n[:, 2], n[:, 3]], axis=-1)
    pr = jnp.stack([zero, dn[:, 0], dn[:, 1], zero, dn[:, 2], dn[:, 3]], axis=-1)
    outer = jnp.einsum("g,gi,gj->ij", w, pu, pu) + jnp.einsum("g,gi,gj->ij", w, pw, pw)
    return L * (rho * A * outer + rho * I * jnp.einsum("g,gi,gj->ij", w, pr, pr))


def rotation(c, s):
    """T (6, 6) with q_local = T q_global for a chord of direction (c, s) (4.2.20)."""
    zero = jnp.zeros_like(c)
    one = jnp.ones_like(c)
    block = jnp.stack(
        [jnp.stack([c, s, zero]), jnp.stack([-s, c, zero]), jnp.stack([zero, zero, one])]
    )
    z3 = jnp.zeros((3, 3), c.dtype)
    return jnp.block([[block, z3], [z3, block]])


def element_mass(rho, A, I, X1, X2, q):
    """Global consistent mass of an element whose chord is at X + q: T^T m T (4.2.35)."""
    L0 = jnp.sqrt(jnp.sum((X2 - X1) ** 2))
    d = X2 - X1 + q[3:5] - q[0:2]
    length = jnp.sqrt(jnp.sum(d**2))
    T = rotation(d[0] / length, d[1] / length)
    return T.T @ local_mass(rho, A, I, L0) @ T
