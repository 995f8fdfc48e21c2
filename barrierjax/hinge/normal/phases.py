"""The phases of report 3.2 per unit impact speed: the accelerative phase
(3.2.9)-(3.2.14) and the constants of the decelerative phase (3.2.15)-(3.2.19): alpha,
the positive root of p(S), its companions beta and gamma, and the exponents of (3.2.19)."""

import equinox as eqx
import jax.numpy as jnp

from ..._custom_types import Scalar
from ..._solve.newton import newton


class Accelerative(eqx.Module):
    s_star: Scalar
    acceleration: Scalar  # beam, (phi - S*)/S*
    deceleration: Scalar  # vehicle, phi/mu
    t_star: Scalar
    v_star: Scalar
    w_star: Scalar


def accelerative_phase(mu, phi) -> Accelerative:
    root = jnp.sqrt(phi**2 + 3.0)
    s_star = 3.0 / (root + phi)  # = root - phi without cancellation at large phi
    # (phi - S*)/S* with phi - S* = 3 (phi^2 - 1)/(2 phi + root), exact as phi -> 1+.
    acceleration = 3.0 * (phi - 1.0) * (phi + 1.0) / ((2.0 * phi + root) * s_star)
    deceleration = phi / mu
    t_star = 1.0 / (acceleration + deceleration)
    return Accelerative(
        s_star=s_star,
        acceleration=acceleration,
        deceleration=deceleration,
        t_star=t_star,
        v_star=acceleration * t_star,
        w_star=0.5 * acceleration * t_star**2,
    )


def _cubic(s, mu):
    """p(S) = S^3 + 3 mu S^2 - 3 S - 3 mu (3.2.17), whose positive root is alpha."""
    return s**3 + 3.0 * mu * s**2 - 3.0 * s - 3.0 * mu


def _cubic_linearised(s, mu):
    return 3.0 * s**2 + 6.0 * mu * s - 3.0, _cubic(s, mu), jnp.inf


def _largest_root(mu):
    """alpha: the positive root of p(S) = S^3 + 3 mu S^2 - 3 S - 3 mu, in [1, sqrt(3)].

    p is increasing and convex on [1, inf) and p(sqrt 3) = 6 mu >= 0, so Newton's method
    from sqrt(3) decreases monotonically onto alpha; eight steps reach rounding for every
    mu >= 0. Differentiated implicitly, not through the iterations (`_solve.newton`)."""
    return newton(
        _cubic_linearised,
        lambda s, mu: (_cubic(s, mu), jnp.inf),
        lambda slope, p: p / slope,
        jnp.full_like(mu, jnp.sqrt(3.0)),
        mu,
        iterations=7,
    ).root


class Decelerative(eqx.Module):
    mu: Scalar
    alpha: Scalar
    beta: Scalar
    gamma: Scalar
    a: Scalar  # exponents of (3.2.19)
    b: Scalar
    c: Scalar
    s_star: Scalar
    v_star: Scalar

    def log_ratio(self, s, log_beta_ratio=None):
        """B ln((S+beta)/(S*+beta)) + C ln((S+gamma)/(S*+gamma)); the first logarithm may
        be passed in where the caller already has it."""
        if log_beta_ratio is None:
            log_beta_ratio = jnp.log1p((s - self.s_star) / (self.s_star + self.beta))
        return self.b * log_beta_ratio + self.c * jnp.log1p(
            (s - self.s_star) / (self.s_star + self.gamma)
        )

    def hinge_from_chi(self, chi):
        """S from the ODE state chi = A ln(alpha - S)."""
        return self.alpha - jnp.exp(chi / self.a)

    def time_per_velocity(self, s):
        """-dT/dV = 2 S (S + 2 mu) / (S^2 + 3), the inverse of (3.2.15)."""
        return 2.0 * s * (s + 2.0 * self.mu) / (s**2 + 3.0)

    def lever(self, s):
        """2 S (S + 2 mu) / ((S + beta)(S + gamma)), so that dT/dS = lever V / (alpha - S)
        (3.2.16, with p(S) factored as in 3.2.17)."""
        return 2.0 * s * (s + 2.0 * self.mu) / ((s + self.beta) * (s + self.gamma))


def decelerative_constants(mu, acc: Accelerative) -> Decelerative:
    alpha = _largest_root(mu)
    # Vieta: beta + gamma = 3 mu + alpha, beta gamma = 3 mu / alpha (no cancellation).
    total = 3.0 * mu + alpha
    gamma = 0.5 * (total + jnp.sqrt(total**2 - 12.0 * mu / alpha))
    beta = 3.0 * mu / (alpha * gamma)
    return Decelerative(
        mu=mu,
        alpha=alpha,
        beta=beta,
        gamma=gamma,
        a=(3.0 + alpha**2) / ((alpha + beta) * (alpha + gamma)),
        b=(3.0 + beta**2) / ((alpha + beta) * (beta - gamma)),
        c=(3.0 + gamma**2) / ((gamma + alpha) * (gamma - beta)),
        s_star=acc.s_star,
        v_star=acc.v_star,
    )
