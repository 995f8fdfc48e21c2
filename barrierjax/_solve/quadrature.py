"""Fixed-node quadrature rules that compile to a handful of fused array operations.

Two rules cover the singular integrals of the rigid-plastic hinge models:

- `gauss_legendre` for smooth integrands on a finite interval;
- `jacobi_product_weights` for integrals of r**lam * f(r) on [0, 1] with f smooth and
  lam > -1 (an algebraic end singularity), by product integration: f is expanded in
  shifted Legendre polynomials through its values at Gauss nodes, and each polynomial
  is integrated against r**lam exactly. The moments obey the stable recurrence

      m_0 = 1 / (lam + 1),   m_n = m_{n-1} (lam - n + 1) / (lam + n + 1),

  from Rodrigues' formula and the Beta integral, so the weights are smooth functions of
  lam and can be differentiated.
"""

import functools

import jax.numpy as jnp
import numpy as np


@functools.cache
def gauss_legendre_unit(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [0, 1] (weights sum to 1)."""
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1.0) / 2.0, w / 2.0


def gauss_legendre(n: int, a, b):
    """Nodes and weights of the n-point Gauss-Legendre rule on [a, b] (a, b may be arrays)."""
    x, w = gauss_legendre_unit(n)
    a = jnp.asarray(a)[..., None]
    b = jnp.asarray(b)[..., None]
    return a + (b - a) * x, (b - a) * w


@functools.cache
def _legendre_projection(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes r_i on [0, 1] and the matrix Q[i, k] = w_i (2k + 1) P_k(2 r_i - 1)."""
    r, w = gauss_legendre_unit(n)
    legendre = np.polynomial.legendre.legvander(2.0 * r - 1.0, n - 1)
    return r, w[:, None] * (2.0 * np.arange(n) + 1.0)[None, :] * legendre


def _shifted_legendre_moments(lam, n: int):
    """m_k = integral of r**lam P_k(2r - 1) over [0, 1], k = 0 .. n-1."""
    lam = jnp.asarray(lam)
    moments = [1.0 / (lam + 1.0)]
    for k in range(1, n):  # unrolled: n is small and static, and XLA fuses the products
        moments.append(moments[-1] * (lam - k + 1.0) / (lam + k + 1.0))
    return jnp.stack(moments, axis=-1)


def jacobi_product_nodes(n: int) -> np.ndarray:
    """The nodes r_i on [0, 1] at which `jacobi_product_weights` samples f."""
    return _legendre_projection(n)[0]


def jacobi_product_weights(n: int, lam):
    """Weights W_i with  integral_0^1 r**lam f(r) dr ~= sum_i W_i f(r_i)  (exact for
    polynomials f of degree < n). `lam` > -1, scalar or array (weights gain a last axis)."""
    _, projection = _legendre_projection(n)
    return _shifted_legendre_moments(lam, n) @ jnp.asarray(projection).T
