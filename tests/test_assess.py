"""barrierjax.assess: the occupant-risk metrics and filters against closed forms, scipy and
the independent numpy reference (tests/reference_occupant_risk.py, written from the
standards' text, sharing no code)."""

import math

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
import reference_occupant_risk as reference
import scipy.signal

from barrierjax.assess import filters, judge, occupant_risk, signals
from barrierjax.assess.matrices import G

DT = 1e-4  # 10 kHz, as crash-test records are sampled
T = np.arange(0.0, 0.6, DT)


def half_sine(amplitude, duration, t=T):
    return jnp.where(t < duration, amplitude * jnp.sin(jnp.pi * t / duration), 0.0)


def haversine(amplitude, duration, t=T):
    return jnp.where(t < duration, amplitude * jnp.sin(jnp.pi * t / duration) ** 2, 0.0)


def trapezoid(plateau, ramp, hold, t=T, start=0.05):
    """Zero, a linear ramp of `ramp` s up to `plateau`, `hold` s at it, a ramp down."""
    up = np.clip((t - start) / ramp, 0.0, 1.0) if ramp > 0 else (t >= start) * 1.0
    end = start + ramp + hold
    down = np.clip(1.0 - (t - end) / ramp, 0.0, 1.0) if ramp > 0 else (t < end) * 1.0
    return plateau * np.minimum(up, down)


@pytest.mark.parametrize("a", [50.0, 200.0])
def test_constant_deceleration_closed_form(a):
    """A constant deceleration a: the occupant travels 0.6 m at t = sqrt(1.2 / a) with
    OIV = sqrt(2 a 0.6); ORA and PHD are a; THIV = OIV without yaw."""
    zeros = np.zeros_like(T)
    r = occupant_risk(T, np.full_like(T, -a), zeros)
    assert float(r.t_impact) == pytest.approx(np.sqrt(1.2 / a), rel=1e-12)
    assert float(r.oiv_x) == pytest.approx(np.sqrt(2 * a * 0.6), rel=1e-10)
    assert float(r.oiv_y) == 0.0
    assert float(r.ora_x) == pytest.approx(a, rel=1e-10)
    assert float(r.thiv) == pytest.approx(float(r.oiv_x), rel=1e-12)
    assert float(r.phd) == pytest.approx(a, rel=1e-10)
    assert bool(r.impact_in_record)


def test_records_of_one_rate_share_a_program_whatever_their_start(compilations):
    """The start time is an argument and the step is read to 12 digits: a record that
    starts 50 ms before contact, its times built as a linspace (whose step is not 1e-4 to
    the last bit), runs the program of one starting at 0; its times shift by the start."""
    a, zeros = 50.0, np.zeros_like(T)
    at_zero = occupant_risk(T, np.full_like(T, -a), zeros)
    shifted = np.linspace(-0.05, T[-1] - 0.05, T.size)
    assert np.diff(shifted)[0] != DT  # float noise in the step
    with compilations() as programs:
        early = occupant_risk(shifted, np.full_like(T, -a), zeros)
    assert not [m for m in programs if "_records" in m], programs
    assert float(early.t_impact) == pytest.approx(float(at_zero.t_impact) - 0.05, rel=1e-12)
    assert float(early.oiv_x) == float(at_zero.oiv_x)


def test_records_of_nearby_lengths_share_a_program_and_read_as_unpadded(compilations):
    """Records are padded with zeros to `record_size` (two sizes an octave) and read as
    ending at their own last sample: a record of another length and the same size runs the
    same program, and every metric equals the unpadded record's (after it the vehicle moves
    on freely), with the impact within the record or after its end, both ASI editions."""
    from barrierjax.assess.occupant import _one_record, record_size

    sizes = [record_size(n) for n in (3, 64, 65, 96, 97, 1000, 1024, 1025, 5001)]
    assert sizes == [64, 64, 96, 96, 128, 1024, 1024, 1536, 6144]
    rng = np.random.default_rng(0)

    def record(n, amplitude):
        t = T[:n]
        noise = lambda scale: rng.normal(0.0, scale, n)
        ax = np.asarray(half_sine(-amplitude, 0.08, t)) + noise(3.0)
        ay = np.asarray(half_sine(0.4 * amplitude, 0.06, t)) + noise(3.0)
        return t, ax, ay, np.asarray(half_sine(1.5, 0.08, t)), noise(8.0)

    within, after = record(1100, 300.0), record(1300, 40.0)  # both padded to 1536
    within[1][-1] -= 1500.0  # a spike at the last sample: the windows that end past it read
    within[2][-1] += 800.0  # zeros there, not a ramp down to the padding's first sample
    risks = {}
    with compilations() as programs:
        for name, channels in (("within", within), ("after", after)):
            for edition in ("2010", "1998"):
                risks[name, edition] = occupant_risk(*channels, asi_edition=edition)
    assert sum("_records" in m for m in programs) == 2, programs  # one program an edition
    assert bool(risks["within", "2010"].impact_in_record)
    assert not bool(risks["after", "2010"].impact_in_record)
    # (The unpadded reference as one program, not an operation at a time.)
    unpadded_record = jax.jit(_one_record, static_argnames=("dt", "edition"))
    for (name, edition), risk in risks.items():
        t, *channels = within if name == "within" else after
        unpadded = unpadded_record(
            *map(jnp.asarray, channels), 0.6, 0.3, 0.0, jnp.int32(t.size), dt=DT, edition=edition
        )
        for field in risk.__dataclass_fields__:
            np.testing.assert_allclose(
                getattr(risk, field), getattr(unpadded, field), rtol=1e-10, err_msg=field
            )


@pytest.mark.parametrize("end", [None, 30e-3, 12.5e-3, 49e-3, 0.0, 60e-3])
def test_the_integral_on_the_sample_grid_is_the_integral_at_each_time(end):
    # The ridedown's windows and the 1998 ASI's average read the cumulative integral at a
    # fixed offset from every sample, by shifting it: the same as locating each time, on
    # and between samples, before the record and past its end (`end`: a sample, between
    # two, its start, beyond its last).
    a = jnp.asarray(np.random.default_rng(2).normal(size=50))
    dt = 1e-3
    at = jax.jit(lambda t: signals.integral_at(a, dt, end)(t))
    for shift in (0.0, 0.01, 0.0105, 0.001, 0.0004, -0.0004, -0.025, 0.049, 0.0491, 0.2, -0.2):
        on_grid = signals.integral_on_grid(a, dt, shift, end)
        np.testing.assert_allclose(on_grid, at(jnp.arange(50.0) * dt + shift), rtol=0, atol=1e-15)


def test_the_integral_on_the_sample_grid_has_the_gradient_of_the_integral_at_each_time():
    a = jnp.asarray(np.random.default_rng(3).normal(size=50))
    weights = jnp.asarray(np.random.default_rng(4).normal(size=50))
    t = jnp.arange(50.0) * 1e-3 + 0.0105
    on_grid = jax.grad(lambda a: weights @ signals.integral_on_grid(a, 1e-3, 0.0105, 0.03))(a)
    at = jax.grad(lambda a: weights @ signals.integral_at(a, 1e-3, 0.03)(t))(a)
    np.testing.assert_allclose(on_grid, at, rtol=1e-12, atol=1e-18)


@pytest.mark.parametrize("shift", [math.nan, math.inf, jnp.asarray(0.01), "0.01"])
def test_the_integral_on_the_sample_grid_refuses_a_shift_not_a_finite_number(shift):
    with pytest.raises(ValueError, match="shift must be a finite Python number"):
        signals.integral_on_grid(jnp.zeros(8), 1e-3, shift)


def test_lateral_constant_acceleration_reaches_the_side_first():
    a = 40.0  # to the left: the occupant moves right, 0.3 m at sqrt(0.6 / a)
    r = occupant_risk(T, np.zeros_like(T), np.full_like(T, a))
    assert float(r.t_impact) == pytest.approx(np.sqrt(0.6 / a), rel=1e-12)
    assert float(r.oiv_y) == pytest.approx(-np.sqrt(2 * a * 0.3), rel=1e-10)


def test_no_motion_gives_no_impact_and_no_nan():
    zeros = np.zeros_like(T)
    r = occupant_risk(T, zeros, zeros)
    assert np.isinf(r.t_impact) and np.isinf(r.t_head)
    values = [
        float(getattr(r, f)) for f in ("oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi")
    ]
    assert values == [0.0] * 7
    assert not bool(r.impact_in_record)
    grad = jax.grad(lambda s: occupant_risk(T, s * zeros, zeros).oiv_x)(1.0)
    assert np.isfinite(grad)


def test_record_that_ends_at_rest_before_the_impact_continues_in_free_flight():
    """A vehicle stopped from 10 m/s in 0.2 m (a model's history ends at rest): the
    occupant hits after the record, at the full 10 m/s."""
    t = np.arange(0.0, 0.04 + DT / 2, DT)
    r = occupant_risk(t, np.full_like(t, -250.0), np.zeros_like(t))  # 10 m/s gone in 40 ms
    assert float(r.oiv_x) == pytest.approx(10.0, rel=1e-10)
    d_end = 0.5 * 250.0 * 0.04**2
    assert float(r.t_impact) == pytest.approx(0.04 + (0.6 - d_end) / 10.0, rel=1e-10)
    assert not bool(r.impact_in_record) and float(r.ora_x) == 0.0


@pytest.mark.parametrize("pulse", [half_sine, haversine])
def test_pulses_against_the_independent_reference(pulse):
    """Half-sine and haversine pulses with yaw, against the numpy reference (constant
    acceleration in a step there, linear here; both second order: agreement to 1e-5)."""
    ax, ay = np.asarray(pulse(-180.0, 0.12)), np.asarray(pulse(70.0, 0.12))
    yaw = np.asarray(pulse(1.5, 0.12))
    az = np.asarray(pulse(20.0, 0.12))
    mine = occupant_risk(T, ax, ay, yaw_rate=yaw, az=az)
    ref = reference.occupant_risk(T, ax, ay, yaw_rate=yaw, az=az)
    for name in ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi"):
        assert float(getattr(mine, name)) == pytest.approx(ref[name], rel=1e-5, abs=1e-6), name


def test_asi_1998_of_a_long_pulse_is_its_plateau_over_12_g():
    a = 6.0 * G
    ax = trapezoid(-a, 0.0, 0.2)
    r = occupant_risk(T, ax, np.zeros_like(T), asi_edition="1998")
    assert float(r.asi) == pytest.approx(a / (12 * G), rel=1e-12)


def test_asi_2010_overshoots_a_step_and_tends_to_the_plateau_as_ramps_lengthen():
    """Measured (ASI over the plateau's a / 12 g): a rectangular pulse 1.0335, the step
    response's overshoot 1 + exp(-3 pi / 4) / (2 sqrt 2) of two passes of the 2-pole
    Butterworth; linear ramps of 20, 80, 200, 800 ms: 1.0301, 1.0114, 1.0045, 1.0011 (the
    excess falls about as 1 / ramp, from the ramps' corners)."""
    a = 6.0 * G
    t = np.arange(0.0, 2.5, DT)
    ratios = [
        float(occupant_risk(t, trapezoid(-a, ramp, 0.4, t), np.zeros_like(t)).asi) / (a / (12 * G))
        for ramp in (0.0, 0.02, 0.08, 0.2, 0.8)
    ]
    assert ratios[0] == pytest.approx(1 + np.exp(-3 * np.pi / 4) / (2 * np.sqrt(2)), rel=2e-3)
    assert all(earlier > later for earlier, later in zip(ratios, ratios[1:]))
    assert 1.0 < ratios[-1] < 1.002


@pytest.mark.parametrize("cfc", [60, 180, 600, 1000])
def test_cfc_filter_lies_in_the_j211_corridor(cfc):
    """The gain at J211's defining points (F_L..F_H flat within 0.5 dB; -1 dB at F_H at
    most; -3 dB at F_N = 5/3 CFC; -4 dB bound there) and beyond, at 10 kHz and 50 kHz."""
    for dt in (1e-4, 2e-5):
        design = filters.J211_DESIGN_FACTOR * cfc
        corridor = reference.cfc_corridor(cfc)
        nyquist = 0.5 / dt
        for f in np.geomspace(corridor["FL"], min(4 * corridor["FN"], 0.9 * nyquist), 60):
            gain = 20 * np.log10(filters.filter_gain(f, dt, design))
            lower, upper = reference.corridor_bounds(cfc, f)
            assert lower - 1e-9 <= gain <= upper + 1e-9, (dt, f, gain)
        if dt == 2e-5 and cfc <= 180:  # the bilinear warp is small at F_N << Nyquist
            fn_gain = 20 * np.log10(filters.filter_gain(corridor["FN"], dt, design))
            assert fn_gain == pytest.approx(-3.0103, abs=0.05)


def test_measured_sine_gain_equals_the_exact_response():
    f, cfc = 200.0, 180
    t = np.arange(0.0, 0.5, DT)
    y = np.asarray(filters.cfc_filter(np.sin(2 * np.pi * f * t), DT, cfc))
    middle = slice(1000, 4000)  # 60 whole periods, away from the ends
    phase = 2 * np.pi * f * t[middle]
    measured = np.hypot(*(2 * np.mean(y[middle] * basis(phase)) for basis in (np.sin, np.cos)))
    exact = filters.filter_gain(f, DT, filters.J211_DESIGN_FACTOR * cfc)
    assert measured == pytest.approx(exact, rel=1e-3)


def test_filtered_record_equals_scipy_filtfilt():
    """scipy's butter(2) (the same bilinear design) with filtfilt, padding by odd
    reflection of the same length, starting from the steady state as here."""
    rng = np.random.default_rng(1)
    x = np.cumsum(rng.normal(size=3000))
    n_pad = 100
    for cfc in (60, 180):
        design = filters.J211_DESIGN_FACTOR * cfc
        b, a = scipy.signal.butter(2, design, fs=1 / DT)
        expected = scipy.signal.filtfilt(b, a, x, padtype="odd", padlen=n_pad)
        np.testing.assert_allclose(
            filters.cfc_filter(x, DT, cfc), expected, rtol=0, atol=1e-9 * np.ptp(x)
        )
    b, a = scipy.signal.butter(2, 13.0, fs=1 / DT)
    padded = np.concatenate([np.zeros(5000), x, np.zeros(5000)])
    expected = scipy.signal.filtfilt(b, a, padded, padtype=None)[5000:-5000]
    got = filters.zero_padded_lowpass(x, DT, 13.0, pad_seconds=0.5)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-9 * np.ptp(x))


def test_vmap_and_batch_axes_equal_the_loop():
    amplitudes = np.array([-120.0, -200.0, -260.0])
    ax = np.stack([np.asarray(half_sine(a, 0.1)) for a in amplitudes])
    ay = 0.3 * ax[::-1]
    batched = occupant_risk(T, ax, ay, yaw_rate=ax / 100)
    mapped = jax.vmap(lambda x, y: occupant_risk(T, x, y, yaw_rate=x / 100))(ax, ay)
    for i in range(3):
        single = occupant_risk(T, ax[i], ay[i], yaw_rate=ax[i] / 100)
        for name in ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi"):
            expected = float(getattr(single, name))
            assert float(getattr(batched, name)[i]) == pytest.approx(expected, rel=1e-12), name
            assert float(getattr(mapped, name)[i]) == pytest.approx(expected, rel=1e-12), name


@pytest.mark.parametrize("name", ["oiv_x", "ora_x", "thiv", "asi", "t_impact"])
def test_gradients_in_pulse_amplitude_and_duration_match_finite_differences(name):
    def metric(params):
        amplitude, duration = params
        ax = half_sine(-amplitude, duration)
        return getattr(occupant_risk(T, ax, 0.3 * ax, yaw_rate=ax / 200), name)

    x0 = jnp.asarray([150.0, 0.11037])  # the pulse's end between samples (a kink on one)
    grad = np.asarray(jax.grad(metric)(x0))
    for j in range(2):
        h = 1e-5 * float(x0[j])
        step = jnp.zeros(2).at[j].set(h)
        fd = (float(metric(x0 + step)) - float(metric(x0 - step))) / (2 * h)
        assert grad[j] == pytest.approx(fd, rel=1e-5, abs=1e-9), j


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (dict(ax=np.full(T.shape, np.nan)), "ax must be finite"),
        (dict(t=np.r_[T[:10], T[9], T[11:]]), "t must be strictly increasing"),
        (dict(t=T * (1 + 0.1 * (T > 0.3))), "t must be uniformly sampled"),
        (dict(ay=np.zeros(5)), "ay must have the samples of t"),
        (dict(t=T[:2], ax=np.zeros(2), ay=np.zeros(2)), "t must be a 1-D array of at least 3"),
        (dict(asi_edition="2003"), "asi_edition must be one of"),
        (dict(flail_x=np.nan), "flail_x must be positive and finite"),
        (dict(flail_x=0.0), "flail_x must be positive and finite"),
        (dict(flail_y=-0.3), "flail_y must be positive and finite"),
    ],
)
def test_bad_inputs_name_the_field_and_the_rule(change, message):
    kwargs = dict(t=T, ax=np.zeros_like(T), ay=np.zeros_like(T)) | change
    with pytest.raises(ValueError, match=message):
        occupant_risk(**kwargs)


def test_judge_refuses_a_metric_that_is_not_finite_and_a_batch():
    ax = half_sine(-150.0, 0.1)
    risk = occupant_risk(T, ax, 0.3 * ax)
    assert all(c.passed for c in judge(risk, "mash"))
    for name, standard in (("oiv_x", "mash"), ("asi", "en1317"), ("ora_y", "nchrp350")):
        broken = eqx.tree_at(lambda r: getattr(r, name), risk, jnp.asarray(np.nan))
        with pytest.raises(ValueError, match=f"{name} must be finite to be judged"):
            judge(broken, standard)
    batch = occupant_risk(T, np.stack([ax, 2 * ax]), np.stack([ax, ax]))
    with pytest.raises(ValueError, match="judge takes one record's OccupantRisk"):
        judge(batch)


def test_nan_inside_jit_raises_instead_of_propagating():
    ax = np.zeros_like(T)
    ax[100] = np.nan
    with pytest.raises(Exception, match="ax must be finite"):
        jax.jit(lambda x: occupant_risk(T, x, jnp.zeros_like(x)).oiv_x)(ax).block_until_ready()
