"""Checks of the independent occupant-risk reference (`tests/reference_occupant_risk.py`).

Closed forms where the standards' models have them; the filter against the ISO 6487 /
SAE J211 response corridor. Plain numpy, no jax; all cases are small.
"""

import math

import numpy as np
import pytest

import reference_occupant_risk as ref

G0 = ref.G0


def _time(duration, dt):
    return np.arange(int(round(duration / dt)) + 1) * dt


# --- filters ---------------------------------------------------------------------------


def test_j211_design_factor_is_the_fn_to_design_frequency_ratio():
    # -3 dB of the forward+backward 2-pole cascade at FN = 5/3 CFC needs fd = FN/(sqrt2-1)^(1/4).
    derived = (5.0 / 3.0) / (math.sqrt(2.0) - 1.0) ** 0.25
    assert ref.J211_FACTOR == pytest.approx(derived, abs=1e-4)
    assert ref.ISO6487_FACTOR == pytest.approx(2.0833333333, abs=1e-9)


def test_two_pole_dc_gain_is_one_and_a_constant_passes_unchanged():
    a0, a1, a2, b1, b2 = ref.two_pole_coefficients(2.0775 * 60, 1e-4)
    assert (a0 + a1 + a2) / (1.0 - b1 - b2) == pytest.approx(1.0, abs=1e-12)
    x = np.full(500, -7.5)
    for pad in ("endpoint", "none"):
        np.testing.assert_allclose(ref.cfc_filter(x, 1e-4, 60, pad=pad), x, rtol=0, atol=1e-12)


def test_corridor_table_values():
    c = ref.cfc_corridor(60)
    assert (c["FL"], c["FH"], c["FN"]) == (0.1, 60.0, 100.0)
    assert (ref.cfc_corridor(180)["FH"], ref.cfc_corridor(180)["FN"]) == (180.0, 300.0)
    assert (ref.cfc_corridor(1000)["FH"], ref.cfc_corridor(1000)["FN"]) == (1000.0, 1650.0)
    assert c["table"]["a"] == (-0.5, 0.5) and c["table"]["c"] == (-4.0, 0.5)
    assert ref.corridor_bounds(60, 100.0) == pytest.approx((-4.0, 0.5))
    assert ref.corridor_bounds(60, 60.0) == pytest.approx((-1.0, 0.5))


@pytest.mark.parametrize("cfc", [60, 180])
def test_cfc_filter_inside_corridor_at_10_khz(cfc):
    dt = 1e-4
    c = ref.cfc_corridor(cfc)
    fh, fn = c["FH"], c["FN"]
    freqs = [10.0, 0.5 * fh, 0.9 * fh, fh, 1.2 * fh, 0.5 * (fh + fn), fn]
    freqs += [1.5 * fn, 2 * fn, 4 * fn, 10 * fn]
    for f in freqs:
        if f >= 0.45 / dt:
            continue
        g = ref.gain_db(lambda x, dt: ref.cfc_filter(x, dt, cfc), f, dt)
        lower, upper = ref.corridor_bounds(cfc, f)
        assert lower <= g <= upper, (cfc, f, g, lower, upper)
    # The design point: -3 dB at FN (up to the bilinear warping of FN/fd).
    g_fn = ref.gain_db(lambda x, dt: ref.cfc_filter(x, dt, cfc), fn, dt)
    assert g_fn == pytest.approx(-3.0103, abs=0.05)


@pytest.mark.parametrize("dt", [1e-3, 1e-4])
def test_butterworth_phaseless_is_minus_6_db_at_cut_off(dt):
    g = ref.gain_db(lambda x, dt: ref.butterworth_phaseless(x, dt, 13.0), 13.0, dt)
    assert g == pytest.approx(20.0 * math.log10(0.5), abs=1e-3)
    # Exact digital response of the pre-warped bilinear design: |H4| = 1/(1 + (tan/tan)^4).
    ratio = math.tan(math.pi * 2.0 * dt) / math.tan(math.pi * 13.0 * dt)
    g2 = ref.gain_db(lambda x, dt: ref.butterworth_phaseless(x, dt, 13.0), 2.0, dt)
    assert g2 == pytest.approx(-20.0 * math.log10(1.0 + ratio**4), abs=1e-3)


# --- flail space (NCHRP 350 / MASH) ----------------------------------------------------


@pytest.mark.parametrize("dt", [1e-4, 3.7e-4])
def test_flail_space_constant_deceleration_closed_form(dt):
    a = 15.0 * G0
    t = _time(0.3, dt)
    fs = ref.flail_space(t, np.full_like(t, -a), np.zeros_like(t))
    assert fs["surface"] == "x"
    assert fs["t_impact"] == pytest.approx(math.sqrt(2 * 0.6 / a), rel=1e-12)
    assert fs["oiv_x"] == pytest.approx(math.sqrt(2 * a * 0.6), rel=1e-12)
    assert fs["oiv_y"] == 0.0
    lin = ref.flail_space(t, np.full_like(t, -a), np.zeros_like(t), method="linear")
    # Linear interpolation of the displacement: second order, error ~ a h^2 / (8 v).
    assert lin["t_impact"] == pytest.approx(math.sqrt(2 * 0.6 / a), rel=2e-6)


def test_flail_space_constant_lateral_acceleration():
    a = 8.0 * G0
    t = _time(0.3, 1e-4)
    fs = ref.flail_space(t, np.zeros_like(t), np.full_like(t, a))
    assert fs["surface"] == "y"
    assert fs["t_impact"] == pytest.approx(math.sqrt(2 * 0.3 / a), rel=1e-12)
    # The vehicle is pushed to +y (left); the occupant moves to -y relative to it.
    assert fs["oiv_y"] == pytest.approx(-math.sqrt(2 * a * 0.3), rel=1e-12)
    assert fs["oiv_x"] == 0.0


def test_flail_space_first_surface_wins():
    ax_, ay_ = 10.0 * G0, 3.0 * G0  # x reached at 0.1106 s, y at 0.1428 s
    t = _time(0.3, 1e-4)
    fs = ref.flail_space(t, np.full_like(t, -ax_), np.full_like(t, ay_))
    t_x = math.sqrt(1.2 / ax_)
    assert fs["surface"] == "x"
    assert fs["t_impact"] == pytest.approx(t_x, rel=1e-12)
    assert fs["oiv_x"] == pytest.approx(ax_ * t_x, rel=1e-12)
    assert fs["oiv_y"] == pytest.approx(-ay_ * t_x, rel=1e-12)


def test_flail_space_no_impact_is_nan():
    t = _time(0.1, 1e-4)
    fs = ref.flail_space(t, np.full_like(t, -1.0), np.zeros_like(t))
    assert math.isnan(fs["t_impact"]) and fs["surface"] is None


# --- ridedown --------------------------------------------------------------------------


def test_ridedown_constant_signal():
    a = 15.0 * G0
    t = _time(0.3, 1e-4)
    ora_x, ora_y = ref.ridedown(t, np.full_like(t, -a), np.full_like(t, 2.0), 0.09)
    assert ora_x == pytest.approx(a, rel=1e-12)
    assert ora_y == pytest.approx(2.0, rel=1e-12)


def test_ridedown_is_a_10_ms_average_after_impact_only():
    dt = 1e-4
    t = _time(0.5, dt)
    ax = np.zeros_like(t)
    ax[1000:1300] = -500.0  # 30 ms before the impact time: ignored
    ax[2000:2200] = -100.0  # 20 ms plateau: a full 10 ms window sees 100
    ay = np.zeros_like(t)
    ay[3000:3050] = 80.0  # 5 ms spike: the best 10 ms window averages it to 40
    ora_x, ora_y = ref.ridedown(t, ax, ay, 0.15)
    assert ora_x == pytest.approx(100.0, rel=1e-9)
    assert ora_y == pytest.approx(40.0, rel=1e-9)


# --- EN 1317 ASI -----------------------------------------------------------------------


def test_asi_constant_12_g_longitudinal_is_one():
    t = _time(0.4, 1e-4)
    ax = np.full_like(t, -12.0 * G0)
    _, m2010 = ref.asi(t, ax, np.zeros_like(t), pad="endpoint")
    _, m1998 = ref.asi(t, ax, np.zeros_like(t), edition="1998")
    assert m2010 == pytest.approx(1.0, abs=1e-9)
    assert m1998 == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("axis,limit_g", [(1, 9.0), (2, 10.0)])
def test_asi_constant_lateral_and_vertical_limits(axis, limit_g):
    t = _time(0.4, 1e-4)
    comps = [np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)]
    comps[axis] = np.full_like(t, limit_g * G0)
    for edition in ("2010", "1998"):
        _, m = ref.asi(t, *comps, edition=edition, pad="endpoint")
        assert m == pytest.approx(1.0, abs=1e-9), edition


def test_asi_long_12_g_pulse_with_zero_padding():
    # A 1 s, 12 g rectangular pulse in a zero record: mid-plateau ASI = 1, and the maximum
    # is the step overshoot of the phaseless 2x2-pole Butterworth, 1 + exp(-3pi/4)/(2 sqrt2).
    dt = 1e-4
    t = _time(2.0, dt)
    ax = np.zeros_like(t)
    ax[5000:15000] = -12.0 * G0
    history, m = ref.asi(t, ax, np.zeros_like(t))
    assert history[10000] == pytest.approx(1.0, abs=1e-6)
    assert m == pytest.approx(1.0 + math.exp(-0.75 * math.pi) / (2.0 * math.sqrt(2.0)), abs=2e-4)
    _, m1998 = ref.asi(t, ax, np.zeros_like(t), edition="1998")
    assert m1998 == pytest.approx(1.0, abs=1e-9)


def test_asi_cfc13_reading_is_a_wider_filter():
    # Same pulse, 50 ms long: the CFC-13 reading (-3 dB at 21.7 Hz) passes more of it.
    dt = 1e-4
    t = _time(0.6, dt)
    ax = np.zeros_like(t)
    ax[2000:2500] = -12.0 * G0
    _, fcut = ref.asi(t, ax, np.zeros_like(t))
    _, cfc13 = ref.asi(t, ax, np.zeros_like(t), filter_reading="cfc")
    assert fcut < cfc13 < 1.1


# --- EN 1317 THIV / PHD ----------------------------------------------------------------


def test_thiv_without_yaw_is_the_flail_space_resultant():
    t = _time(0.3, 1e-4)
    ax = -12.0 * G0 * np.sin(np.pi * t / 0.3)
    ay = 4.0 * G0 * np.sin(np.pi * t / 0.3) ** 2
    fs = ref.flail_space(t, ax, ay)
    head = ref.thiv_phd(t, ax, ay, np.zeros_like(t))
    assert head["t_flight"] == pytest.approx(fs["t_impact"], rel=1e-12)
    assert head["thiv"] == pytest.approx(math.hypot(fs["oiv_x"], fs["oiv_y"]), rel=1e-12)
    assert head["thiv_kmh"] == pytest.approx(3.6 * head["thiv"], rel=1e-15)


def test_phd_of_a_constant_acceleration():
    a = 15.0 * G0
    t = _time(0.3, 1e-4)
    head = ref.thiv_phd(t, np.full_like(t, -a), np.full_like(t, 0.5 * a), np.zeros_like(t))
    assert head["phd"] == pytest.approx(math.hypot(a, 0.5 * a), rel=1e-12)


def test_thiv_pure_yaw_closed_form():
    # No CG acceleration, constant yaw rate w, head at x0 ahead of the CG moving with that
    # point at t0: in the vehicle frame xb - x0 = x0 (cos u + u sin u - 1),
    # yb = x0 (u cos u - sin u), u = w t, and |v_rel| = x0 w u.
    x0, w = 0.5, 3.0

    def first_root(fun, limit):
        u, du = 0.0, 1e-3
        while abs(fun(u + du)) < limit:
            u += du
        lo, hi = u, u + du
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            if abs(fun(mid)) < limit:
                lo = mid
            else:
                hi = mid
        return 0.5 * (lo + hi)

    u_x = first_root(lambda u: x0 * (math.cos(u) + u * math.sin(u) - 1.0), 0.6)
    u_y = first_root(lambda u: x0 * (u * math.cos(u) - math.sin(u)), 0.3)
    u = min(u_x, u_y)
    t = _time(1.0, 1e-4)
    zero = np.zeros_like(t)
    head = ref.thiv_phd(t, zero, zero, np.full_like(t, w), x0=x0)
    assert head["surface"] == ("y" if u_y < u_x else "x")
    assert head["t_flight"] == pytest.approx(u / w, rel=1e-9)
    assert head["thiv"] == pytest.approx(x0 * w * u, rel=1e-8)
    assert head["vx_rel"] == pytest.approx(x0 * w * u * math.cos(u), rel=1e-7)


def test_thiv_mirror_symmetry():
    t = _time(0.3, 1e-4)
    ax = -10.0 * G0 * np.sin(np.pi * t / 0.3)
    ay = 5.0 * G0 * np.sin(np.pi * t / 0.3)
    yaw = 2.0 * np.sin(np.pi * t / 0.6)
    left = ref.thiv_phd(t, ax, ay, yaw, y0=0.1)
    right = ref.thiv_phd(t, ax, -ay, -yaw, y0=-0.1)
    assert right["thiv"] == pytest.approx(left["thiv"], rel=1e-12)
    assert right["t_flight"] == pytest.approx(left["t_flight"], rel=1e-12)
    assert right["vy_rel"] == pytest.approx(-left["vy_rel"], rel=1e-12)


# --- everything ------------------------------------------------------------------------


def test_occupant_risk_collects_the_metrics():
    dt = 1e-4
    t = _time(0.4, dt)
    ax = -20.0 * G0 * np.sin(np.pi * np.clip(t / 0.2, 0.0, 1.0))
    ay = 6.0 * G0 * np.sin(np.pi * np.clip(t / 0.2, 0.0, 1.0))
    out = ref.occupant_risk(t, ax, ay)
    assert set(out) == {"t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi"}
    fs = ref.flail_space(t, ax, ay)
    assert out["oiv_x"] == fs["oiv_x"] and out["t_impact"] == fs["t_impact"]
    assert out["thiv"] == pytest.approx(math.hypot(out["oiv_x"], out["oiv_y"]), rel=1e-12)
    assert 0.0 < out["ora_x"] <= 20.0 * G0 and 0.0 < out["ora_y"] <= 6.0 * G0
    assert 0.0 < out["asi"] < 2.5
    filtered = ref.occupant_risk(t, ax, ay, prefilter_cfc=180)
    assert filtered["oiv_x"] == pytest.approx(out["oiv_x"], rel=1e-3)
