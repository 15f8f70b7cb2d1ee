#!/usr/bin/python3
"""Convergence table of a study store: every point against a reference point.

Usage: studies/convergence_table.py STORE.sqlite --reference SERIES[@LABEL] [--model 2d]
                                    [--tolerance 0.01] [--fit SERIES]... [--avalanches]

For every (series, point) of the store: replicates, mean J_paper and J_mid with Student-t
95 % intervals, the relative difference to the reference point with a Welch 95 % interval
(runs at different settings are independent: with the same seeds they decorrelate within a
second of flow, measured rho 0.1-0.3, so no pairing is claimed), the verdict against the
tolerance (costs are measured elsewhere: wall times in a store include waiting on a loaded
machine). A setting "converged" when the whole interval of its difference
lies inside +-tolerance; "within" when its mean is inside but the interval is not; "outside" when the mean is outside but the interval is not;
"diverged" when the whole interval lies outside.

Reads only the store (sqlite3 from Python's standard library); writes to stdout. Runs with Debian's\n/usr/bin/python3 (python3-scipy for the t quantile).
"""
import argparse
import math
import sqlite3
import statistics
import sys

import scipy.stats

def t975(df):
    """Two-sided 95 % Student-t quantile (Debian's python3-scipy)."""
    return float(scipy.stats.t.ppf(0.975, df)) if df > 0 else float("inf")


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
        "SELECT series, point_label, j_paper, j_mid, time_step_s "
        "FROM runs WHERE model = ? ORDER BY series, point, replicate", (model,)).fetchall()
    points = {}
    for series, label, jp, jm, dt in rows:
        p = points.setdefault((series, label), {"label": label, "jp": [], "jm": [], "dt": dt, "n": 0})
        p["n"] += 1
        if jp is not None:
            p["jp"].append(jp)
        if jm is not None:
            p["jm"].append(jm)
    return points


def reference_key(points, reference, store):
    """(series, label) of --reference SERIES[@LABEL]; the label may be left out when the series has one point.

    Points are keyed by their label, not their index: a series whose sweep gained a value keeps
    its stored runs under their old indices."""
    series, _, label = reference.partition("@")
    labels = [l for (s, l) in points if s == series]
    if label:
        if label not in labels:
            sys.exit(f"{store}: no point '{label}' in series '{series}' (points: {labels})")
        return series, label
    if len(labels) != 1:
        sys.exit(f"{store}: series '{series}' has {len(labels)} points; name one as {series}@LABEL (points: {labels})")
    return series, labels[0]


def avalanche_sizes(store, model):
    """{(series, point): (label, [(sum of sizes, avalanches) per run])}: avalanches that are neither
    a run's first (it starts from the initial packing) nor censored (cut by the end of the run)."""
    con = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    rows = con.execute(
        "SELECT r.series, r.point, r.point_label, r.job_key, COALESCE(SUM(a.size), 0), COUNT(a.size) FROM runs r "
        "LEFT JOIN avalanches a ON a.job_key = r.job_key AND a.\"first\" = 0 AND a.censored = 0 "
        "WHERE r.model = ? GROUP BY r.job_key ORDER BY r.series, r.point, r.replicate", (model,)).fetchall()
    out = {}
    for series, _, label, _, total, count in rows:
        out.setdefault((series, label), (label, []))[1].append((total, count))
    return out


def ratio_estimate(runs):
    """<s> = sum S / sum N over runs, with its standard error clustered by run (runs are independent,
    avalanches within a run are not); intervals use Student-t with runs - 1 degrees of freedom."""
    n = len(runs)
    total, count = sum(s for s, _ in runs), sum(c for _, c in runs)
    mean = total / count
    nbar = count / n
    var = sum((s - mean * c) ** 2 for s, c in runs) / (n * (n - 1)) / nbar**2
    return mean, math.sqrt(var), count


def avalanche_table(args):
    points = avalanche_sizes(args.store, args.model)
    ref_key = reference_key(points, args.reference, args.store)
    ref = points[ref_key]
    rm, rse, _ = ratio_estimate(ref[1])
    print(f"Mean avalanche size <s> (neither first nor censored; 95 % intervals clustered by run), reference "
          f"'{ref_key[0]}' {ref_key[1]}\n")
    print("| series | setting | runs | avalanches | <s> | vs ref |")
    print("|---|---|---:|---:|---|---|")
    for (series, _), (label, runs) in sorted(points.items()):
        m, se, count = ratio_estimate(runs)
        if (series, label) == ref_key:
            rel = "reference"
        else:
            r = m / rm
            t = t975(min(len(runs), len(ref[1])) - 1)  # conservative df
            rel = f"{100 * (r - 1):+.1f} ± {100 * t * r * math.sqrt((se / m) ** 2 + (rse / rm) ** 2):.1f} %"
        print(f"| {series} | {label} | {len(runs)} | {count} | {m:.1f} ± {t975(len(runs) - 1) * se:.1f} | {rel} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store")
    ap.add_argument("--reference", required=True, help="SERIES[@LABEL] of the reference setting")
    ap.add_argument("--model", default="2d")
    ap.add_argument("--tolerance", type=float, default=0.01, help="relative tolerance on J (default 0.01)")
    ap.add_argument("--avalanches", action="store_true",
                    help="compare mean avalanche sizes <s> instead of J (clogging studies)")
    ap.add_argument("--fit", action="append", default=[], metavar="SERIES",
                    help="fit J = J(0) (1 + a dt) over the series' points (weighted least squares)")
    args = ap.parse_args()

    if args.avalanches:
        avalanche_table(args)
        return
    points = load(args.store, args.model)
    ref_key = reference_key(points, args.reference, args.store)
    ref = points[ref_key]

    print(f"Reference: series '{ref_key[0]}' {ref_key[1]}, tolerance +-{100 * args.tolerance:g} %\n")
    print("| series | setting | runs | J_paper /s | vs ref | J_mid /s | vs ref | verdict (paper / mid) |")
    print("|---|---|---:|---|---|---|---|---|")
    for (series, label), p in sorted(points.items(), key=lambda kv: (kv[0][0], -kv[1]["dt"])):
        cells = []
        verdicts = []
        for key in ("jp", "jm"):
            m, h, _ = mean_ci(p[key])
            cells.append(f"{m:.2f} ± {h:.2f}")
            if (series, label) == ref_key:
                cells.append("reference")
                verdicts.append("-")
            else:
                d, dh = welch_ratio(p[key], ref[key])
                cells.append(f"{100 * d:+.2f} ± {100 * dh:.2f} %")
                verdicts.append(verdict(d, dh, args.tolerance))
        print(f"| {series} | {p['label'] or '(no sweep)'} | {p['n']} | {cells[0]} | {cells[1]} | {cells[2]} | {cells[3]} "
              f"| {' / '.join(verdicts)} |")
    print_fits(points, args.fit)


def linear_fit(points, series, key):
    """Weighted least squares of mean J against dt over one series: J = b0 + b1 dt.

    Returns (J0, J0 half-width, a = b1/b0 per second, a half-width, chi2, dof) with 95 % intervals
    from the covariance of (b0, b1) scaled by max(1, chi2/dof) (delta method for the ratio), with a
    Student-t quantile (dof) when the scale was estimated (chi2/dof > 1)."""
    xs, ys, ws = [], [], []
    for (s, _), p in points.items():
        if s != series or len(p[key]) < 2:
            continue
        m, _, sd = mean_ci(p[key])
        xs.append(p["dt"])
        ys.append(m)
        ws.append(len(p[key]) / sd**2)
    if len(xs) < 3:
        return None
    return weighted_line(xs, ys, ws)


def weighted_line(xs, ys, ws):
    """Weighted least squares y = b0 + b1 x (weights 1/variance), as described in linear_fit."""
    sw = sum(ws)
    sx = sum(w * x for w, x in zip(ws, xs))
    sy = sum(w * y for w, y in zip(ws, ys))
    sxx = sum(w * x * x for w, x in zip(ws, xs))
    sxy = sum(w * x * y for w, x, y in zip(ws, xs, ys))
    det = sw * sxx - sx * sx
    b1 = (sw * sxy - sx * sy) / det
    b0 = (sy - b1 * sx) / sw
    chi2 = sum(w * (y - b0 - b1 * x) ** 2 for w, x, y in zip(ws, xs, ys))
    dof = len(xs) - 2
    scale = max(1.0, chi2 / dof)
    v00, v11, v01 = scale * sxx / det, scale * sw / det, -scale * sx / det
    a = b1 / b0
    va = a**2 * (v11 / b1**2 + v00 / b0**2 - 2 * v01 / (b0 * b1))
    # A scale estimated from the residuals has dof degrees of freedom: Student-t then, not the normal.
    q = t975(dof) if chi2 / dof > 1.0 else 1.96
    return b0, q * math.sqrt(v00), a, q * math.sqrt(va), chi2, dof


def print_fits(points, fits):
    if not fits:
        return
    print("\nFirst-order step error, J(dt) = J(0) (1 + a dt), weighted least squares over each series' steps "
          "(95 % intervals; when chi2/dof > 1 the covariance is widened by it and the quantile is Student-t with dof):\n")
    print("| series | J | J(0) /s | a (per ms) | error at 1 ms | error at 2 ms | chi2 / dof |")
    print("|---|---|---|---|---|---|---|")
    for series in fits:
        for key, name in (("jp", "J_paper"), ("jm", "J_mid")):
            f = linear_fit(points, series, key)
            if f is None:
                print(f"| {series} | {name} | fewer than 3 steps | | | | |")
                continue
            j0, j0h, a, ah, chi2, dof = f
            print(f"| {series} | {name} | {j0:.2f} ± {j0h:.2f} | {100 * a / 1000:+.2f} ± {100 * ah / 1000:.2f} % "
                  f"| {100 * a * 0.001:+.2f} ± {100 * ah * 0.001:.2f} % | {100 * a * 0.002:+.2f} ± {100 * ah * 0.002:.2f} % "
                  f"| {chi2:.1f} / {dof} |")


if __name__ == "__main__":
    main()
