"""Viscoplastic rectangular beam sections, report section 4.1.

A rectangle of depth H = 2h and width B, plane sections staying plane, loaded from rest at a
constant curvature rate kappa' and extension rate lambda' (4.1.1), (4.1.21): the fibre at
height z strains at the constant rate eps' = lambda' + kappa' z. Every fibre obeys the
Cowper-Symonds overstress law

    E eps' = sigma' + E D <|sigma|/sigma0 - 1>^q sign(sigma),

the report's (4.1.18)-(4.1.20) with phi(x) = E D x^q / sigma0 ... written so that q = 1 is its
linear law (4.1.2), E eps' = sigma' + (sigma0/tau*) <sigma/sigma0 - 1>, with
tau* = sigma0 / (E D), and q = 5, D = 40/s is the law (4.3.1) of the examples.

Dimensionless variables (4.1.4), (4.1.32): z_ = z/h, sigma_ = sigma/sigma0, t_ = t/tau*,
kappa_ = E kappa h / sigma0 (curvature over the yield curvature), kappa_' = E kappa' tau* h /
sigma0 = kappa' h / D, lambda_' = 2 E lambda' tau* / sigma0 = 2 lambda' / D, M_ = M/M0 with
M0 = sigma0 B H^2/4 and N_ = N/N0 with N0 = sigma0 B H. A fibre then strains at the rate
rho = lambda_'/2 + kappa_' z_ and its overstress x = |sigma_| - 1 grows, once it yields at
t_ = 1/|rho|, by x' = |rho| - x^q. The section's forces are N_ = (1/2) int sigma_ dz_ and
M_ = int sigma_ z_ dz_ over [-1, 1], so that N_ lambda_' + M_ kappa_' is the rate of work.

The fibre's constant-rate solution: with x = |rho|^(1/q) y and s = (t_ - 1/|rho|) |rho|^(1-1/q),
F_q(y) = int_0^y dv / (1 - v^q) = s. For q = 1, y = 1 - e^-s (the report's exponential); for
other q, F_q is inverted by Newton's method (`_saturation`). The section integral is then
semi-closed: exact in the elastic band, Gauss quadrature in the viscoplastic zones, on panels
graded towards the moving elastic-viscoplastic boundaries (4.1.6), (4.1.23), where the
fibres' stress changes fastest.

Departures from the printed report (re-derived):
- (4.1.6) z0 = 1/(kappa_' t_) = 1/kappa_; (4.1.10), (4.1.12): the lower limit of the
  exponential integral is 1/kappa_', and the coefficient of the Ei term is 1/(3 kappa_'^2).
- The static limit (rate -> 0) beyond yield is M_ = 1 - 1/(3 kappa_^2) (elastic-perfectly
  plastic; M/M_elastic = (3/2)(1 - 1/(3 kappa_^2)) with M_elastic = (2/3) M0).
- (4.1.44): the rate measure is D = (lambda_'^2 + (4/3) kappa_'^2)^(1/2) (printed 1/3), so that
  (4.1.45)-(4.1.46) have (R^2 + 4/3)^(1/2) in their denominators (printed 14/3 and 1/4) and
  (4.1.47) 4 (N_ - 1)^2 + 3 M_^2 = D^2 holds as printed, with the normality (4.1.48).
- (4.1.42)-(4.1.43) and the yield surface hold for every q in the form `steady_forces`; the
  report's rate measure D is the q = 1 level of the viscous dissipation potential.
- The transient combined forces (4.1.33)-(4.1.41) are computed by `section_forces` (any q), not
  from the printed polynomial coefficients, which the scan garbles beyond recovery.
"""

import jax
import jax.numpy as jnp
import numpy as np

from .._checks import check, non_negative, positive

_FIBRE_NODES = 24  # Gauss nodes of F_q's regular part
_NEWTON_STEPS = 10
_PANEL_NODES = 12
_PANEL_GRADING = (4.0**-6, 4.0**-5, 4.0**-4, 4.0**-3, 4.0**-2, 4.0**-1, 1.0)


def _gauss(n, dtype):
    nodes, weights = np.polynomial.legendre.leggauss(n)
    return jnp.asarray(nodes, dtype), jnp.asarray(weights, dtype)


def _exponent_at_least_one(q):
    return check("q", q, lambda x: (x >= 1) & (x < jnp.inf), "at least 1 and finite")


# ---------------------------------------------------------------------------------------
# One fibre at a constant strain rate.


def _integrand(v, q):
    """1/(1 - v^q) - 1/(q (1 - v)) at v in [0, 1): G_q's integrand, bounded for q >= 1."""
    positive_v = v > 0
    v_safe = jnp.where(positive_v, v, 0.5 * jnp.ones_like(v))
    v_q = jnp.where(positive_v, jnp.exp(q * jnp.log(v_safe)), jnp.zeros_like(v))
    return 1 / (1 - v_q) - 1 / (q * (1 - v))


def _regular_part(y, q):
    """G_q(y) = int_0^y [1/(1 - v^q) - 1/(q (1 - v))] dv (Gauss-Legendre; zero for q = 1)."""
    xi, w = _gauss(_FIBRE_NODES, y.dtype)
    v = 0.5 * y[..., None] * (1 + xi)
    return 0.5 * y * jnp.sum(w * _integrand(v, q[..., None]), axis=-1)


def _saturation(s, q):
    """y in [0, 1) with F_q(y) = -log(1 - y)/q + G_q(y) = s, solved for w = -log(1 - y).

    r(w) = w/q + G_q(1 - e^-w) - s is increasing and concave, with slope
    1/q + G_q'(y) e^-w = (1 - y)/(1 - y^q) in [1/q, 1], so Newton's method converges from any
    start. A fixed count runs on stopped gradients, then one step with gradients gives the
    implicit function theorem's derivative."""
    s, q = jnp.broadcast_arrays(s, q)

    def residual(w):
        return w / q + _regular_part(-jnp.expm1(-w), q) - s

    def step(w):
        started = w > 0
        w_safe = jnp.where(started, w, jnp.ones_like(w))
        return w - residual(w) / jnp.where(started, 1 / _secant(jnp.exp(-w_safe), q), 1)

    w = jax.lax.stop_gradient(q * s)
    w = jax.lax.fori_loop(0, _NEWTON_STEPS, lambda _, w: step(w), w)
    return -jnp.expm1(-step(jax.lax.stop_gradient(w)))


def _secant(u, q):
    """(1 - (1 - u)^q)/u for u in (0, 1], with its limit q - q (q - 1) u/2 as u -> 0."""
    small = u < 1e-8
    u_safe = jnp.where(small, 0.5 * jnp.ones_like(u), u)
    exact = -jnp.expm1(q * jnp.log1p(-u_safe)) / u_safe
    return jnp.where(small, q - 0.5 * q * (q - 1) * u, exact)


@jax.jit
def _fibre_stress_bar(rho, t, q):
    """sigma/sigma0 of a fibre strained from rest at the dimensionless rate rho for a time t.

    Elastic, sigma_ = rho t, until |rho| t = 1; then |sigma_| = 1 + x with
    x = |rho|^(1/q) y, F_q(y) = (t - 1/|rho|) |rho|^(1 - 1/q)."""
    speed = jnp.abs(rho)
    plastic_time = t - 1 / jnp.where(speed > 0, speed, jnp.ones_like(speed))
    yielded = (speed > 0) & (plastic_time > 0)
    speed_safe = jnp.where(yielded, speed, jnp.ones_like(speed))
    plastic_time = jnp.where(yielded, plastic_time, jnp.zeros_like(plastic_time))
    saturated = speed_safe ** (1 / q)
    y = _saturation(plastic_time * speed_safe / saturated, q)
    return jnp.where(yielded, jnp.sign(rho) * (1 + saturated * y), rho * t)


def fibre_stress(strain_rate, time, *, E, sigma0, D, q):
    """Stress of a fibre strained from rest at a constant rate: the constant-rate solution of
    the Cowper-Symonds law E eps' = sigma' + E D <|sigma|/sigma0 - 1>^q sign(sigma), which the
    report integrates fibre by fibre for q = 1 (before (4.1.6))."""
    strain_rate = check("strain_rate", strain_rate, jnp.isfinite, "finite")
    time = non_negative("time", time)
    E, sigma0, D = positive("E", E), positive("sigma0", sigma0), positive("D", D)
    q = _exponent_at_least_one(q)
    return sigma0 * _fibre_stress_bar(strain_rate / D, time * E * D / sigma0, q)


# ---------------------------------------------------------------------------------------
# The section: elastic band exactly, viscoplastic zones by graded Gauss panels.


def _graded_panel(start, end, dtype):
    """Gauss nodes and weights on the segment from `start` (a yield line) to `end`, on panels
    whose lengths grow geometrically away from `start`."""
    xi, w = np.polynomial.legendre.leggauss(_PANEL_NODES)
    edges = np.concatenate([[0.0], _PANEL_GRADING])
    lengths = np.diff(edges)
    fractions = (edges[:-1, None] + 0.5 * lengths[:, None] * (1 + xi)).ravel()
    weights = (0.5 * lengths[:, None] * w).ravel()
    span = (end - start)[..., None]
    z = start[..., None] + span * jnp.asarray(fractions, dtype)
    return z, jnp.abs(span) * jnp.asarray(weights, dtype)


@jax.jit
def _section_bar(t, kappa_rate, extension_rate, q):
    """(N_, M_) at the dimensionless time t under the rates kappa_' > 0 and lambda_'."""
    t, kappa_rate, extension_rate, q = jnp.broadcast_arrays(t, kappa_rate, extension_rate, q)
    c = 0.5 * extension_rate
    one = jnp.ones_like(t)
    lower = jnp.clip((-1 / t - c) / kappa_rate, -one, one)
    upper = jnp.clip((1 / t - c) / kappa_rate, -one, one)
    normal = 0.5 * t * (c * (upper - lower) + 0.5 * kappa_rate * (upper**2 - lower**2))
    moment = t * (0.5 * c * (upper**2 - lower**2) + kappa_rate * (upper**3 - lower**3) / 3)
    for start, end in ((upper, one), (lower, -one)):
        z, w = _graded_panel(start, end, t.dtype)
        rho = c[..., None] + kappa_rate[..., None] * z
        sigma = _fibre_stress_bar(rho, t[..., None], q[..., None])
        normal = normal + 0.5 * jnp.sum(w * sigma, axis=-1)
        moment = moment + jnp.sum(w * sigma * z, axis=-1)
    return normal, moment


def section_forces_bar(time, kappa_rate, extension_rate, q=1.0):
    """(N/N0, M/M0) at the dimensionless time t_ = t/tau* after loading from rest at the
    constant dimensionless rates kappa_' > 0 and lambda_' (4.1.32): the solution of the
    generalized constitutive equations (4.1.33)-(4.1.41) (q = 1) and their analogue for any
    q >= 1. |lambda_'| <= 2 kappa_' is the report's case (a), the strain rate changing sign
    across the depth; |lambda_'| >= 2 kappa_' is case (b)."""
    time = positive("time", time)
    kappa_rate = positive("kappa_rate", kappa_rate)
    extension_rate = check("extension_rate", extension_rate, jnp.isfinite, "finite")
    return _section_bar(time, kappa_rate, extension_rate, _exponent_at_least_one(q))


def moment_curvature_bar(kappa, kappa_rate, q=1.0):
    """M/M0 at the curvature kappa_ = kappa/kappa_e reached at the constant rate kappa_'
    (4.1.11)-(4.1.12) for q = 1, and its analogue for any q >= 1."""
    kappa = positive("kappa", kappa)
    kappa_rate = positive("kappa_rate", kappa_rate)
    zero = jnp.zeros_like(kappa * kappa_rate)
    return _section_bar(kappa / kappa_rate, kappa_rate, zero, _exponent_at_least_one(q))[1]


def _scales(E, sigma0, D, depth, width):
    E, sigma0, D = positive("E", E), positive("sigma0", sigma0), positive("D", D)
    depth, width = positive("depth", depth), positive("width", width)
    return E, sigma0, D, depth, width


def section_forces(time, curvature_rate, extension_rate, *, E, sigma0, D, q, depth, width):
    """Axial force N and bending moment M of a rectangular section (depth H, width B) at
    `time` after loading from rest at a constant curvature rate kappa' > 0 and extension rate
    lambda' (4.1.21)-(4.1.41), Cowper-Symonds law (D, q)."""
    E, sigma0, D, depth, width = _scales(E, sigma0, D, depth, width)
    time = positive("time", time)
    curvature_rate = positive("curvature_rate", curvature_rate)
    extension_rate = check("extension_rate", extension_rate, jnp.isfinite, "finite")
    normal, moment = _section_bar(
        time * E * D / sigma0,
        0.5 * curvature_rate * depth / D,
        2 * extension_rate / D,
        _exponent_at_least_one(q),
    )
    return sigma0 * width * depth * normal, 0.25 * sigma0 * width * depth**2 * moment


def moment_curvature(curvature, curvature_rate, *, E, sigma0, D, q, depth, width):
    """Bending moment at the curvature reached from rest at a constant curvature rate
    (4.1.9)-(4.1.12), for the Cowper-Symonds law (D, q) (q = 1: the report's linear law)."""
    curvature = positive("curvature", curvature)
    curvature_rate = positive("curvature_rate", curvature_rate)
    return section_forces(
        curvature / curvature_rate,
        curvature_rate,
        jnp.zeros_like(curvature * curvature_rate),
        E=E,
        sigma0=sigma0,
        D=D,
        q=q,
        depth=depth,
        width=width,
    )[1]


# ---------------------------------------------------------------------------------------
# Pure bending, linear law (q = 1): the closed form and the report's approximations.

_ASYMPTOTIC_FROM = 40.0
_ASYMPTOTIC_TERMS = 40


@jax.jit
def _expi_scaled(x):
    """e^-x Ei(x) for x > 0, by its asymptotic series sum k!/x^(k+1) for large x (where
    e^x overflows; at x = 40 the smallest term is about 1e-16 of the sum)."""
    large = x > _ASYMPTOTIC_FROM
    x_small = jnp.where(large, jnp.ones_like(x), x)
    x_large = jnp.where(large, x, _ASYMPTOTIC_FROM * jnp.ones_like(x))
    factorials = np.cumprod(np.concatenate([[1.0], np.arange(1.0, _ASYMPTOTIC_TERMS)]))
    powers = x_large[..., None] ** jnp.arange(1, _ASYMPTOTIC_TERMS + 1, dtype=x.dtype)
    series = jnp.sum(jnp.asarray(factorials, x.dtype) / powers, axis=-1)
    return jnp.where(large, series, jnp.exp(-x_small) * jax.scipy.special.expi(x_small))


def moment_linear(kappa, kappa_rate):
    """M/M0 of the linear law at kappa_ reached at the constant rate kappa_', (4.1.11)-(4.1.12):

        M_ = (2/3) kappa_                                                    (kappa_ <= 1)
        M_ = 1 + (2/3) k' + 1/(3 k' kappa_) - (1/3 + (2/3) k' + 1/(3 k')) e^((1 - kappa_)/k')
             - 1/(3 k'^2) e^(-kappa_/k') int_{1/k'}^{kappa_/k'} e^x/x dx         (kappa_ >= 1)

    with k' = kappa_'. The printed lower limit 1/kappa is 1/k'. The terms of order 1/k'
    cancel to leave M_ of order 1: at k' = 1e-3 about three digits are lost, so for slow
    rates prefer `moment_curvature_bar`, which has no such cancellation."""
    kappa = positive("kappa", kappa)
    kappa_rate = positive("kappa_rate", kappa_rate)
    kappa, kappa_rate = jnp.broadcast_arrays(kappa, kappa_rate)
    yielded = kappa > 1
    k = jnp.where(yielded, kappa, 2 * jnp.ones_like(kappa))
    a = 1 / kappa_rate
    t = k * a
    integral = _expi_scaled(t) - jnp.exp(a - t) * _expi_scaled(a)  # e^-t int_a^t e^x/x dx
    viscoplastic = (
        1
        + (2 / 3) * kappa_rate
        + a / (3 * k)
        - (1 / 3 + (2 / 3) * kappa_rate + a / 3) * jnp.exp(a - t)
        - a**2 / 3 * integral
    )
    return jnp.where(yielded, viscoplastic, (2 / 3) * kappa)


def static_moment(kappa):
    """M/M0 of the elastic-perfectly plastic section, the rate -> 0 limit:
    (2/3) kappa_ for kappa_ <= 1, 1 - 1/(3 kappa_^2) beyond."""
    kappa = non_negative("kappa", kappa)
    k = jnp.where(kappa > 1, kappa, jnp.ones_like(kappa))
    return jnp.where(kappa > 1, 1 - 1 / (3 * k**2), (2 / 3) * kappa)


def moment_limit(kappa_rate, q=1.0):
    """The dynamic moment capacity, M_ as t -> infinity (4.1.13): every fibre at its steady
    overstress (kappa_' z_)^(1/q), so M_ = 1 + 2q/(2q + 1) kappa_'^(1/q); q = 1 gives the
    printed 1 + (2/3) kappa_'."""
    kappa_rate = non_negative("kappa_rate", kappa_rate)
    q = _exponent_at_least_one(q)
    return 1 + 2 * q / (2 * q + 1) * kappa_rate ** (1 / q)


def moment_rigid_plastic(kappa, kappa_rate):
    """Approximation (4.1.14): rigid until the dynamic capacity 1 + (2/3) kappa_', then
    flowing at it (M_ = 0 at kappa_ = 0)."""
    kappa = non_negative("kappa", kappa)
    capacity = moment_limit(kappa_rate)
    return jnp.where(kappa > 0, capacity, jnp.zeros_like(capacity))


def moment_elastic_plastic(kappa, kappa_rate):
    """Approximation (4.1.15): elastic, (2/3) kappa_, up to the dynamic capacity
    1 + (2/3) kappa_' (reached at kappa_ = 1.5 + kappa_'), then flowing at it."""
    kappa = non_negative("kappa", kappa)
    return jnp.minimum((2 / 3) * kappa, moment_limit(kappa_rate))


def moment_exponential(kappa, kappa_rate, alpha=1.0):
    """Approximations (4.1.16) (alpha = 1) and (4.1.17): elastic to kappa_ = 1, then
    M_ = (2/3) kappa_ e^(-alpha (kappa_ - 1)) + (1 + (2/3) kappa_') (1 - e^(-alpha (kappa_ - 1)))."""
    kappa = non_negative("kappa", kappa)
    alpha = positive("alpha", alpha)
    decay = jnp.exp(-alpha * jnp.maximum(kappa - 1, jnp.zeros_like(kappa)))
    return (2 / 3) * kappa * decay + moment_limit(kappa_rate) * (1 - decay)


# ---------------------------------------------------------------------------------------
# The dynamic yield surface (t -> infinity).


def steady_forces(kappa_rate, extension_rate, q=1.0):
    """(N_, M_) as t -> infinity at the rates kappa_' >= 0, lambda_' (4.1.42)-(4.1.43), for
    any q >= 1: every fibre at sigma_ = sign(rho) (1 + |rho|^(1/q)), rho = lambda_'/2 +
    kappa_' z_, integrated in closed form. (N_, M_) is the gradient of the dissipation
    potential int (|rho| + |rho|^(1+1/q)/(1+1/q)) dz_ with respect to (lambda_', kappa_')."""
    kappa_rate = positive("kappa_rate", kappa_rate)
    extension_rate = check("extension_rate", extension_rate, jnp.isfinite, "finite")
    q = _exponent_at_least_one(q)
    kappa_rate, extension_rate, q = jnp.broadcast_arrays(kappa_rate, extension_rate, q)
    p = 1 / q
    c = 0.5 * extension_rate
    one = jnp.ones_like(c)
    neutral = jnp.clip(-c / kappa_rate, -one, one)
    top, bottom = c + kappa_rate, c - kappa_rate

    def power(x, n):  # |x|^n with a finite gradient at x = 0 (n > 1)
        nonzero = x != 0
        x_safe = jnp.where(nonzero, jnp.abs(x), one)
        return jnp.where(nonzero, x_safe**n, jnp.zeros_like(x))

    viscous_n = (power(top, p + 1) - power(bottom, p + 1)) / ((p + 1) * kappa_rate)
    viscous_m = (
        (jnp.sign(top) * power(top, p + 2) - jnp.sign(bottom) * power(bottom, p + 2)) / (p + 2)
        - c * (power(top, p + 1) - power(bottom, p + 1)) / (p + 1)
    ) / kappa_rate**2
    return -neutral + 0.5 * viscous_n, 1 - neutral**2 + viscous_m


def yield_surface(rate, ratio):
    """(N_, M_) on the dynamic yield surface of the linear law (4.1.45)-(4.1.46) at the rate
    measure D = (lambda_'^2 + (4/3) kappa_'^2)^(1/2) and the ratio R = lambda_'/kappa_' >= 0
    (4.1.44): kappa_' = D/(R^2 + 4/3)^(1/2), lambda_' = R kappa_'. The printed 1/3 in (4.1.44)
    and 14/3, 1/4 in (4.1.45)-(4.1.46) are 4/3: only then does (4.1.47) hold as printed."""
    rate = non_negative("rate", rate)
    ratio = non_negative("ratio", ratio)
    kappa_rate = rate / jnp.sqrt(ratio**2 + 4 / 3)
    half = jnp.minimum(0.5 * ratio, jnp.ones_like(ratio))
    normal = half + 0.5 * ratio * kappa_rate
    moment = 1 - half**2 + (2 / 3) * kappa_rate
    return normal, moment


def yield_function(normal, moment, rate):
    """The surface (4.1.47) of case (b), R >= 2: 4 (N_ - 1)^2 + 3 M_^2 - D^2 (zero on it);
    its gradient is 4 (lambda_', kappa_'), the rate vector (normality, (4.1.48))."""
    return 4 * (normal - 1) ** 2 + 3 * moment**2 - rate**2


def static_yield_function(normal, moment):
    """|M_| + N_^2 - 1, the static interaction of a rectangle (D = 0)."""
    return jnp.abs(moment) + normal**2 - 1
