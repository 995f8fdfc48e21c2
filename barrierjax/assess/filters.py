"""Signal conditioning of crash-test records: the phaseless Butterworth low-pass of SAE J211-1
(channel frequency classes, CFC) and of EN 1317-1's acceleration severity index, and moving
averages.

Every filter here is the 2-pole Butterworth low-pass of SAE J211-1 (Mar 1995) Appendix C,
Equation C1, by the bilinear transform with prewarping (wa = tan(wd T / 2)),

    Y[n] = a0 X[n] + a1 X[n-1] + a2 X[n-2] + b1 Y[n-1] + b2 Y[n-2],

run forward and then backward over the record: a 4-pole filter without phase shift, whose
gain is the square of one pass's. What differs between the standards is the design
frequency f_d of one pass (and the padding of the record's ends):

- SAE J211-1 / ISO 6487 channel frequency class CFC: the combined gain is -3 dB at
  F_N = 5/3 CFC (J211-1 Table 1: CFC 60, 180, 600, 1000 have F_N 100, 300, 1000, 1650 Hz).
  Two passes of 1 / (1 + (f/f_d)^4) lose 3 dB where (f/f_d)^4 = sqrt(2) - 1, so
  f_d = F_N / (sqrt(2) - 1)^(1/4) = 1.2465 F_N = 2.0775 CFC: J211-1's "wd = 2 pi CFC 2.0775"
  (`J211_DESIGN_FACTOR`). ISO 6487 rounds 1.2465 to 1.25 (2.0833 CFC); implementations that
  write 2 pi CFC 1.25 5/3 follow ISO. `cfc_filter` takes J211's factor; its response is
  checked against J211's corridor in the tests.
- EN 1317-1:2010 ASI: "a four-pole phaseless Butterworth low-pass filter with a cut-off
  frequency of 13 Hz". Read here as J211's construction (two 2-pole passes) with the
  one-pass cut-off f_d = 13 Hz, as `scipy.signal.butter(2, 13, fs=...)` with `filtfilt`
  gives it: -6 dB at 13 Hz. (A CFC-13 reading, f_d = 2.0775 x 13 Hz, passes more.)

The ends: J211-1 Appendix C extends a record by point reflection about each end value before
filtering (at least 10 ms), and discards the extension after (`phaseless_lowpass`,
`cfc_filter`; each pass starts at rest on its first input value, the steady state of a
constant input, as `scipy.signal.filtfilt` starts); EN 1317-1:2010 pads the record by 0.5 s
at each end (here with zeros: the vehicle unaccelerated before and after), where the two
passes are a time-invariant filter applied by FFT (`zero_padded_lowpass`). All functions are pure JAX, differentiable, along the last
axis of `x`.
"""

import math

import jax
import jax.numpy as jnp
import numpy as np

from . import signals

__all__ = [
    "ASI_CUTOFF",
    "CFC_PAD_SECONDS",
    "ISO6487_DESIGN_FACTOR",
    "J211_DESIGN_FACTOR",
    "butterworth_coefficients",
    "cfc_filter",
    "filter_gain",
    "moving_average",
    "phaseless_lowpass",
    "zero_padded_lowpass",
]

J211_DESIGN_FACTOR = 5.0 / 3.0 / (math.sqrt(2.0) - 1.0) ** 0.25  # 2.0775: f_d / CFC
ISO6487_DESIGN_FACTOR = 1.25 * 5.0 / 3.0  # 2.0833: ISO 6487's rounding of the same
CFC_PAD_SECONDS = 0.010  # J211-1 Appendix C: extend each end by at least 10 ms
ASI_CUTOFF = 13.0  # Hz, EN 1317-1:2010 clause on ASI


def butterworth_coefficients(f_design, dt, xp=jnp):
    """(a0, a1, a2, b1, b2) of one 2-pole pass (SAE J211-1 Appendix C, Equation C1) with
    design (-3 dB per pass) frequency `f_design` (Hz) at the sampling step `dt` (s), in
    the array module `xp` (jax.numpy, or numpy for concrete values)."""
    wa = xp.tan(xp.pi * f_design * dt)
    denominator = 1.0 + math.sqrt(2.0) * wa + wa**2
    a0 = wa**2 / denominator
    b1 = -2.0 * (wa**2 - 1.0) / denominator
    b2 = (-1.0 + math.sqrt(2.0) * wa - wa**2) / denominator
    return a0, 2.0 * a0, a0, b1, b2


def _one_pass(x, coefficients):
    """Equation C1 along the last axis, from rest at x[..., 0]."""
    a0, a1, a2, b1, b2 = coefficients

    def step(carry, x_n):
        x1, x2, y1, y2 = carry
        y_n = a0 * x_n + a1 * x1 + a2 * x2 + b1 * y1 + b2 * y2
        return (x_n, x1, y_n, y1), y_n

    first = x[..., 0]
    _, y = jax.lax.scan(step, (first, first, first, first), jnp.moveaxis(x, -1, 0), unroll=8)
    return jnp.moveaxis(y, 0, -1)


def _reflected(x, n_pad: int):
    """`x` extended at each end by `n_pad` samples of point reflection about the end
    values (J211-1 Appendix C)."""
    front = 2.0 * x[..., :1] - x[..., n_pad:0:-1]
    back = 2.0 * x[..., -1:] - x[..., -2 : -n_pad - 2 : -1]
    return jnp.concatenate([front, x, back], axis=-1)


def _pad_samples(dt, pad_seconds: float) -> int:
    return math.ceil(pad_seconds / float(dt) - 1e-9)


def phaseless_lowpass(x, dt, f_design, *, pad_seconds: float = CFC_PAD_SECONDS):
    """Two passes of the 2-pole Butterworth low-pass, forward then backward, with design
    frequency `f_design` (Hz, one pass's -3 dB point) at sampling step `dt` (s) along the
    last axis of `x`, each from rest on its first input. The record is extended by
    `pad_seconds` of point reflection at each end (J211-1) and the extension discarded.
    `dt` must be concrete (it fixes the padding's sample count); `x` and `f_design` may be
    traced."""
    x = jnp.asarray(x)
    if x.shape[-1] < 2:
        raise ValueError(f"x must have at least 2 samples to filter; got {x.shape[-1]}")
    n_pad = min(_pad_samples(dt, pad_seconds), x.shape[-1] - 1)  # within the other end
    coefficients = butterworth_coefficients(f_design, dt)
    padded = _reflected(x, n_pad) if n_pad else x
    forward = _one_pass(padded, coefficients)
    both = jnp.flip(_one_pass(jnp.flip(forward, -1), coefficients), -1)
    return both[..., n_pad : n_pad + x.shape[-1]]


def cfc_filter(x, dt, cfc, *, factor: float = J211_DESIGN_FACTOR):
    """SAE J211-1 (Mar 1995) Appendix C channel filter of class `cfc` (60, 180, 600, 1000)
    along the last axis of `x` sampled at `dt` seconds: two passes with f_d = `factor` x
    CFC (J211's 2.0775; `ISO6487_DESIGN_FACTOR` for ISO 6487's 2.0833), the record's ends
    extended by 10 ms of point reflection. Gain -3 dB at 5/3 CFC, inside J211's corridor
    (tests/test_assess_filters.py)."""
    return phaseless_lowpass(x, dt, factor * cfc)


def zero_padded_lowpass(x, dt, f_design, *, pad_seconds: float):
    """The two passes of `phaseless_lowpass` on the record padded by `pad_seconds` of
    zeros at each end (EN 1317-1:2010's ASI), computed in the frequency domain: on a
    zero-padded record the two passes from rest are the linear, time-invariant filter whose
    gain is `filter_gain` (|H|^2, real: no phase), applied here by FFT to the padded record
    (its length rounded up to a product of 2, 3 and 5 with further zeros). Equal to the recursion
    to the rounding while the padding is long against the filter's decay (0.5 s against
    1 / 13 Hz for the ASI: e^-29; tests/test_assess.py checks it against scipy's filtfilt),
    and without its per-sample sequential loop."""
    x = jnp.asarray(x)
    n = x.shape[-1]
    n_pad = _pad_samples(dt, pad_seconds)
    length = _fast_length(n + 2 * n_pad)
    frequencies = np.fft.rfftfreq(length, dt)
    spectrum = jnp.fft.rfft(x, n=length, axis=-1)
    spectrum = spectrum * jnp.asarray(filter_gain(frequencies, dt, f_design), dtype=spectrum.dtype)
    return jnp.fft.irfft(spectrum, n=length, axis=-1)[..., :n]


def _fast_length(n: int) -> int:
    """The smallest 2^a 3^b 5^c >= n: an FFT length without large prime factors."""
    best = 1 << math.ceil(math.log2(n))
    power5 = 1
    while power5 < best:
        power35 = power5
        while power35 < best:
            length = power35 << max(0, math.ceil(math.log2(n / power35)))
            best = min(best, length)
            power35 *= 3
        power5 *= 5
    return best


def filter_gain(f, dt, f_design):
    """The steady-state gain (ratio, not dB) of `phaseless_lowpass` at frequency `f` (Hz):
    the square of one pass's |H(exp(i 2 pi f dt))|, exact for the digital filter."""
    # In NumPy: concrete even where called under jit, and no JAX program to compile each
    # time a record's length is new (six of them, with `jax.ensure_compile_time_eval`).
    a0, a1, a2, b1, b2 = butterworth_coefficients(float(f_design), dt, xp=np)
    z = np.exp(-2j * np.pi * np.asarray(f, dtype=float) * dt)
    h = (a0 + a1 * z + a2 * z**2) / (1.0 - b1 * z - b2 * z**2)
    return np.abs(h) ** 2


def moving_average(x, dt, window: float, end=None):
    """The centred moving average over `window` seconds of the piecewise-linear interpolant
    of `x` (samples along the last axis at step `dt`), at every sample, with x = 0 outside
    the record (which ends at `end`, default its last sample): EN 1317-1:1998's 50 ms
    average of the ASI. Exact integrals."""

    def one(x):
        half = 0.5 * window
        later, earlier = (signals.integral_on_grid(x, dt, h, end) for h in (half, -half))
        return (later - earlier) / window

    return jnp.vectorize(one, signature="(n)->(n)")(jnp.asarray(x))
