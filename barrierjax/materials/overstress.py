"""Overstress (viscoplastic) laws E eps' = sigma' + g(sigma, eps), report (2.2.1)-(2.2.8).

The plastic strain rate is eps_p' = g / E sign(sigma), with g >= 0 a function of the
overstress x = |sigma| - k(kappa) beyond the static curve (`barrierjax.materials.curves`):
flow happens only for x > 0 (the report's rule g = 0 between f-(eps) and f+(eps)), stress below
the curve unloads elastically, and at fixed strain the stress relaxes onto the curve.

Compression and reversed loading: the report writes the static stress as a curve f(eps) of the
total strain. Under reversed loading that band moves with the elastic strain (after tensile
flow, a small positive strain with a compressive stress would flow in compression at
|sigma| < sigma0), so the static stress here is the static curve at the accumulated plastic
strain kappa (isotropic hardening), the same in tension and compression. For monotonic loading
with the elastic-perfectly plastic curve it is the report's law exactly (k = f = sigma0 wherever
sigma > f); with a hardening curve it is the report's law with f read at the current plastic
strain rather than the total strain, so closed forms such as (2.2.4) hold only for the
elastic-perfectly plastic curve.

The report's second unloading rule (E eps' = sigma' whenever eps' < 0 and sigma > f+(eps), and
symmetrically in compression) is the static option `elastic_unloading=True`. By default flow is
governed by the overstress alone, "flow iff |sigma| > sigma0" as in the beam chapter
(4.2.12)-(4.2.13); relaxation at fixed strain (eps' = 0) continues under both rules.

Three per-step updates over a strain increment d_strain in time dt:
- `update`: backward Euler, unconditionally stable. The overstress x at the end of the step
  solves x - x_trial + dt g(x) + k(kappa + dt g(x)/E) - k(kappa) = 0 on [0, x_trial]; a
  safeguarded Newton iteration (Newton, else bisection: Numerical Recipes' rtsafe) runs a fixed
  number of times on stopped gradients, then one Newton step with gradients gives the implicit
  function theorem's derivative at the converged root.
- `report_update`: the report's scheme (4.2.8)-(4.2.11).
- `explicit_update`: forward Euler (conditionally stable: dt < 2 / g'(x)).
`plastic_rate` is the vector field for an ODE solver.
"""

from typing import NamedTuple

import equinox as eqx
import jax
import jax.numpy as jnp

from .._checks import check, positive
from .curves import ElasticPerfectlyPlastic, StaticCurve


class OverstressState(NamedTuple):
    plastic_strain: jnp.ndarray
    kappa: jnp.ndarray  # accumulated plastic strain


def _static_yield(sigma0):
    """A scalar sigma0 is the elastic-perfectly plastic curve; a `StaticCurve` is kept."""
    return sigma0 if isinstance(sigma0, StaticCurve) else ElasticPerfectlyPlastic(sigma0)


def _positive_part(x):
    """x where x > 0, else 1: keeps the untaken branch of a `where` finite (double where)."""
    return jnp.where(x > 0, x, jnp.ones_like(x))


class OverstressLaw(eqx.Module):
    """Base of the laws E eps' = sigma' + g(x) sign(sigma), x = |sigma| - k(kappa)."""

    E: jnp.ndarray
    sigma0: StaticCurve
    elastic_unloading: bool = eqx.field(static=True)
    iterations: int = eqx.field(static=True)

    def _init_common(self, E, sigma0, elastic_unloading, iterations, **positive_parameters):
        """Set the fields every law has, then each of the law's own `positive_parameters`
        (name=value), checked positive and finite, as the field of that name."""
        self.E = positive("E", E)
        self.sigma0 = None if sigma0 is None else _static_yield(sigma0)
        self.elastic_unloading = bool(elastic_unloading)
        if int(iterations) < 1:
            raise ValueError(f"iterations must be a positive integer; got {iterations!r}")
        self.iterations = int(iterations)
        for name, value in positive_parameters.items():
            setattr(self, name, positive(name, value))

    def flow(self, overstress, static_stress, strain):
        """g >= 0, E times the plastic strain rate, for overstress >= 0 (0 at 0)."""
        raise NotImplementedError

    def flow_inverse(self, rate, static_stress, strain):
        """The overstress x with g(x) = rate (rate >= 0), where it has a closed form: it
        starts the backward-Euler iteration (`update`). Default: no estimate (inf)."""
        return jnp.full_like(rate, jnp.inf)

    def static_stress(self, kappa):
        return self.sigma0.yield_stress(kappa)

    def init_state(self):
        zero = jnp.zeros_like(self.E)
        return OverstressState(zero, zero)

    def _flows(self, direction, strain_change):
        """The report's extra unloading rule, where it is switched on."""
        if not self.elastic_unloading:
            return jnp.ones_like(direction, dtype=bool)
        return strain_change * direction >= 0

    def _rate(self, stress, state, strain_change):
        """Signed g(sigma) at fixed state (zero inside the static curve)."""
        k = self.static_stress(state.kappa)
        strain = state.plastic_strain + stress / self.E
        x = jnp.abs(stress) - k
        direction = jnp.sign(stress)
        active = (x > 0) & self._flows(direction, strain_change)
        g = self.flow(jnp.where(active, x, jnp.zeros_like(x)), k, strain)
        return jnp.where(active, direction * g, jnp.zeros_like(g))

    def plastic_rate(self, stress, state, strain_rate):
        """The state's time derivative (eps_p', kappa') at the given stress."""
        rate = self._rate(stress, state, strain_rate) / self.E
        return OverstressState(rate, jnp.abs(rate))

    def explicit_update(self, stress, state, d_strain, dt):
        """Forward Euler: d_sigma = E d_eps - dt g(sigma_n)."""
        d_plastic = dt * self._rate(stress, state, d_strain) / self.E
        new_state = OverstressState(
            state.plastic_strain + d_plastic, state.kappa + jnp.abs(d_plastic)
        )
        return stress + self.E * (d_strain - d_plastic), new_state

    def report_update(self, stress, state, d_strain, dt, iterations=0):
        """The report's scheme (4.2.8)-(4.2.10): alpha E d_eps = d_sigma + d_sigma', with
        alpha = 1 / (1 + dt/2 g'(sigma_n)) and d_sigma' = alpha g(sigma_n) dt, from the
        trapezoidal rule for the flow integral (4.2.7) with g linearised about sigma_n.
        `iterations` repeats (4.2.11): alpha re-evaluated at sigma_n + d_sigma/2, g kept at
        sigma_n as printed. Flow iff |sigma_n| > k, the rule (4.2.12)-(4.2.13)."""
        g, dg = jax.jvp(
            lambda s: self._rate(s, state, d_strain), (stress,), (jnp.ones_like(stress),)
        )

        def increment(slope):
            alpha = 1 / (1 + dt / 2 * slope)
            return alpha * (self.E * d_strain - g * dt)

        d_stress = increment(dg)
        for _ in range(iterations):
            midpoint = stress + d_stress / 2
            _, dg_mid = jax.jvp(
                lambda s: self._rate(s, state, d_strain), (midpoint,), (jnp.ones_like(stress),)
            )
            d_stress = increment(dg_mid)
        d_plastic = d_strain - d_stress / self.E
        new_state = OverstressState(
            state.plastic_strain + d_plastic, state.kappa + jnp.abs(d_plastic)
        )
        return stress + d_stress, new_state

    def _residual(self, x, x_trial, kappa, k, strain, dt):
        g = self.flow(x, k, strain)
        hardening = self.static_stress(kappa + dt * g / self.E) - k
        return x - x_trial + dt * g + hardening

    def update(self, stress, state, d_strain, dt):
        """Backward Euler over the step (see the module docstring)."""
        k = self.static_stress(state.kappa)
        trial = stress + self.E * d_strain
        direction = jnp.sign(trial)
        strain = state.plastic_strain + trial / self.E
        active = (jnp.abs(trial) > k) & self._flows(direction, d_strain)
        x_trial = jnp.where(active, jnp.abs(trial) - k, jnp.zeros_like(trial))

        frozen = jax.lax.stop_gradient((self, x_trial, state.kappa, k, strain, dt))

        def value_and_slope(law, x, *args):
            return jax.jvp(lambda y: law._residual(y, *args), (x,), (jnp.ones_like(x),))

        def safeguarded_newton(carry):
            x, low, high, last_step, _, iteration = carry
            r, dr = value_and_slope(frozen[0], x, *frozen[1:])
            low = jnp.where(r <= 0, x, low)
            high = jnp.where(r >= 0, x, high)
            newton = x - r / dr
            use_newton = (
                (newton >= low) & (newton <= high) & (jnp.abs(2 * r) <= jnp.abs(last_step * dr))
            )
            new = jnp.where(use_newton, newton, (low + high) / 2)
            # Converged to rounding: stay. Otherwise a residual of rounding noise fails the
            # step test and bisects towards a stale end of the bracket, far from the root.
            converged = jnp.abs(r) <= tolerance
            new = jnp.where(converged, x, new)
            return new, low, high, new - x, jnp.all(converged), iteration + 1

        # Start at x0 = min(x_trial, g^-1(x_trial / dt)): the residual is >= 0 there (either
        # dt g(x0) >= x_trial - x0 or x0 = x_trial), and near the root when the step is stiff,
        # where Newton from x_trial would shrink x by only a factor (1 - 1/q) per step.
        law, x_bound, _, k_frozen, strain_frozen, dt_frozen = frozen
        stiff = dt_frozen > 0
        absorbed = jnp.where(stiff, x_bound / jnp.where(stiff, dt_frozen, 1.0), jnp.inf)
        x0 = jnp.minimum(x_bound, law.flow_inverse(absorbed, k_frozen, strain_frozen))
        tolerance = 16 * jnp.finfo(x_bound.dtype).eps * (x_bound + k_frozen)
        start = (x0, jnp.zeros_like(x_trial), x0, 2 * x_bound, jnp.asarray(False), 0)
        # Up to `iterations`, ending early once every point has converged (it then stays).
        x = jax.lax.while_loop(
            lambda c: ~c[4] & (c[5] < self.iterations), safeguarded_newton, start
        )[0]
        r, dr = value_and_slope(self, x, x_trial, state.kappa, k, strain, dt)
        x = x - r / dr

        d_plastic = direction * dt * self.flow(x, k, strain) / self.E
        new_state = OverstressState(
            state.plastic_strain + d_plastic, state.kappa + jnp.abs(d_plastic)
        )
        return trial - self.E * d_plastic, new_state


class LinearOverstress(OverstressLaw):
    """g = x / tau: Sokolovsky's law (2.2.2) with a scalar `sigma0`, Malvern's (2.2.3) with a
    `StaticCurve`. At constant strain rate alpha after yield at t_y = sigma0/(E alpha), with
    the elastic-perfectly plastic curve, (2.2.4) gives
    sigma = sigma0 + E alpha tau (1 - exp(-(t - t_y)/tau)).

    The report's text after (2.2.3) cites "(2.1.22)" for (2.2.3).
    """

    tau: jnp.ndarray

    def __init__(self, E, sigma0, tau, *, elastic_unloading=False, iterations=4):
        self._init_common(E, sigma0, elastic_unloading, iterations, tau=tau)

    def flow(self, overstress, static_stress, strain):
        return overstress / self.tau

    def flow_inverse(self, rate, static_stress, strain):
        return self.tau * rate


class StrainDependentOverstress(OverstressLaw):
    """(2.2.5): g = mu(eps) x / tau with mu(eps) = eps0 / (eps0 - |eps|), eps0 < 0.

    The printed mu = eps0 / (eps - eps0) is -1 at eps = 0 and would make the law flow
    backwards; the sign is a misprint. mu = eps0/(eps0 - eps) is the form that gives mu(0) = 1
    and the report's own constant-rate solution: with the elastic-perfectly plastic curve and
    eps' = alpha, y = sigma - sigma0 solves dy/deps = E - m y / (eps - eps0), m = -eps0/(alpha
    tau), so y = E (eps_y - eps0)/(1 + m) [(eps - eps0)/(eps_y - eps0)
    - ((eps_y - eps0)/(eps - eps0))^m], asymptotically slope E / (1 - eps0/(alpha tau)),
    increasing with the rate alpha, as printed. |eps| makes mu symmetric in compression.
    """

    tau: jnp.ndarray
    eps0: jnp.ndarray

    def __init__(self, E, sigma0, tau, eps0, *, elastic_unloading=False, iterations=4):
        self._init_common(E, sigma0, elastic_unloading, iterations, tau=tau)
        self.eps0 = check("eps0", eps0, lambda x: (x < 0) & (x > -jnp.inf), "negative and finite")

    def flow(self, overstress, static_stress, strain):
        mu = self.eps0 / (self.eps0 - jnp.abs(strain))
        return mu * overstress / self.tau

    def flow_inverse(self, rate, static_stress, strain):
        return self.tau * rate * (self.eps0 - jnp.abs(strain)) / self.eps0


class _CharacteristicStressLaw(OverstressLaw):
    """A law whose flow is sigma_c/tau times a function of x/sigma_c (logarithmic, sinh)."""

    sigma_c: jnp.ndarray
    tau: jnp.ndarray

    def __init__(self, E, sigma0, sigma_c, tau, *, elastic_unloading=False, iterations=12):
        self._init_common(E, sigma0, elastic_unloading, iterations, sigma_c=sigma_c, tau=tau)


class LogOverstress(_CharacteristicStressLaw):
    """(2.2.6): g = sigma_c/tau (exp(x/sigma_c) - 1): an overstress logarithmic in the rate.

    The printed (2.2.6) has the exponent -(sigma - f)/sigma_c; the sign must be + for g > 0
    above the curve. Steady flow at constant rate alpha: x = sigma_c ln(1 + E alpha tau/sigma_c).
    With u = exp(-x/sigma_c) the law is linear, u' = 1/tau - beta u, beta = E alpha/sigma_c +
    1/tau, so after yield at constant rate (elastic-perfectly plastic curve, s = t - t_y)
    sigma = sigma0 - sigma_c ln{e^(-beta s) + (1 - e^(-beta s)) / (1 + E alpha tau/sigma_c)},
    which is (2.2.8) evaluated exactly. The printed constant-rate form multiplies by
    (1 + E alpha tau / sigma_c) where it must divide (its own asymptote needs the division).
    """

    def flow(self, overstress, static_stress, strain):
        return self.sigma_c / self.tau * jnp.expm1(overstress / self.sigma_c)

    def flow_inverse(self, rate, static_stress, strain):
        return self.sigma_c * jnp.log1p(self.tau * rate / self.sigma_c)


class SinhOverstress(_CharacteristicStressLaw):
    """g = sigma_c/tau sinh(x/sigma_c) (thermally activated dislocation motion, Dorn and Mote);
    written for x > 0 only, so that the law keeps the elastic range of 2.2."""

    def flow(self, overstress, static_stress, strain):
        return self.sigma_c / self.tau * jnp.sinh(overstress / self.sigma_c)

    def flow_inverse(self, rate, static_stress, strain):
        return self.sigma_c * jnp.arcsinh(self.tau * rate / self.sigma_c)


class CowperSymonds(OverstressLaw):
    """Plastic strain rate D <|sigma|/k - 1>^q sign(sigma), report (4.3.1) with D = 40 1/s,
    q = 5 (E eps' = sigma' + 40 E <sigma/sigma0 -+ 1>^5). With a hardening `StaticCurve` the
    ratio uses k at the start of the step. Steady flow at rate alpha:
    |sigma| = k (1 + (alpha/D)^(1/q))."""

    D: jnp.ndarray
    q: jnp.ndarray

    def __init__(self, E, sigma0, D, q, *, elastic_unloading=False, iterations=12):
        self._init_common(E, sigma0, elastic_unloading, iterations, D=D, q=q)

    def flow(self, overstress, static_stress, strain):
        ratio = _positive_part(overstress) / static_stress
        return jnp.where(overstress > 0, self.E * self.D * ratio**self.q, 0 * ratio)

    def flow_inverse(self, rate, static_stress, strain):
        return static_stress * (rate / (self.E * self.D)) ** (1 / self.q)


class QuadraticOverstress(OverstressLaw):
    """The uniaxial form of (2.2.12), g = (sigma^2 - k^2) / (tau |sigma|) = x (x + 2k) /
    (tau (x + k)), for an incompressible material (E = 3G): the law that the hereditary law
    (2.2.15) with the single relaxation time tau/2 reduces to."""

    tau: jnp.ndarray

    def __init__(self, E, sigma0, tau, *, elastic_unloading=False, iterations=12):
        self._init_common(E, sigma0, elastic_unloading, iterations, tau=tau)

    def flow(self, overstress, static_stress, strain):
        return (
            overstress
            * (overstress + 2 * static_stress)
            / (self.tau * (overstress + static_stress))
        )


class GilmanJohnston(OverstressLaw):
    """Plastic strain rate rate0 exp(-D/|sigma|) sign(sigma): no elastic range (k = 0).

    The report writes g = (1/tau) exp(-D/sigma), which is not a stress rate; here g = E rate0
    exp(-D/|sigma|) with rate0 a strain rate and D a drag stress.
    """

    rate0: jnp.ndarray
    D: jnp.ndarray

    def __init__(self, E, rate0, D, *, elastic_unloading=False, iterations=12):
        self._init_common(E, None, elastic_unloading, iterations, rate0=rate0, D=D)

    def static_stress(self, kappa):
        return jnp.zeros_like(kappa)

    def flow(self, overstress, static_stress, strain):
        activation = jnp.exp(-self.D / _positive_part(overstress))
        return jnp.where(overstress > 0, self.E * self.rate0 * activation, 0 * activation)
