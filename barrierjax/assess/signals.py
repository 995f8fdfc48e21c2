"""A sampled record as a function of time: the piecewise-linear interpolant of uniformly
spaced samples, its exact first and second integrals, and values between the samples.

The occupant-risk models integrate the vehicle's acceleration once for the occupant's
velocity relative to the vehicle and twice for its displacement. Taking the acceleration
linear between samples makes the velocity piecewise quadratic and the displacement piecewise
cubic, so that a cubic Hermite interpolant through the samples of the displacement and its
slope (the velocity) is the displacement exactly, and a crossing time found on it is exact for
the sampled record. Outside the record the acceleration is zero: before it the vehicle is
unaccelerated, after it the vehicle moves on freely (a model's history ends at rest or at exit).
Functions take one record (1-D arrays); `jax.vmap` batches them. A record padded past its
end (so that records of nearby lengths share one compiled program) is read through its
`end` (the last real sample's time) and `continued` past it.
"""

import math

import jax
import jax.numpy as jnp

__all__ = [
    "continued",
    "cumulative_integrals",
    "first_crossing",
    "first_crossings",
    "first_impact",
    "hermite_at",
    "integral_at",
    "integral_on_grid",
    "max_window_mean",
    "safe_norm",
]


def cumulative_integrals(a, dt):
    """(v, d): the integrals of the piecewise-linear `a` from the first sample to each
    sample, once (trapezoids) and twice (exact for the linear pieces)."""
    v_steps = 0.5 * dt * (a[1:] + a[:-1])
    v = jnp.concatenate([jnp.zeros_like(a[:1]), jnp.cumsum(v_steps)])
    d_steps = dt * v[:-1] + dt**2 * (2.0 * a[:-1] + a[1:]) / 6.0
    d = jnp.concatenate([jnp.zeros_like(a[:1]), jnp.cumsum(d_steps)])
    return v, d


def _interval(tau, dt, n: int):
    """The sample interval [i, i + 1] that holds `tau` (s from the first sample; clipped to
    the record) and the offset into it, clipped to [0, dt]."""
    i = jnp.clip(jnp.floor(jax.lax.stop_gradient(tau) / dt).astype(int), 0, n - 2)
    return i, jnp.clip(tau - i.astype(tau.dtype) * dt, 0.0, dt)


def integral_at(a, dt, end=None):
    """The function tau -> integral of `a` from the first sample to `tau` (s after it), with
    a = 0 outside the record, which ends at `end` (s; default its last sample).
    Differentiable in `a` and `tau`."""
    return _integral(a, cumulative_integrals(a, dt)[0], dt, end)


def _integral(a, v, dt, end):
    """`integral_at`'s function, given `a`'s integral at the samples `v`."""

    def integral(tau):
        i, s = _interval(tau if end is None else jnp.minimum(tau, end), dt, a.shape[0])
        inside = v[i] + a[i] * s + 0.5 * (a[i + 1] - a[i]) * s**2 / dt
        return jnp.where(tau <= 0.0, 0.0, inside)

    return integral


def _shifted(x, m: int):
    """y[k] = x[k + m] where that is a sample of `x` (its first axis), 0 elsewhere: a pad
    and a slice (the shift is static), no gather."""
    n = x.shape[0]
    padded = jnp.pad(x, [(max(0, -m), max(0, m))] + [(0, 0)] * (x.ndim - 1))
    return padded[max(0, m) : max(0, m) + n]


def integral_on_grid(a, dt, shift: float, end=None):
    """`integral_at(a, dt, end)` at every sample's time plus `shift` (s, a Python number):
    the cumulative integral read at a fixed offset from each sample, by shifting it rather
    than locating each time in the record, a gather a time (the ridedown's windows and the
    1998 ASI's average: a batch of records 12 % faster in the 2010 edition and 42 % in the
    1998, the robust sizing's crash tests and their derivatives a third faster;
    benchmarks/README.md, "Thirtieth pass")."""
    if not isinstance(shift, (int, float)) or not math.isfinite(shift):
        raise ValueError(f"shift must be a finite Python number (s); got {shift!r}")
    n = a.shape[0]
    v, _ = cumulative_integrals(a, dt)
    samples = shift / dt
    on_sample = abs(samples - round(samples)) < 1e-9  # (0.01 / 1e-4 is 100 to rounding)
    whole = round(samples) if on_sample else math.floor(samples)
    s = 0.0 if on_sample else shift - whole * dt  # into the sample interval, [0, dt)
    # (Only the times within the record, 0 < t < stop, are read from the shifted samples:
    # their interval [k + whole, k + whole + 1] then lies in it.)
    v0 = _shifted(v, whole)
    if s > 0.0:
        a0 = _shifted(a, whole)
        v0 = v0 + a0 * s + 0.5 * (_shifted(a, whole + 1) - a0) * s**2 / dt
    t = jnp.arange(n, dtype=a.dtype) * dt + shift
    stop = (n - 1) * dt if end is None else jnp.minimum(end, (n - 1) * dt)
    after = jnp.where(t >= stop, _integral(a, v, dt, end)(jnp.asarray(stop, a.dtype)), v0)
    return jnp.where(t <= 0.0, 0.0, after)


def hermite_at(position, velocity, dt):
    """The function tau -> (position, velocity) of the cubic Hermite interpolant of samples
    `position` with slopes `velocity` (s after the first sample; axis 0 is time, trailing
    axes are components), continued in a straight line at the last velocity after the
    record."""
    n = position.shape[0]

    def at(tau):
        i, s = _interval(tau, dt, n)
        u = s / dt
        p0, p1, v0, v1 = position[i], position[i + 1], dt * velocity[i], dt * velocity[i + 1]
        h00, h10, h01, h11 = (
            2 * u**3 - 3 * u**2 + 1,
            u**3 - 2 * u**2 + u,
            -2 * u**3 + 3 * u**2,
            u**3 - u**2,
        )
        dh00, dh10, dh01, dh11 = (
            6 * u**2 - 6 * u,
            3 * u**2 - 4 * u + 1,
            -6 * u**2 + 6 * u,
            3 * u**2 - 2 * u,
        )
        p = h00 * p0 + h10 * v0 + h01 * p1 + h11 * v1
        dp = (dh00 * p0 + dh10 * v0 + dh01 * p1 + dh11 * v1) / dt
        beyond = jnp.maximum(tau - (n - 1) * dt, 0.0)
        return p + beyond * velocity[-1], dp

    return at


def continued(position, velocity, n_real, dt):
    """`position` and `velocity` (axis 0 time) with the samples from `n_real` on replaced
    by the straight line from sample `n_real` - 1 at its velocity: a padded record's path,
    continued past its end as the path runs on straight after a record."""
    k = jnp.arange(position.shape[0], dtype=jnp.result_type(n_real))
    last = n_real - 1
    real = (k < n_real).reshape(-1, *(1,) * (position.ndim - 1))
    elapsed = ((k - last).astype(position.dtype) * dt).reshape(real.shape)
    line = position[last] + elapsed * velocity[last]
    return jnp.where(real, position, line), jnp.where(real, velocity, velocity[last])


def first_crossings(position, velocity, limits, dt, n_real=None):
    """`first_crossing` of each component: position and velocity (n, k), limits (k,)."""
    crossing = lambda p, v, limit: first_crossing(p, v, limit, dt, n_real=n_real)
    return jax.vmap(crossing, in_axes=(1, 1, 0))(position, velocity, limits)


def first_crossing(position, velocity, limit, dt, newton_steps: int = 6, n_real=None):
    """When the 1-D path (`position` samples, slopes `velocity`, on `hermite_at`'s
    interpolant) first reaches |position| = `limit`: (time from the first sample, whether
    within the record: its first `n_real` samples, default all). Past the record the path
    runs on straight; a path that never reaches the limit gives +inf.

    The crossing's sample interval is found by comparison (piecewise constant), the time
    in it by Newton's method on the interpolant; the last Newton step is taken with the
    gradient, so that d(time)/d(input) = -d(residual)/d(input) / d(residual)/d(time),
    exact by the implicit function theorem (a sample index would give zero)."""
    n = position.shape[0]
    path = hermite_at(position, velocity, dt)
    reached = jnp.abs(position) >= limit
    k = jnp.argmax(reached)
    in_record = reached[k]
    previous = jnp.maximum(k - 1, 0)
    k_time, previous_time = k.astype(position.dtype) * dt, previous.astype(position.dtype) * dt
    end = (n - 1) * dt
    # In the record: between samples k - 1 and k, from the chord; past it: on the line.
    sign = jnp.where(in_record, jnp.sign(position[k]), jnp.sign(velocity[-1]))
    p0, p1 = position[previous], position[k]
    chord = previous_time + (sign * limit - p0) / jnp.where(p1 == p0, 1.0, p1 - p0) * dt
    moving_out = sign * velocity[-1] > 0.0
    line = end + (sign * limit - position[-1]) / jnp.where(moving_out, velocity[-1], 1.0)
    never = ~in_record & ~moving_out
    lower = jnp.where(in_record, previous_time, end)
    upper = jnp.where(in_record, k_time, jnp.inf)
    guess = jnp.where(in_record, chord, jnp.where(never, end, line))

    def newton(tau):
        p, v = path(tau)
        step = (sign * p - limit) / jnp.where(v == 0.0, 1.0, sign * v)
        return tau - step

    def iterate(_, tau):
        return jnp.clip(newton(tau), lower, jnp.minimum(upper, 1e30))

    lower, upper = jax.lax.stop_gradient((lower, upper))
    tau = jax.lax.fori_loop(0, newton_steps, iterate, jax.lax.stop_gradient(guess))
    tau = newton(jax.lax.stop_gradient(tau))
    if n_real is not None:  # (a padded record: a crossing on its padding is past the end)
        in_record = in_record & (k < jnp.asarray(n_real).astype(k.dtype))
    return jnp.where(never, jnp.inf, tau), in_record


def first_impact(position, velocity, limits, dt, n_real=None):
    """When a 2-D path (samples `position`, `velocity`, (n, 2)) first reaches
    |component k| = `limits[k]` on either axis: (time, the velocity then (2,), whether
    within the record, its first `n_real` samples); +inf and a zero velocity without an
    impact."""
    (t_x, t_y), (in_x, in_y) = first_crossings(position, velocity, limits, dt, n_real)
    t_hit = jnp.minimum(t_x, t_y)
    finite = jnp.isfinite(t_hit)
    _, at_hit = hermite_at(position, velocity, dt)(jnp.where(finite, t_hit, 0.0))
    return t_hit, jnp.where(finite, at_hit, 0.0), jnp.where(t_x <= t_y, in_x, in_y)


def max_window_mean(a, dt, window: float, t_from, end=None):
    """The largest |mean| of the piecewise-linear `a` over `window` seconds among the
    windows that start at `t_from` or at a later sample (a = 0 past the record, which ends
    at `end`: `integral_at`); 0 when `t_from` is +inf. The mean over a window starting at
    `t_from` makes it continuous and differentiable in `t_from`."""
    integral = integral_at(a, dt, end)
    finite = jnp.isfinite(t_from)
    finite_from = jnp.where(finite, t_from, 0.0)
    at_samples = integral_on_grid(a, dt, window, end) - integral_on_grid(a, dt, 0.0, end)
    at_from = integral(finite_from + window) - integral(finite_from)
    after = (jnp.arange(a.shape[0], dtype=a.dtype) * dt >= finite_from) & finite
    from_samples = jnp.max(jnp.abs(jnp.where(after, at_samples, 0.0)))
    return jnp.maximum(from_samples, jnp.abs(jnp.where(finite, at_from, 0.0))) / window


def safe_norm(x, axis=-1):
    """The Euclidean norm along `axis`, with a zero (not NaN) gradient at zero."""
    squares = jnp.sum(x**2, axis=axis)
    positive = squares > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squares, 1.0)), 0.0)
