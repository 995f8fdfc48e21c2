"""Benchmark of crash-test assessment (`barrierjax.assess.occupant_risk`): records per
second, batched, beside a per-record NumPy/scipy loop written the way a test house would.

    python benchmarks/assess.py [--quick] [--out DIR] [--seed N]

Records: 1 s at 10 kHz (10 001 samples), a half-sine pulse on ax (5 to 25 g, 40 to 200 ms),
ay a random fraction of it, a yaw rate, no az: every metric computed (flail space OIV and
ORA, THIV and PHD with the yaw, ASI 2010 with its 13 Hz filter on 0.5 s padding). barrierjax:
`occupant_risk` on chunks of 200 records (one compiled executable; larger chunks run slower
here, out of cache), 1e5 records (--quick: 2e3;
four distinct chunks of random records taken in turn, to bound the memory).
The loop: for each record, scipy.signal's butter and filtfilt for the ASI, np.cumsum
trapezoids for the occupant, the first sample past the flail distance with linear
interpolation, 10 ms window means from the cumulative integral, THIV by rotating into the
ground frame: vectorised NumPy per record, as a spreadsheet macro or TRAP-like script does;
timed on a subset and given per record. Both are checked against each other on the first
records (max relative difference printed). Then the first call in a fresh process (one
record, one chunk), with its peak memory. Writes `assess.json` to `--out`.
"""

import jax

jax.config.update("jax_enable_x64", True)

import time

import numpy as np
import scipy.signal
from harness import argument_parser, first_calls, steady, table, write_json

from barrierjax.assess import occupant_risk

G = 9.80665
DT = 1e-4
T = np.arange(10_001) * DT
METRICS = ("t_impact", "oiv_x", "oiv_y", "ora_x", "ora_y", "thiv", "phd", "asi")


def records(n: int, seed: int):
    rng = np.random.default_rng(seed)
    amplitude = rng.uniform(5.0, 25.0, (n, 1)) * G
    duration = rng.uniform(0.04, 0.2, (n, 1))
    pulse = np.where(T < duration, np.sin(np.pi * T / duration), 0.0)
    ax = -amplitude * pulse
    ay = rng.uniform(-0.5, 0.5, (n, 1)) * amplitude * pulse
    yaw = rng.uniform(-2.0, 2.0, (n, 1)) * pulse
    return ax, ay, yaw


# --- The test house's loop --------------------------------------------------------------


def _crossing(t, d, v, limit):
    hit = np.flatnonzero(np.abs(d) >= limit)
    if hit.size == 0:
        return np.inf, np.zeros(2)
    k = hit[0]
    target = np.sign(d[k]) * limit
    f = (target - d[k - 1]) / (d[k] - d[k - 1])
    return t[k - 1] + f * (t[k] - t[k - 1]), k, f


def _window_max(t, a, t_from, window=0.010):
    n = int(round(window / DT))
    cumulative = np.concatenate([[0.0], np.cumsum(0.5 * DT * (a[1:] + a[:-1]))])
    means = (cumulative[n:] - cumulative[:-n]) / window
    return np.max(np.abs(means[t[: len(means)] >= t_from])) if np.isfinite(t_from) else 0.0


def _first_of(t, d, v, limits):
    best = (np.inf, None, None)
    for axis, limit in enumerate(limits):
        found = _crossing(t, d[:, axis], v[:, axis], limit)
        if found[0] < best[0]:
            best = found
    t_hit, k, f = best
    return t_hit, (1 - f) * v[k - 1] + f * v[k]


def loop_record(ax, ay, yaw):
    """Every metric of one record, in NumPy and scipy."""
    cum = lambda a: np.concatenate([[0.0], np.cumsum(0.5 * DT * (a[1:] + a[:-1]))])
    v = -np.stack([cum(ax), cum(ay)], 1)
    d = np.stack([cum(v[:, 0]), cum(v[:, 1])], 1)
    t_impact, oiv = _first_of(T, d, v, (0.6, 0.3))
    psi = cum(yaw)
    gx, gy = np.cos(psi) * ax - np.sin(psi) * ay, np.sin(psi) * ax + np.cos(psi) * ay
    vg = -np.stack([cum(gx), cum(gy)], 1)
    dg = np.stack([cum(vg[:, 0]), cum(vg[:, 1])], 1)
    c, s = np.cos(psi), np.sin(psi)
    hx, hy = c * dg[:, 0] + s * dg[:, 1], -s * dg[:, 0] + c * dg[:, 1]
    ux = c * vg[:, 0] + s * vg[:, 1] + yaw * hy
    uy = -s * vg[:, 0] + c * vg[:, 1] - yaw * hx
    t_head, relative = _first_of(T, np.stack([hx, hy], 1), np.stack([ux, uy], 1), (0.6, 0.3))
    b, a = scipy.signal.butter(2, 13.0, fs=1 / DT)
    pad = np.zeros(5000)
    filtered = [
        scipy.signal.filtfilt(b, a, np.concatenate([pad, x, pad]), padtype=None)[5000:-5000]
        for x in (ax, ay)
    ]
    asi = np.max(np.sqrt((filtered[0] / (12 * G)) ** 2 + (filtered[1] / (9 * G)) ** 2))
    return dict(
        t_impact=t_impact, oiv_x=oiv[0], oiv_y=oiv[1],
        ora_x=_window_max(T, ax, t_impact), ora_y=_window_max(T, ay, t_impact),
        thiv=float(np.hypot(*relative)), phd=_window_max(T, np.hypot(ax, ay), t_head), asi=asi,
    )  # fmt: skip


def main():
    args = argument_parser(__doc__).parse_args()
    n_records = 2_000 if args.quick else 100_000
    chunk = 200
    n_loop = 50 if args.quick else 500
    # Four distinct chunks, taken in turn (1e5 records at once would be 24 GB of float64).
    chunks = [records(chunk, args.seed + i) for i in range(4)]

    def batched(ax, ay, yaw):
        return occupant_risk(T, ax, ay, yaw_rate=yaw)

    steady(batched, *chunks[0], reps=2)  # compiles the chunk's executable
    start = time.perf_counter()
    risks = [jax.block_until_ready(batched(*chunks[i % 4])) for i in range(n_records // chunk)]
    jax_time = time.perf_counter() - start
    ax, ay, yaw = (np.concatenate(channel) for channel in zip(*chunks))  # the 800 records
    start = time.perf_counter()
    reference = [loop_record(ax[i], ay[i], yaw[i]) for i in range(n_loop)]
    loop_time = time.perf_counter() - start

    differences = {  # relative to the metric's largest value over the 20 records
        name: max(
            abs(float(getattr(risks[0], name)[i]) - r[name]) for i, r in enumerate(reference[:20])
        )
        / max(abs(r[name]) for r in reference[:20])
        for name in METRICS
    }
    jax_rate, loop_rate = n_records / jax_time, n_loop / loop_time
    rows = [
        dict(
            method=f"barrierjax occupant_risk, chunks of {chunk}",
            records=n_records,
            seconds=jax_time,
            rate=jax_rate,
            ratio=jax_rate / loop_rate,
        ),
        dict(
            method="NumPy/scipy loop, one record at a time",
            records=n_loop,
            seconds=loop_time,
            rate=loop_rate,
            ratio=1.0,
        ),
    ]
    table(
        "Occupant risk of 1 s records at 10 kHz (every metric): steady state",
        rows,
        [
            ("method", "method", "s"),
            ("records", "records", "d"),
            ("s", "seconds", ".2f"),
            ("records/s", "rate", ".0f"),
            ("x the loop", "ratio", ".1f"),
        ],
    )
    table(
        "barrierjax against the loop on 20 records (max difference over the largest value: "
        "exact crossings of the interpolated motion against the loop's chords)",
        [dict(metric=k, difference=v) for k, v in differences.items()],
        [("metric", "metric", "s"), ("max rel. difference", "difference", ".1e")],
    )
    setup = f"""
        import numpy as np
        from barrierjax.assess import occupant_risk
        from assess import records, T
        ax, ay, yaw = records({chunk}, 1)
    """
    first = first_calls(
        {
            "one record": (setup, "occupant_risk(T, ax[0], ay[0], yaw_rate=yaw[0])"),
            f"a chunk of {chunk}": (setup, "occupant_risk(T, ax, ay, yaw_rate=yaw)"),
        },
        steady_reps=2,
    )
    write_json(args, "assess", dict(steady=rows, agreement=differences, first_call=first))


if __name__ == "__main__":
    main()
