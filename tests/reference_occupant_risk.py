"""Independent reference implementation of crash-test occupant-risk metrics.

Plain numpy with explicit Python loops (no scipy, no jax), written from the standards' text
as far as public sources expose it, to test `barrierjax`'s own implementation against. It
deliberately shares no code with the package.

Units are SI throughout: time in s, acceleration in m/s^2, velocity in m/s, angle in rad,
yaw rate in rad/s. Axes are vehicle-fixed, SAE J211 / ISO 6487 sense: x forward, y left,
z up; a frontal impact gives a negative ``ax``. ``G0 = 9.80665 m/s^2`` (standard gravity)
converts the g-valued limits.

Sources, and what each was used for (the standards themselves are paywalled; where only a
secondary source was available this is said at the clause):

* SAE J211-1 (MAR95), Appendix C, "Digital filtering": the two-pole difference equation
  (its Equation C1), the constants a0..b2 and the design frequency
  ``wd = 2*pi*CFC*2.0775``; run forward then backward for the 4-pole phaseless filter.
  Transcribed identically by pyavia ``J211_2pole`` ("exact algorithm of SAE J211-1
  Appendix C"), D. C. Hartlen's ``SaeJ211Filter.m``, the NI DIAdem forum thread
  "Replicating CFC filters in script" (ni.lithium.com, 2025), and the FlexPro
  "CFC Filter Calculation" page (weisang.com), which also states that ISO 6487 differs
  only in ``wd``.
* J211-1 Appendix C start-up: the DIAdem ``ChnCFCFiltCalc`` page paraphrases it: when the
  pre- and post-event history is unknown, copy at least 10 ms of data next to each end and
  point-reflect it ("rotary reflection") about the end point ("EndPoints") or about the
  origin ("ZeroMagnitude"), filter the extended record, then drop the added points.
* ISO 6487 (as reproduced in UN ECE R94 Annex 8, table "CFC / FL / FH / FN / logarithmic
  scale"): the response corridor letters a..g and the FL/FH/FN frequencies per CFC. ISO
  6487:2015's contents list an informative Annex A, "Example of Butterworth four-pole
  phaseless digital filter (including initial conditions treatment) algorithm"; its text
  was not readable. A public ISO-MME channel reader's "ISO-6487" method uses
  ``wd = 2*pi*CFC*1.25*5/3``, pads max(10 ms, 100 samples) by point reflection about the
  end samples and starts each pass from the mean of the first 10 samples.
* EN 1317-1:2010 / :1998 ASI, THIV, PHD: the Oasys T/HIS 22.1 manual pages "Acceleration
  Severity Index" and "Theoretical Head Impact Velocity & Post Impact Head Deceleration",
  and NI DIAdem's ``ChnASICalc``, ``ChnTHIVCalc``, ``ChnPHDCalc`` and ``ChnOIVCalc``
  pages (EN 1317-2 clause 5.6 named there for the CFC 180 pre-filter).
* NCHRP Report 350 / MASH flail-space model (Michie 1981): OIV at 0.6 m longitudinal or
  0.3 m lateral occupant travel, ORA the largest 10 ms average after occupant impact; as
  summarised in Gabauer & Gabler (PMC3217488) and the FHWA/TTI TRAP 2.1 report
  (Bligh et al., 2000, report 472540-F), whose body text was not readable here.

Nothing in this module is tuned to agree with barrierjax; where the sources disagree the
choice is a keyword argument and the docstring says which variant is the default.
"""

from __future__ import annotations

import math

import numpy as np

G0 = 9.80665
"""Standard gravity, m/s^2 (the g of the EN 1317 ASI limits and of the MASH g limits)."""

J211_FACTOR = 2.0775
"""SAE J211-1 Appendix C design-frequency factor: ``wd = 2*pi*CFC*J211_FACTOR``.

Derivation. The channel's -3 dB frequency is ``FN = (5/3)*CFC`` (CFC 60 -> 100 Hz,
180 -> 300 Hz, 600 -> 1000 Hz, 1000 -> ~1650 Hz). One pass of a 2-pole Butterworth with
design frequency ``fd`` has ``|H|^2 = 1/(1 + (f/fd)^4)``; forward plus backward squares
it, ``|H_4| = 1/(1 + (f/fd)^4)``, which is -3 dB where ``(f/fd)^4 = sqrt(2) - 1``. So
``fd = FN / (sqrt(2) - 1)**0.25 = 1.24650*FN = 2.07750*CFC``. ISO 6487 rounds 1.2465 to
1.25 and writes ``wd = 2*pi*CFC*1.25*5/3`` (factor 2.0833); see `ISO6487_FACTOR`.
The ``sin/cos`` (= tan) in ``wa`` pre-warps the bilinear transform so that one digital pass
is exactly -3.0103 dB at ``fd`` (the cascade exactly -6.02 dB there); FN itself then sits
at -3 dB only to the bilinear warping of ``FN/fd`` (negligible at ``fs >> FN``).
"""

ISO6487_FACTOR = 1.25 * 5.0 / 3.0
"""ISO 6487 Annex A design-frequency factor (2.08333...), see `J211_FACTOR`."""

FLAIL_DX = 0.6
"""Flail-space / THIV longitudinal distance, m (NCHRP 350, MASH; EN 1317-1 Dx)."""

FLAIL_DY = 0.3
"""Flail-space / THIV lateral distance, m (NCHRP 350, MASH; EN 1317-1 Dy)."""

ASI_LIMITS_G = (12.0, 9.0, 10.0)
"""EN 1317-1 ASI limit accelerations (x, y, z) in g."""


# ---------------------------------------------------------------------------------------
# Filtering (SAE J211-1 Appendix C, ISO 6487 Annex A)
# ---------------------------------------------------------------------------------------


def two_pole_coefficients(f_design, dt):
    """Constants of the SAE J211-1 Appendix C 2-pole low-pass, for design frequency ``f_design``.

    J211-1 Appendix C (as transcribed by the sources in the module docstring)::

        wd = 2*pi*f_design          (J211 writes wd = 2*pi*CFC*2.0775)
        wa = sin(wd*T/2) / cos(wd*T/2)
        a0 = wa^2 / (1 + sqrt(2)*wa + wa^2);  a1 = 2*a0;  a2 = a0
        b1 = -2*(wa^2 - 1) / (1 + sqrt(2)*wa + wa^2)
        b2 = (-1 + sqrt(2)*wa - wa^2) / (1 + sqrt(2)*wa + wa^2)

    Returns ``(a0, a1, a2, b1, b2)``. Their DC gain ``(a0+a1+a2)/(1-b1-b2)`` is exactly 1.
    """
    wd = 2.0 * math.pi * float(f_design)
    wa = math.sin(wd * dt / 2.0) / math.cos(wd * dt / 2.0)
    den = 1.0 + math.sqrt(2.0) * wa + wa * wa
    a0 = wa * wa / den
    a1 = 2.0 * a0
    a2 = a0
    b1 = -2.0 * (wa * wa - 1.0) / den
    b2 = (-1.0 + math.sqrt(2.0) * wa - wa * wa) / den
    return a0, a1, a2, b1, b2


def two_pole_pass(x, coefficients):
    """One forward pass of J211-1 Equation C1, sample by sample.

    ``Y[n] = a0*X[n] + a1*X[n-1] + a2*X[n-2] + b1*Y[n-1] + b2*Y[n-2]``, started with
    ``Y[0] = X[0]`` and ``Y[1] = X[1]`` (the start pyavia's transcription of Appendix C
    uses; with a constant input it makes the output exactly that constant).
    """
    a0, a1, a2, b1, b2 = coefficients
    xs = [float(v) for v in np.asarray(x, dtype=float).ravel()]
    n = len(xs)
    ys = [0.0] * n
    if n == 0:
        return np.zeros(0)
    ys[0] = xs[0]
    if n > 1:
        ys[1] = xs[1]
    for i in range(2, n):
        ys[i] = a0 * xs[i] + a1 * xs[i - 1] + a2 * xs[i - 2] + b1 * ys[i - 1] + b2 * ys[i - 2]
    return np.array(ys)


def pad_record(x, n_pad, mode):
    """Extend a record at both ends by ``n_pad`` samples; returns ``(padded, n_front)``.

    Modes:

    * ``"endpoint"``: point ("rotary") reflection about the end samples,
      ``x[-k] = 2*x[0] - x[k]`` and ``x[N-1+k] = 2*x[N-1] - x[N-1-k]`` (J211-1 Appendix C
      start-up as DIAdem's "EndPoints"; a public "ISO-6487" implementation does the same);
      ``n_pad`` is capped at ``N - 1``.
    * ``"origin"``: point reflection about zero, ``x[-k] = -x[k]`` (DIAdem "ZeroMagnitude").
    * ``"zero"``: zeros (a vehicle at rest, or coasting, before and after the impact).
    * ``"none"``: no padding.
    """
    xs = [float(v) for v in np.asarray(x, dtype=float).ravel()]
    n = len(xs)
    if mode == "none" or n_pad <= 0 or n == 0:
        return np.array(xs), 0
    if mode in ("endpoint", "origin"):
        n_pad = min(int(n_pad), n - 1)
    if n_pad <= 0:
        return np.array(xs), 0
    front = [0.0] * n_pad
    back = [0.0] * n_pad
    for k in range(1, n_pad + 1):
        if mode == "endpoint":
            front[n_pad - k] = 2.0 * xs[0] - xs[k]
            back[k - 1] = 2.0 * xs[n - 1] - xs[n - 1 - k]
        elif mode == "origin":
            front[n_pad - k] = -xs[k]
            back[k - 1] = -xs[n - 1 - k]
        elif mode == "zero":
            pass
        else:
            raise ValueError(f"unknown padding mode {mode!r}")
    return np.array(front + xs + back), n_pad


def phaseless_filter(x, dt, f_design, *, pad="endpoint", pad_s=0.010):
    """2-pole J211 low-pass forward, then backward (4-pole, zero phase), with padding.

    ``f_design`` is the per-pass design frequency (``fd``); the cascade is -6.02 dB there.
    """
    coefficients = two_pole_coefficients(f_design, dt)
    n_pad = int(round(pad_s / dt)) if pad != "none" else 0
    padded, n_front = pad_record(x, n_pad, pad)
    forward = two_pole_pass(padded, coefficients)
    backward = two_pole_pass(forward[::-1], coefficients)[::-1]
    n = len(np.asarray(x).ravel())
    return backward[n_front : n_front + n].copy()


def cfc_filter(x, dt, cfc, *, factor=J211_FACTOR, pad="endpoint", pad_s=0.010):
    """SAE J211-1 Appendix C CFC filter: 2-pole Butterworth forward then backward.

    ``wd = 2*pi*CFC*factor`` with ``factor = 2.0775`` (J211; derivation at `J211_FACTOR`)
    or `ISO6487_FACTOR` (2.0833). The start-up handling J211-1 Appendix C suggests when the
    record has no pre-/post-event history is the default: extend each end by 10 ms of
    point-reflected data (``pad="endpoint"``; ``"origin"`` and ``"none"`` also available,
    see `pad_record`), filter, and discard the extension. ``dt`` must be the uniform
    sample period in seconds.
    """
    return phaseless_filter(x, dt, factor * float(cfc), pad=pad, pad_s=pad_s)


def butterworth_phaseless(x, dt, f_cut, *, pad="endpoint", pad_s=0.010):
    """4-pole phaseless Butterworth low-pass (2-pole forward + backward) with cut-off ``f_cut``.

    ``f_cut`` is the per-pass -3 dB (design) frequency, so the phaseless cascade is
    -6.02 dB at ``f_cut`` (two passes of -3.01 dB); this is the reading of EN 1317-1:2010's
    "four-pole phaseless Butterworth filter with a 13 Hz cut-off frequency" for the ASI
    (T/HIS manual wording). Some tools instead run the J211 CFC algorithm with CFC = 13
    (DIAdem ``ChnASICalc`` "CFC filter with CFR=13 Hz"); that is
    ``cfc_filter(x, dt, 13)``, design frequency 27.0 Hz and -3 dB at 21.7 Hz.
    The difference equation is J211-1 Appendix C's with ``wd = 2*pi*f_cut``.
    Padding: J211's 10 ms point reflection by default; for the ASI see `asi`.
    """
    return phaseless_filter(x, dt, f_cut, pad=pad, pad_s=pad_s)


def cfc_corridor(cfc):
    """ISO 6487 / SAE J211-1 data-channel frequency-response corridor for a CFC.

    The standard's table (ISO 6487; reproduced in UN ECE R94 Annex 8), logarithmic scale:

    ====  =====  =====  =====
    CFC   FL Hz  FH Hz  FN Hz
    ====  =====  =====  =====
    1000  <=0.1  1000   1650
    600   <=0.1  600    1000
    180   <=0.1  180    300
    60    <=0.1  60     100
    ====  =====  =====  =====

    a = +-0.5 dB; b = +0.5; -1 dB; c = +0.5; -4 dB; d = -9 dB/octave; e = -24 dB/octave;
    f = infinity; g = -30 dB.

    Geometry used here (the figure itself was not readable, so beyond FN this is an
    interpretation, stated so a failure can be judged):

    * FL <= f < FH: lower -0.5 dB, upper +0.5 dB (a);
    * f = FH: lower -1 dB (b); FH < f <= FN: lower straight on log f from -1 dB at FH to
      -4 dB at FN (b -> c); upper +0.5 dB up to FN;
    * f > FN: lower unbounded (f = infinite slope); upper falls at d = -9 dB/octave from
      +0.5 dB at FN, but not below the stop-band level (g = -30 dB for CFC 60/180; -40 dB
      for CFC 600/1000, the stop-band attenuation DIAdem and FlexPro list). Where the
      standard's figure places e = -24 dB/octave was not confirmed; using only d makes the
      upper bound here looser than or equal to a d-then-e bound.

    Returns a dict with ``cfc, FL, FH, FN, table`` (the letters) and ``f, lower, upper``:
    breakpoint frequencies with the bounds there (``-inf`` for unbounded); evaluate
    between breakpoints with `corridor_bounds`.
    """
    cfc = int(cfc)
    rows = {
        1000: (0.1, 1000.0, 1650.0),
        600: (0.1, 600.0, 1000.0),
        180: (0.1, 180.0, 300.0),
        60: (0.1, 60.0, 100.0),
    }
    if cfc not in rows:
        raise ValueError(f"CFC {cfc} is not in the ISO 6487 / J211 table (1000, 600, 180, 60)")
    fl, fh, fn = rows[cfc]
    floor = -30.0 if cfc in (60, 180) else -40.0
    f_floor = fn * 2.0 ** ((0.5 - floor) / 9.0)
    table = {
        "a": (-0.5, 0.5),
        "b": (-1.0, 0.5),
        "c": (-4.0, 0.5),
        "d_db_per_octave": -9.0,
        "e_db_per_octave": -24.0,
        "f": -math.inf,
        "g_db": -30.0,
    }
    f = np.array([fl, fh, fh, fn, fn, f_floor])
    lower = np.array([-0.5, -0.5, -1.0, -4.0, -math.inf, -math.inf])
    upper = np.array([0.5, 0.5, 0.5, 0.5, 0.5, floor])
    return {
        "cfc": cfc,
        "FL": fl,
        "FH": fh,
        "FN": fn,
        "stopband_db": floor,
        "table": table,
        "f": f,
        "lower": lower,
        "upper": upper,
    }


def corridor_bounds(cfc, f):
    """``(lower_db, upper_db)`` of `cfc_corridor` at frequency ``f`` (Hz)."""
    c = cfc_corridor(cfc)
    fl, fh, fn, floor = c["FL"], c["FH"], c["FN"], c["stopband_db"]
    f = float(f)
    if f < fl:
        raise ValueError(f"{f} Hz is below FL = {fl} Hz, where the corridor is not defined")
    if f < fh:
        return -0.5, 0.5
    if f <= fn:
        lower = -1.0 + (-4.0 + 1.0) * math.log(f / fh) / math.log(fn / fh)
        return lower, 0.5
    return -math.inf, max(floor, 0.5 - 9.0 * math.log2(f / fn))


def gain_db(filter_fn, f, dt, *, periods=40, min_duration=0.5, settle_fraction=0.25):
    """Steady-state gain (dB) of ``filter_fn(x, dt) -> y`` at frequency ``f`` (Hz).

    Filters a unit sine ``sin(2*pi*f*t)`` lasting ``max(periods/f, min_duration)`` s, drops
    ``settle_fraction`` of the record at each end (start-up and end effects), and fits
    ``y = A*sin + B*cos + C`` over the rest by least squares; returns
    ``20*log10(sqrt(A^2 + B^2))``.
    """
    f = float(f)
    duration = max(periods / f, min_duration)
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    w = 2.0 * math.pi * f
    x = np.sin(w * t)
    y = np.asarray(filter_fn(x, dt), dtype=float)
    i0 = int(settle_fraction * n)
    i1 = n - i0
    tt = t[i0:i1]
    basis = np.stack([np.sin(w * tt), np.cos(w * tt), np.ones_like(tt)], axis=1)
    coef, *_ = np.linalg.lstsq(basis, y[i0:i1], rcond=None)
    amplitude = math.hypot(coef[0], coef[1])
    return 20.0 * math.log10(amplitude)


# ---------------------------------------------------------------------------------------
# Integration helpers
# ---------------------------------------------------------------------------------------


def _as_float_lists(*arrays):
    return [[float(v) for v in np.asarray(a, dtype=float).ravel()] for a in arrays]


def _uniform_dt(t):
    t = np.asarray(t, dtype=float)
    steps = np.diff(t)
    dt = float(steps.mean())
    if np.any(np.abs(steps - dt) > 1e-9 * max(1.0, abs(dt)) + 1e-6 * abs(dt)):
        raise ValueError("this filter needs uniformly sampled time")
    return dt


def _crossing(s0, v0, s1, h, limit, method):
    """Time ``tau`` in ``(0, h]`` where a coordinate reaches ``+-limit`` inside one step.

    The coordinate is ``s0`` with rate ``v0`` at the step's start and ``s1`` at its end
    (``|s0| < limit <= |s1|``). ``method="quadratic"`` takes
    ``s(tau) = s0 + v0*tau + c*tau^2`` with ``c`` from ``s(h) = s1``: for the flail space
    this is exactly the constant-acceleration motion that the trapezoid rule integrates
    (``c = a_mean/2``), so the crossing is exact for a piecewise-constant relative
    acceleration, and the method is second order, like the trapezoid rule itself, for a
    smooth one. ``method="linear"`` interpolates ``s`` linearly (also second order in the
    crossing time, error ``|a|*h^2/(8*|v|)``).
    """
    target = limit if s1 > 0 else -limit
    if method == "linear":
        return h * (target - s0) / (s1 - s0)
    if method != "quadratic":
        raise ValueError(f"unknown crossing method {method!r}")
    c = (s1 - s0 - v0 * h) / (h * h)
    k = s0 - target  # solve c*tau^2 + v0*tau + k = 0
    roots = []
    if abs(c) * h < 1e-14 * max(abs(v0), 1e-300):
        if v0 != 0.0:
            roots.append(-k / v0)
    else:
        disc = v0 * v0 - 4.0 * c * k
        if disc >= 0.0:
            sq = math.sqrt(disc)
            q = -0.5 * (v0 + math.copysign(sq, v0)) if v0 != 0.0 else -0.5 * sq
            if q != 0.0:
                roots.append(q / c)
                roots.append(k / q)
            else:
                roots.append(0.0)
    tol = 1e-12 * h
    inside = [r for r in roots if -tol <= r <= h + tol]
    if inside:
        return min(max(min(inside), 0.0), h)
    # Numerical corner (root just outside [0, h]): bisect the sign change of s - target.
    lo, hi = 0.0, h
    g_lo = s0 - target
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        g_mid = s0 + v0 * mid + c * mid * mid - target
        if (g_mid > 0.0) == (g_lo > 0.0):
            lo, g_lo = mid, g_mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _cumulative(t, a):
    """Trapezoid cumulative integral at the nodes (explicit loop)."""
    out = [0.0] * len(t)
    for k in range(1, len(t)):
        out[k] = out[k - 1] + 0.5 * (a[k] + a[k - 1]) * (t[k] - t[k - 1])
    return out


def _value_at(t, a, cum, tau):
    """Exact integral of the linear interpolant of ``a`` from ``t[0]`` to ``tau``."""
    n = len(t)
    if tau <= t[0]:
        return 0.0
    if tau >= t[n - 1]:
        return cum[n - 1]
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if t[mid] <= tau:
            lo = mid
        else:
            hi = mid
    s = tau - t[lo]
    slope = (a[lo + 1] - a[lo]) / (t[lo + 1] - t[lo])
    return cum[lo] + a[lo] * s + 0.5 * slope * s * s


def max_window_average(t, a, t_from, window=0.010, *, absolute=True):
    """Largest ``window``-average of ``a`` over windows starting at or after ``t_from``.

    Window starts are ``t_from`` itself and every sample time after it, with the whole
    window inside the record (``start + window <= t[-1]``). The average is the exact
    integral of the samples' linear interpolant over the window divided by ``window`` (the
    velocity change over the window / window, the physical meaning of a "10 ms average").
    ``absolute=True`` maximises ``|average|``. Returns ``(value, start_time)``; ``nan``
    when no full window fits.
    """
    (tl, al) = _as_float_lists(t, a)
    cum = _cumulative(tl, al)
    t_end = tl[-1]
    starts = [float(t_from)] + [tk for tk in tl if tk > t_from]
    best, best_t = -math.inf, math.nan
    eps = 1e-12 * max(1.0, abs(t_end))
    for start in starts:
        if start + window > t_end + eps:
            break
        avg = (_value_at(tl, al, cum, start + window) - _value_at(tl, al, cum, start)) / window
        score = abs(avg) if absolute else avg
        if score > best:
            best, best_t = score, start
    if best_t != best_t:  # nan
        return math.nan, math.nan
    return best, best_t


# ---------------------------------------------------------------------------------------
# NCHRP 350 / MASH flail space
# ---------------------------------------------------------------------------------------


def flail_space(t, ax, ay, *, dx=FLAIL_DX, dy=FLAIL_DY, method="quadratic"):
    """Flail-space model (Michie 1981; NCHRP Report 350; MASH 2016): OIV and occupant impact.

    The unrestrained occupant, at rest relative to the vehicle at ``t[0]``, keeps its
    velocity while the vehicle accelerates; its acceleration relative to the vehicle is
    ``-ax, -ay`` (vehicle frame, no yaw, as the flail-space model assumes). Relative
    velocity and displacement are integrated sample by sample with the trapezoid rule
    (``v += -(a_k + a_{k+1})/2 * h``, ``s += (v_k + v_{k+1})/2 * h``). Occupant impact is
    the first instant the occupant has travelled ``dx = 0.6 m`` longitudinally or
    ``dy = 0.3 m`` laterally (either sign); within the step where a node first reaches a
    boundary the crossing time is solved for (see `_crossing`: ``"quadratic"`` default,
    exact for the trapezoid rule's piecewise-constant acceleration; ``"linear"`` option).
    The OIV components are the relative velocity components at that instant (same
    interpolation: linear in the step, i.e. constant acceleration).

    Returns ``{"t_impact", "oiv_x", "oiv_y", "surface"}``: ``oiv_*`` are signed velocities
    of the occupant relative to the vehicle (``oiv_x > 0`` in a frontal impact);
    ``surface`` is ``"x"`` or ``"y"``. All ``nan`` (surface ``None``) if the occupant never
    reaches a boundary within the record.
    """
    tl, axl, ayl = _as_float_lists(t, ax, ay)
    vx = vy = sx = sy = 0.0
    for i in range(len(tl) - 1):
        h = tl[i + 1] - tl[i]
        arx = -0.5 * (axl[i] + axl[i + 1])
        ary = -0.5 * (ayl[i] + ayl[i + 1])
        vx1 = vx + arx * h
        vy1 = vy + ary * h
        sx1 = sx + 0.5 * (vx + vx1) * h
        sy1 = sy + 0.5 * (vy + vy1) * h
        hit_x = abs(sx1) >= dx
        hit_y = abs(sy1) >= dy
        if hit_x or hit_y:
            tau_x = _crossing(sx, vx, sx1, h, dx, method) if hit_x else math.inf
            tau_y = _crossing(sy, vy, sy1, h, dy, method) if hit_y else math.inf
            tau = min(tau_x, tau_y)
            return {
                "t_impact": tl[i] + tau,
                "oiv_x": vx + arx * tau,
                "oiv_y": vy + ary * tau,
                "surface": "x" if tau_x <= tau_y else "y",
            }
        vx, vy, sx, sy = vx1, vy1, sx1, sy1
    return {"t_impact": math.nan, "oiv_x": math.nan, "oiv_y": math.nan, "surface": None}


def ridedown(t, ax, ay, t_impact, *, window=0.010):
    """Occupant ridedown accelerations (NCHRP 350 / MASH): ``(ora_x, ora_y)`` in m/s^2.

    After occupant impact the occupant is assumed to stay in contact with the interior and
    ride down with the vehicle; ORA is, per component, the largest absolute 10 ms average
    of the vehicle acceleration over windows starting at or after ``t_impact`` (see
    `max_window_average`). ``nan`` when ``t_impact`` is ``nan`` or no full window fits.
    """
    if t_impact != t_impact:
        return math.nan, math.nan
    ora_x, _ = max_window_average(t, ax, t_impact, window)
    ora_y, _ = max_window_average(t, ay, t_impact, window)
    return ora_x, ora_y


# ---------------------------------------------------------------------------------------
# EN 1317-1 THIV / PHD
# ---------------------------------------------------------------------------------------


def thiv_phd(
    t,
    ax,
    ay,
    yaw_rate,
    *,
    dx=FLAIL_DX,
    dy=FLAIL_DY,
    x0=0.0,
    y0=0.0,
    method="quadratic",
    phd_window=0.010,
    phd_filter_hz=None,
):
    """EN 1317-1 theoretical head model: THIV (m/s), PHD (m/s^2), flight time (s).

    The theoretical head is a free point mass: it keeps, in the ground frame, the velocity
    it had at ``t[0]`` (that of the vehicle point where it sits, ``(x0, y0)`` from the CG in
    the vehicle frame), while the vehicle translates and yaws. Vehicle-frame CG
    accelerations ``ax, ay`` are rotated by the yaw angle ``psi`` (trapezoid integral of
    ``yaw_rate``, ``psi(t0) = 0``) into the ground frame and integrated twice (trapezoid)
    to the CG's velocity and displacement; the head's relative position is rotated back
    into the vehicle frame. (The vehicle's initial speed cancels in every relative
    quantity, so it is not an input.) The head hits the interior when it has moved
    ``dx = 0.6 m`` longitudinally or ``dy = 0.3 m`` laterally from its start, measured in
    the vehicle frame; that time is the flight time ``T``.

    THIV is the magnitude of the head's velocity relative to the vehicle at ``T``, taken as
    the time derivative of its vehicle-frame position (the velocity with which it meets
    the interior surface point, including the ``-omega x r`` term):
    ``xdot = c*dVx + s*dVy + omega*yb``, ``ydot = -s*dVx + c*dVy - omega*xb``. EN 1317-1
    reports it in km/h (``thiv_kmh``; limit 33 km/h); here it is m/s. Without yaw it is
    ``hypot(oiv_x, oiv_y)`` of `flail_space` at the same instant.

    PHD: after ``T`` the head is taken to move with the vehicle; PHD is the largest 10 ms
    moving average of the resultant vehicle acceleration ``sqrt(ax^2 + ay^2)`` after ``T``
    (T/HIS manual wording: average of the resultant). ``phd_filter_hz`` optionally
    low-passes ax, ay first with `butterworth_phaseless` (a 20 Hz pre-filter is sometimes
    cited for PHD; not confirmed, so off by default).

    Returns ``{"thiv", "thiv_kmh", "phd", "phd_g", "t_flight", "surface",
    "vx_rel", "vy_rel"}``; ``nan`` where the head never reaches a surface.
    """
    tl, axl, ayl, wl = _as_float_lists(t, ax, ay, yaw_rate)
    n = len(tl)
    # Ground frame co-moving with the CG's initial velocity; psi(t0) = 0.
    psi = [0.0] * n
    for k in range(1, n):
        psi[k] = psi[k - 1] + 0.5 * (wl[k] + wl[k - 1]) * (tl[k] - tl[k - 1])
    agx = [0.0] * n
    agy = [0.0] * n
    for k in range(n):
        c, s = math.cos(psi[k]), math.sin(psi[k])
        agx[k] = c * axl[k] - s * ayl[k]
        agy[k] = s * axl[k] + c * ayl[k]
    vcx = [0.0] * n
    vcy = [0.0] * n
    pcx = [0.0] * n
    pcy = [0.0] * n
    for k in range(1, n):
        h = tl[k] - tl[k - 1]
        vcx[k] = vcx[k - 1] + 0.5 * (agx[k] + agx[k - 1]) * h
        vcy[k] = vcy[k - 1] + 0.5 * (agy[k] + agy[k - 1]) * h
        pcx[k] = pcx[k - 1] + 0.5 * (vcx[k] + vcx[k - 1]) * h
        pcy[k] = pcy[k - 1] + 0.5 * (vcy[k] + vcy[k - 1]) * h
    # Head: at (x0, y0) at t0 with the velocity of that vehicle point, omega0 x r0.
    w0 = wl[0]
    hvx, hvy = -w0 * y0, w0 * x0

    def relative(k):
        """Head position and velocity relative to the CG, in the vehicle frame, at node k."""
        dxg = x0 + hvx * (tl[k] - tl[0]) - pcx[k]
        dyg = y0 + hvy * (tl[k] - tl[0]) - pcy[k]
        dvx = hvx - vcx[k]
        dvy = hvy - vcy[k]
        c, s = math.cos(psi[k]), math.sin(psi[k])
        xb = c * dxg + s * dyg
        yb = -s * dxg + c * dyg
        xdot = c * dvx + s * dvy + wl[k] * yb
        ydot = -s * dvx + c * dvy - wl[k] * xb
        return xb, yb, xdot, ydot

    nan_result = {
        "thiv": math.nan,
        "thiv_kmh": math.nan,
        "phd": math.nan,
        "phd_g": math.nan,
        "t_flight": math.nan,
        "surface": None,
        "vx_rel": math.nan,
        "vy_rel": math.nan,
    }
    xb, yb, xd, yd = relative(0)
    hit = None
    for k in range(n - 1):
        xb1, yb1, xd1, yd1 = relative(k + 1)
        ex1, ey1 = xb1 - x0, yb1 - y0
        hit_x = abs(ex1) >= dx
        hit_y = abs(ey1) >= dy
        if hit_x or hit_y:
            h = tl[k + 1] - tl[k]
            tau_x = _crossing(xb - x0, xd, ex1, h, dx, method) if hit_x else math.inf
            tau_y = _crossing(yb - y0, yd, ey1, h, dy, method) if hit_y else math.inf
            tau = min(tau_x, tau_y)
            frac = tau / h
            vxr = xd + (xd1 - xd) * frac
            vyr = yd + (yd1 - yd) * frac
            hit = (tl[k] + tau, vxr, vyr, "x" if tau_x <= tau_y else "y")
            break
        xb, yb, xd, yd = xb1, yb1, xd1, yd1
    if hit is None:
        return nan_result
    t_flight, vxr, vyr, surface = hit
    thiv = math.hypot(vxr, vyr)
    if phd_filter_hz is not None:
        dt = _uniform_dt(tl)
        axl = list(butterworth_phaseless(axl, dt, phd_filter_hz))
        ayl = list(butterworth_phaseless(ayl, dt, phd_filter_hz))
    resultant = [math.hypot(axl[k], ayl[k]) for k in range(n)]
    phd, _ = max_window_average(tl, resultant, t_flight, phd_window)
    return {
        "thiv": thiv,
        "thiv_kmh": thiv * 3.6,
        "phd": phd,
        "phd_g": phd / G0,
        "t_flight": t_flight,
        "surface": surface,
        "vx_rel": vxr,
        "vy_rel": vyr,
    }


# ---------------------------------------------------------------------------------------
# EN 1317-1 ASI
# ---------------------------------------------------------------------------------------


def _forward_window_average_series(t, a, window):
    """``abar(t_k) = (1/window) * integral_{t_k}^{t_k+window} a``; ``nan`` where it overruns."""
    (tl, al) = _as_float_lists(t, a)
    cum = _cumulative(tl, al)
    out = [math.nan] * len(tl)
    eps = 1e-12 * max(1.0, abs(tl[-1]))
    for k, tk in enumerate(tl):
        if tk + window > tl[-1] + eps:
            break
        out[k] = (_value_at(tl, al, cum, tk + window) - cum[k]) / window
    return np.array(out)


def asi(
    t,
    ax,
    ay,
    az=None,
    edition="2010",
    *,
    f_cut=13.0,
    filter_reading="fcut",
    pad="zero",
    pad_s=0.5,
    window_1998=0.050,
):
    """EN 1317-1 Acceleration Severity Index: ``(asi_history, asi_max)``.

    ``ASI(t) = sqrt((abar_x/12g)^2 + (abar_y/9g)^2 + (abar_z/10g)^2)``, g = 9.80665 m/s^2,
    limits 12 g / 9 g / 10 g (x, y, z); ``az=None`` means zero.

    * ``edition="2010"`` (EN 1317-1:2010): ``abar`` is each component through a four-pole
      phaseless Butterworth low-pass at 13 Hz. ``filter_reading="fcut"`` (default): 13 Hz
      is the per-pass design frequency (`butterworth_phaseless`, -6 dB at 13 Hz);
      ``"cfc"``: the J211 CFC algorithm with CFC = 13 (`cfc_filter`, -3 dB at 21.7 Hz), as
      DIAdem's "CFC filter with CFR=13 Hz" reads it. The record is extended before
      filtering: the T/HIS manual says the 2010 calculation pads "+/-0.5 seconds of data as
      per the specification" without saying with what; default ``pad="zero"`` (vehicle
      acceleration zero outside the record), ``pad_s=0.5``; any `pad_record` mode works.
    * ``edition="1998"`` (EN 1317-1:1998): ``abar`` is the 50 ms moving average
      ``(1/0.05) * integral_t^{t+0.05} a dt``; ``nan`` where the window overruns the record.

    The inputs are expected already CFC 180 filtered (EN 1317-2 clause 5.6 per DIAdem);
    nothing here applies that pre-filter. ``t`` must be uniformly sampled for ``"2010"``.
    """
    if az is None:
        az = np.zeros(len(np.asarray(t)))
    gx, gy, gz = (limit * G0 for limit in ASI_LIMITS_G)
    if edition == "2010":
        dt = _uniform_dt(t)
        if filter_reading == "fcut":
            smooth = [
                butterworth_phaseless(c, dt, f_cut, pad=pad, pad_s=pad_s) for c in (ax, ay, az)
            ]
        elif filter_reading == "cfc":
            smooth = [cfc_filter(c, dt, f_cut, pad=pad, pad_s=pad_s) for c in (ax, ay, az)]
        else:
            raise ValueError(f"unknown filter_reading {filter_reading!r}")
    elif edition == "1998":
        smooth = [_forward_window_average_series(t, c, window_1998) for c in (ax, ay, az)]
    else:
        raise ValueError(f"unknown EN 1317-1 edition {edition!r}")
    bx, by, bz = (list(np.asarray(c, dtype=float)) for c in smooth)
    history = np.array(
        [
            math.sqrt((bx[k] / gx) ** 2 + (by[k] / gy) ** 2 + (bz[k] / gz) ** 2)
            for k in range(len(bx))
        ]
    )
    finite = history[np.isfinite(history)]
    return history, (float(finite.max()) if finite.size else math.nan)


# ---------------------------------------------------------------------------------------
# Everything at once
# ---------------------------------------------------------------------------------------


def occupant_risk(t, ax, ay, yaw_rate=None, az=None, *, prefilter_cfc=None, asi_edition="2010"):
    """All metrics for one vehicle-CG record: MASH/NCHRP 350 OIV and ORA, EN 1317 THIV/PHD/ASI.

    ``prefilter_cfc`` (e.g. 180) optionally runs every acceleration channel through
    `cfc_filter` first (EN 1317-2 asks for CFC 180 vehicle data; the MASH prescription was
    not confirmed here); default: the inputs are used as given. ``yaw_rate=None`` means no
    yaw. Returns ``{"t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd",
    "asi"}`` in SI units (``asi`` the maximum, dimensionless).
    """
    t = np.asarray(t, dtype=float)
    n = len(t)
    if yaw_rate is None:
        yaw_rate = np.zeros(n)
    if prefilter_cfc is not None:
        dt = _uniform_dt(t)
        ax = cfc_filter(ax, dt, prefilter_cfc)
        ay = cfc_filter(ay, dt, prefilter_cfc)
        if az is not None:
            az = cfc_filter(az, dt, prefilter_cfc)
    fs = flail_space(t, ax, ay)
    ora_x, ora_y = ridedown(t, ax, ay, fs["t_impact"])
    head = thiv_phd(t, ax, ay, yaw_rate)
    _, asi_max = asi(t, ax, ay, az, edition=asi_edition)
    return {
        "t_impact": fs["t_impact"],
        "oiv_x": fs["oiv_x"],
        "oiv_y": fs["oiv_y"],
        "ora_x": ora_x,
        "ora_y": ora_y,
        "thiv": head["thiv"],
        "phd": head["phd"],
        "asi": asi_max,
    }
