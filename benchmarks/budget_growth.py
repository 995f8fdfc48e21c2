"""What a few heavy vehicles cost a batch: the scenarios that spend the first step budget.

    python benchmarks/budget_growth.py [--quick] [--out DIR] [--seed N] [--before PATH]

A batch of `oblique_impact.py`'s box (10,000 scenarios; 512 with `--quick`) whose first k
scenarios are replaced by heavy vehicles that barely yield the barrier (log-uniform mass
ratio 50-300, phi - 1 from 2e-3 to 1e-2, the box's angles and speeds), of which about 60 %
spend the oblique model's first budget of 1,024 steps (measured on 32 of them: each solves
within 65,536). For the oblique and the axial models (axial ratio 0.5), rtol 1e-6, k = 0,
1, 10 and 100: the first call in a fresh process (tracing, compilation, every budget's
growth, one run), the steady time of the same call (best of 3) and the peak memory.
`--before PATH`: the same cases with the `barrierjax` package of another checkout (a folder
holding `barrierjax/`), side by side. Writes `budget_growth.json`.
"""

from pathlib import Path

from harness import argument_parser, first_call, table, write_json

_SETUP = """
    import numpy as np
    import oblique_impact as ob
    from barrierjax.hinge import axial_impact, oblique_impact
    rng = np.random.default_rng({seed})
    s = ob.draw({n}, rng)
    m, p, vn, vh, f = (np.array(s[k]) for k in ob.INPUTS)
    k = {heavy}
    log_uniform = lambda lo, hi: np.exp(rng.uniform(np.log(lo), np.log(hi), k))
    m[:k], p[:k] = log_uniform(50.0, 300.0), 1.0 + log_uniform(2e-3, 1e-2)
"""

MODELS = {
    "oblique (3.3)": "oblique_impact(m, p, vn, vh, friction=f, rtol=1e-6).exit_angle_deg",
    "axial (3.4)": "axial_impact(m, p, vn, 0.5 + 0.0 * m, rtol=1e-6).damage",
}


def run(n: int, seed: int, package=None) -> list:
    rows = []
    for model, call in MODELS.items():
        for heavy in (0, 1, 10, 100):
            setup = _SETUP.format(n=n, seed=seed, heavy=heavy)
            result = first_call(setup, call, timeout=900.0, steady_reps=3, package=package)
            row = dict(model=model, heavy=heavy, n=n, **result)
            if result["ok"]:
                row["us"] = result["steady_s"] / n * 1e6
                print(f"  {model}, {heavy} heavy: {result['first_call_s']:.1f} s first, "
                      f"{row['us']:.1f} us a scenario, {result['peak_rss_mb']:.0f} MB", flush=True)
            else:
                print(f"  {model}, {heavy} heavy: FAILED {result['failure']}", flush=True)
            rows.append(row)
    return rows


def main():
    parser = argument_parser(__doc__)
    parser.add_argument("--before", type=Path, help="a folder holding another checkout's barrierjax/")
    args = parser.parse_args()
    n = 512 if args.quick else 10_000
    print("after (this checkout):")
    rows = run(n, args.seed)
    columns = [("model", "model", "s"), ("heavy", "heavy", "d"), ("first call s", "first_call_s", ".1f"),
               ("us a scenario", "us", ".1f"), ("peak MB", "peak_rss_mb", ".0f")]
    if args.before:
        print(f"before ({args.before}):")
        for row, old in zip(rows, run(n, args.seed, package=args.before.resolve())):
            row.update({f"before_{key}": old.get(key) for key in ("first_call_s", "us", "peak_rss_mb")})
        columns = [columns[0], columns[1]] + [
            c for (label, key, fmt) in columns[2:] for c in ((f"{label}: before", f"before_{key}", fmt), (label, key, fmt))
        ]
    table(f"{n} scenarios of the box, the first k heavy vehicles; rtol 1e-6; fresh processes", rows, columns)
    for model in MODELS:
        by_heavy = {r["heavy"]: r for r in rows if r["model"] == model and r["ok"]}
        if 0 in by_heavy and 1 in by_heavy:
            ratio = lambda key: by_heavy[1][key] / by_heavy[0][key] if by_heavy[0].get(key) else float("nan")
            before = f" (before: {ratio('before_us'):.2f})" if args.before else ""
            print(f"SUMMARY: {model}, one heavy vehicle: {ratio('us'):.2f} times the box's time a scenario{before}")
    write_json(args, "budget_growth", {"rows": rows})


if __name__ == "__main__":
    main()
