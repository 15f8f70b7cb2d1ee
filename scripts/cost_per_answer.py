#!/usr/bin/python3
"""CPU-seconds per answer from a study store (issue 15, item 6).

Usage: scripts/cost_per_answer.py STORE --baseline SERIES --point SERIES --cpu-per-run S
                                  [--model 2d] [--j paper] [--label TEXT]

Two answers, for the protocol the store's runs used:
  1. J_0 to +-2 % (95 %): replicates n with t(n-1) cv / sqrt(n) <= 0.02, times the CPU of a run;
  2. "does the point differ from J_0 by 3 %?" (two-sided 5 %, power 80 %): n per arm from the
     normal approximation n = (z_0.975 + z_0.8)^2 var / 0.03^2 with var = cv_0^2 + cv_1^2
     (unpaired) or cv_0^2 + cv_1^2 - 2 rho cv_0 cv_1 (paired by replicate: same seeds, same
     particle sets), times 2 runs per replicate pair.
The cv come from the store (sample standard deviation over the mean); the run-to-run spread of
a sample of n runs is itself uncertain, so each cost carries the 95 % range that the chi-square
interval of the standard deviation gives (Debian's python3-scipy for the quantiles). CPU per run is measured
by the caller (the store's wall times include waiting on a loaded machine).
Prints one markdown table row per answer.
"""
import argparse
import math
import sqlite3
import statistics

import scipy.stats

Z975, Z80 = float(scipy.stats.norm.ppf(0.975)), float(scipy.stats.norm.ppf(0.8))


def t975(df):
    return float(scipy.stats.t.ppf(0.975, df))


def chi2_quantile(p, df):
    return float(scipy.stats.chi2.ppf(p, df))


def sd_range(n):
    """Factors (low, high) on a sample standard deviation for its 95 % interval."""
    df = n - 1
    return math.sqrt(df / chi2_quantile(0.975, df)), math.sqrt(df / chi2_quantile(0.025, df))


def runs_for_halfwidth(cv, rel):
    n = 2
    while t975(n - 1) * cv / math.sqrt(n) > rel:
        n += 1
    return n


def load(store, model, where, column):
    """{replicate: J} of one point: `where` is SERIES or SERIES:POINT (point index in the series)."""
    series, _, point = where.partition(":")
    con = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    sql = f"SELECT replicate, {column} FROM runs WHERE model = ? AND series = ? AND {column} IS NOT NULL"
    args = [model, series]
    if point:
        sql += " AND point = ?"
        args.append(int(point))
    rows = con.execute(sql, args).fetchall()
    if len({r for r, _ in rows}) != len(rows):
        raise SystemExit(f"{store}: series '{series}' has several points; name one as {series}:POINT")
    if len(rows) < 3:
        raise SystemExit(f"{store}: fewer than 3 runs with {column} at '{where}' ({model})")
    return dict(rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store")
    ap.add_argument("--baseline", required=True, help="SERIES[:POINT] of the no-obstruction point")
    ap.add_argument("--point", required=True, help="SERIES[:POINT] of the obstruction point")
    ap.add_argument("--cpu-per-run", type=float, required=True, help="CPU seconds of one run (measured)")
    ap.add_argument("--model", default="2d")
    ap.add_argument("--j", default="paper", choices=["paper", "flowing", "mid"])
    ap.add_argument("--label", default="")
    a = ap.parse_args()

    col = "j_" + a.j
    j0, j1 = load(a.store, a.model, a.baseline, col), load(a.store, a.model, a.point, col)
    x0, x1 = list(j0.values()), list(j1.values())
    cv0 = statistics.stdev(x0) / statistics.fmean(x0)
    cv1 = statistics.stdev(x1) / statistics.fmean(x1)
    common = sorted(set(j0) & set(j1))
    rho = statistics.correlation([j0[r] for r in common], [j1[r] for r in common]) if len(common) > 2 else 0.0
    lo, hi = sd_range(len(x0))

    n_est = runs_for_halfwidth(cv0, 0.02)
    n_lo, n_hi = runs_for_halfwidth(cv0 * lo, 0.02), runs_for_halfwidth(cv0 * hi, 0.02)
    var_unpaired = cv0**2 + cv1**2
    var_paired = max(0.0, var_unpaired - 2 * rho * cv0 * cv1)
    k = (Z975 + Z80) ** 2 / 0.03**2
    n_dec = math.ceil(k * var_unpaired)
    n_dec_p = math.ceil(k * var_paired)
    c = a.cpu_per_run
    label = a.label or f"{a.store} ({a.model}, J_{a.j})"
    print(f"| {label} | J_0 = {statistics.fmean(x0):.2f} /s, cv {100 * cv0:.1f} % (n = {len(x0)}) "
          f"| {c:.1f} | {n_est} runs: **{n_est * c:.0f}** CPU-s ({n_lo * c:.0f}-{n_hi * c:.0f}) "
          f"| cv_1 {100 * cv1:.1f} %, rho {rho:+.2f} (n = {len(common)} pairs) "
          f"| {n_dec} per arm: **{2 * n_dec * c:.0f}** CPU-s unpaired; {n_dec_p} per arm: {2 * n_dec_p * c:.0f} CPU-s paired |")


if __name__ == "__main__":
    main()
