"""Benchmark of large batches solved in parts, one a core (`barrierjax._solve.batching`).

    python benchmarks/parts.py [--quick] [--out DIR] [--seed N] [--rounds N] [--only WORD ...]
                               [--compare PATH] [--slower X]

A model called on concrete arrays of 1,024 scenarios or more splits them, on a CPU, into
equal parts called from threads of their own, so that each core runs one part's program.
Each case runs in a fresh process twice: with `BARRIERJAX_PARTS=1` (the whole batch as
one program, as before) and as shipped (as many parts as cores, at most 8, at least 512
scenarios each); the two alternate, `--rounds` times, so that the machine's drift falls on
both. Per case: the time per scenario (the best of 5 calls after the first, in each round;
the median over rounds), the speed-up, the median and slowest of every call timed (the best
hides calls whose parts ran one after the other), and each configuration's first call
(tracing, compilation and one run) and peak memory. The scenarios are `oblique_impact.py`'s box
(log-uniform mass ratio 0.1-10, force ratio 1.1-8, angle 5-85 degrees, speed 0.1-1; friction
0.1-0.4 on every third); the normal models take its mass ratio, force ratio and normal
speed; the axial model an axial ratio of 0.5. rtol 1e-6 for the three integrations.
`--only`: the cases whose label ("model, scenarios", e.g. "oblique (3.3), 10000") holds one
of the words. `--compare PATH`: an earlier run's parts.json, each case's time beside its own
there, flagged where more than `--slower` (1.5) times it (the axial batch ran 3.2 times
slower for three days before a full run showed it). Where the oblique model and the normal
ODE ran on the same scenarios, their ratio per scenario (issue 28's sweep criterion) closes
the summary. Writes `parts.json` to `--out`.
"""

import json
import os
import statistics
from pathlib import Path

from harness import argument_parser, first_call, first_call_table, table, write_json

MODELS = {
    "normal, closed form": "normal_impact(m, p, vn)",
    "normal, ODE": 'normal_impact(m, p, vn, method="ode", rtol=1e-6)',
    "axial (3.4)": "axial_impact(m, p, vn, 0.5 + 0.0 * m, rtol=1e-6)",
    "oblique (3.3)": "oblique_impact(m, p, vn, vh, friction=f, rtol=1e-6)",
}

SETUP = """
    import numpy as np
    import oblique_impact as ob
    from barrierjax.hinge import axial_impact, normal_impact, oblique_impact
    s = ob.draw({n}, np.random.default_rng({seed}))
    m, p, vn, vh, f = (s[k] for k in ob.INPUTS)
"""


def cases(quick: bool) -> list:
    if quick:
        return [("normal, ODE", 2048)]
    sizes = {"normal, closed form": (10_000, 100_000), "normal, ODE": (2048, 10_000, 100_000)}
    return [(model, n) for model in MODELS for n in sizes.get(model, (2048, 10_000))]


def measure(model: str, n: int, seed: int, rounds: int) -> dict:
    runs = {"one": [], "parts": []}
    for _ in range(rounds):
        for label, env in (("one", {"BARRIERJAX_PARTS": "1"}), ("parts", {})):
            setup = SETUP.format(n=n, seed=seed)
            runs[label].append(first_call(setup, MODELS[model], steady_reps=5, env=env))
    row = {"model": model, "n": n, "cores": len(os.sched_getaffinity(0))}
    failed = [r for rs in runs.values() for r in rs if not r["ok"]]
    if failed:
        return dict(row, ok=False, failure=failed[0]["failure"])
    for label, rs in runs.items():
        row[f"{label}_us"] = statistics.median(r["steady_s"] for r in rs) / n * 1e6
        row[f"{label}_first_s"] = statistics.median(r["first_call_s"] for r in rs)
        row[f"{label}_peak_mb"] = max(r["peak_rss_mb"] for r in rs)
        row[f"{label}_runs_us"] = [r["steady_s"] / n * 1e6 for r in rs]
        calls = [t / n * 1e6 for r in rs for t in r["steady_runs_s"]]
        row[f"{label}_median_call_us"] = statistics.median(calls)
        row[f"{label}_slowest_call_us"] = max(calls)
    row["speedup"] = row["one_us"] / row["parts_us"]
    return dict(row, ok=True, first_calls=runs)


def compared(rows: list, reference: list, slower: float) -> list:
    """Each case's time per scenario beside the same case's in `reference` (the rows of an
    earlier run's parts.json), whole and in parts; `slower` where either is more than
    `slower` times its reference."""
    earlier = {(r["model"], r["n"]): r for r in reference if r.get("ok")}
    out = []
    for r in rows:
        before = earlier.get((r["model"], r["n"])) if r["ok"] else None
        if before is None:
            continue
        ratios = {k: r[f"{k}_us"] / before[f"{k}_us"] for k in ("one", "parts")}
        out.append(dict(model=r["model"], n=r["n"],
                        one_before_us=before["one_us"], one_us=r["one_us"],
                        parts_before_us=before["parts_us"], parts_us=r["parts_us"],
                        one_ratio=ratios["one"], parts_ratio=ratios["parts"],
                        slower=max(ratios.values()) > slower))  # fmt: skip
    return out


def main():
    parser = argument_parser(__doc__)
    parser.add_argument("--rounds", type=int, default=2, help="alternating rounds per case")
    parser.add_argument("--only", nargs="*", default=(), help="cases whose label holds one of these words")
    parser.add_argument("--compare", type=Path, help="an earlier run's parts.json")
    parser.add_argument("--slower", type=float, default=1.5, help="flag this many times slower")
    args = parser.parse_args()
    rounds = 1 if args.quick else args.rounds
    selected = [
        (model, n) for model, n in cases(args.quick) if not args.only or any(w in f"{model}, {n}" for w in args.only)
    ]
    rows = [measure(model, n, args.seed, rounds) for model, n in selected]
    first = [
        dict(case=f"{r['model']}, {r['n']}, {label}", **r["first_calls"][label][0])
        for r in rows
        if r["ok"]
        for label in ("one", "parts")
    ]
    first_call_table(first)
    table(
        f"SUMMARY: us a scenario, the batch whole (BARRIERJAX_PARTS=1) and in parts, "
        f"median of {rounds} alternating fresh processes (best of 5 calls in each)",
        rows,
        [("model", "model", "s"), ("scenarios", "n", "d"), ("whole us", "one_us", ".2f"),
         ("parts us", "parts_us", ".2f"), ("speed-up", "speedup", ".2f"),
         ("median call us whole / parts", "one_median_call_us", ".2f"),
         ("", "parts_median_call_us", ".2f"),
         ("slowest call us whole / parts", "one_slowest_call_us", ".2f"),
         ("", "parts_slowest_call_us", ".2f"),
         ("first s whole / parts", "one_first_s", ".1f"), ("", "parts_first_s", ".1f"),
         ("peak MB whole / parts", "one_peak_mb", ".0f"), ("", "parts_peak_mb", ".0f")],
    )  # fmt: skip
    ode = {r["n"]: r for r in rows if r["ok"] and r["model"] == "normal, ODE"}
    for r in rows:
        if r["ok"] and r["model"] == "oblique (3.3)" and r["n"] in ode:
            ratio = lambda key: r[key] / ode[r["n"]][key]
            r["over_normal_ode"] = {k: ratio(f"{k}_us") for k in ("one", "parts")}
            r["over_normal_ode_median_call"] = {
                k: ratio(f"{k}_median_call_us") for k in ("one", "parts")
            }
            print(f"oblique / normal ODE per scenario at {r['n']}: whole {r['over_normal_ode']['one']:.2f}, "
                  f"in parts {r['over_normal_ode']['parts']:.2f} (medians of every call: whole "
                  f"{r['over_normal_ode_median_call']['one']:.2f}, in parts "
                  f"{r['over_normal_ode_median_call']['parts']:.2f})")
    for r in rows:
        r.pop("first_calls", None)
    results = {"first_call": first, "parts": rows}
    if args.compare:
        earlier = json.loads(args.compare.read_text())["parts"]
        results["compared"] = compared(rows, earlier, args.slower)
        table(
            f"Against {args.compare}: us a scenario then and now "
            f"(slower: more than {args.slower} times)",
            results["compared"],
            [("model", "model", "s"), ("scenarios", "n", "d"),
             ("whole then", "one_before_us", ".2f"), ("now", "one_us", ".2f"),
             ("in parts then", "parts_before_us", ".2f"), ("now", "parts_us", ".2f"),
             ("ratio whole / parts", "one_ratio", ".2f"), ("", "parts_ratio", ".2f"),
             ("slower", "slower", "s")],
        )  # fmt: skip
    write_json(args, "parts", results, rounds=rounds)


if __name__ == "__main__":
    main()
