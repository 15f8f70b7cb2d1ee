#!/usr/bin/env python3
"""Convergence table of a study store: every point against a reference point.

Usage: studies/convergence_table.py STORE.sqlite --reference SERIES:POINT [--model 2d]
                                    [--tolerance 0.01] [--markdown]

For every (series, point) of the store: replicates, mean J_paper and J_mid with Student-t
95 % intervals, the relative difference to the reference point with a Welch 95 % interval
(runs at different settings are independent: with the same seeds they decorrelate within a
second of flow, measured rho 0.1-0.3, so no pairing is claimed), the verdict against the
tolerance, and the cost: CPU seconds of stepping per simulated second (wall time of a run
on one worker thread). A setting "converged" when the whole interval of its difference
lies inside +-tolerance; "within" when its mean is inside but the interval is not;
"diverged" when the whole interval lies outside.

Reads only the store (sqlite3 from Python's standard library); writes to stdout.
"""
import argparse
import json
import math
import sqlite3
import statistics
import sys

# Student-t 0.975 quantiles (two-sided 95 %) for small df; beyond 60 the normal value is
# within 1.5 %. Python's standard library has no t distribution.
T975 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306, 9: 2.262,
        10: 2.228, 12: 2.179, 15: 2.131, 20: 2.086, 25: 2.060, 30: 2.042, 40: 2.021, 60: 2.000,
        120: 1.980}


def t975(df):
    if df <= 0:
        return float("inf")
    keys = sorted(T975)
    for k in keys:
        if df <= k:
            return T975[k]
    return 1.960


def mean_ci(xs):
    n = len(xs)
    m = statistics.fmean(xs)
    if n < 2:
        return m, float("inf"), float("nan")
    s = statistics.stdev(xs)
    return m, t975(n - 1) * s / math.sqrt(n), s


def welch_ratio(a, b):
    """Relative difference mean(a)/mean(b) - 1 with a 95 % interval (delta method, Welch df)."""
    ma, mb = statistics.fmean(a), statistics.fmean(b)
    va, vb = statistics.variance(a) / len(a), statistics.variance(b) / len(b)
    r = ma / mb
    se = r * math.sqrt(va / ma**2 + vb / mb**2)
    df = (va + vb) ** 2 / (va**2 / (len(a) - 1) + vb**2 / (len(b) - 1))
    return r - 1, t975(int(df)) * se


def verdict(diff, half, tol):
    if abs(diff) + half <= tol:
        return "converged"
    if abs(diff) - half > tol:
        return "diverged"
    return "within" if abs(diff) <= tol else "outside"


def load(store, model):
    con = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    rows = con.execute(
        "SELECT series, point, point_label, axes_json, j_paper, j_mid, wall_time_s, sim_time_s, time_step_s "
        "FROM runs WHERE model = ? ORDER BY series, point, replicate", (model,)).fetchall()
    points = {}
    for series, point, label, axes, jp, jm, wall, sim, dt in rows:
        p = points.setdefault((series, point), {"label": label, "axes": json.loads(axes), "jp": [], "jm": [],
                                                "wall": 0.0, "sim": 0.0, "dt": dt, "n": 0})
        p["n"] += 1
        p["wall"] += wall
        p["sim"] += sim
        if jp is not None:
            p["jp"].append(jp)
        if jm is not None:
            p["jm"].append(jm)
    return points


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store")
    ap.add_argument("--reference", required=True, help="SERIES:POINT of the reference setting")
    ap.add_argument("--model", default="2d")
    ap.add_argument("--tolerance", type=float, default=0.01, help="relative tolerance on J (default 0.01)")
    args = ap.parse_args()

    points = load(args.store, args.model)
    ref_series, _, ref_point = args.reference.rpartition(":")
    ref = points.get((ref_series, int(ref_point)))
    if ref is None:
        sys.exit(f"{args.store}: no point {args.reference} for model {args.model}")
    ref_cost = ref["wall"] / ref["sim"]

    print(f"Reference: series '{ref_series}' point {ref_point} ({ref['label']}), tolerance +-{100 * args.tolerance:g} %\n")
    print("| series | setting | runs | J_paper /s | vs ref | J_mid /s | vs ref | verdict (paper / mid) "
          "| CPU s per sim s | speed-up vs ref |")
    print("|---|---|---:|---|---|---|---|---|---:|---:|")
    for (series, point), p in sorted(points.items(), key=lambda kv: (kv[0][0], -kv[1]["dt"])):
        cells = []
        verdicts = []
        for key in ("jp", "jm"):
            m, h, _ = mean_ci(p[key])
            cells.append(f"{m:.2f} ± {h:.2f}")
            if (series, point) == (ref_series, int(ref_point)):
                cells.append("reference")
                verdicts.append("-")
            else:
                d, dh = welch_ratio(p[key], ref[key])
                cells.append(f"{100 * d:+.2f} ± {100 * dh:.2f} %")
                verdicts.append(verdict(d, dh, args.tolerance))
        cost = p["wall"] / p["sim"]
        print(f"| {series} | {p['label']} | {p['n']} | {cells[0]} | {cells[1]} | {cells[2]} | {cells[3]} "
              f"| {' / '.join(verdicts)} | {cost:.3f} | {ref_cost / cost:.1f}× |")


if __name__ == "__main__":
    main()
