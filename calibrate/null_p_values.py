#!/usr/bin/python3
"""Are the loop's p-values what they say on the blind passes' null twins (no planted effect, so the baseline
model is the truth and every p-value of its baseline fit should be about uniform)? A diagnostic; it decides
nothing.

    /usr/bin/python3 calibrate/null_p_values.py PASS_DIR [PASS_DIR...]

Reads each pass's null cases (folders null-*: summary.json, points.csv, and the twin's data file
twins/null-*.toml for its floor). Part 1: the baseline fit's p-values as the loop computed them (summary.json
"before": the fitted points on the response surface, which rule 1's gate and rule 5 read; the held-out points
on fresh seeds, which the held-out test reads; the fitted points on fresh seeds), each as the count below 0.05
and 0.10 against a uniform p's (with the binomial chance of at least that many), the quartiles, and the
Kolmogorov-Smirnov distance to uniform with its p. A uniform p is the reference with known variances; the
loop's are estimated from a few runs, which raises every point's chi^2 a little (below). Part 2: the
calibrations whose surface p is below 0.05, with each observable's sum of squared whitened residuals over
its points (points.csv residual_before, the surface's). Part 3, per observable, over every null's fitted
points: the mean square of those residuals with its se counted over the calibrations (the points of one
calibration share a surface and a fit), and what the stated se's give it: the share of the stated variance
that is not the data's floor, mean over the points of (e^2 - f^2 + se_s^2) / (e^2 + se_s^2) with e the
data's se (its floor f = hypot(relative x |value|, absolute) added in quadrature: the observable's [floors]
entry, else [observable] floor_relative; calibrate/data_file.cpp) and se_s the surface's, all on the fit scale; then that times a point's chi^2 for normal samples with variances estimated
from 10 data runs and 5 nodes of 6 (calibrate/tails_chi2.py, about 1.10); the share beyond 2.5 and 3 with
that construction's reference beside (about 2.1 % and 0.7 %; 1.24 % and 0.27 % with known variances); and
how often the observable holds a calibration's largest residual. Exit 2 on usage, or when no folder holds a
null case."""
import csv
import json
import math
import sys
import tomllib
from collections import defaultdict, namedtuple
from pathlib import Path

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tails_chi2 import SEED, normal_reference  # noqa: E402

LINEAR = {"exit_offset", "clog_share", "ln_s_plus_1"}   # calibrate/data_file.cpp default_scale (the blind twins
# keep every observable's default scale; a data file whose [observable] scale overrides it is not read right here)
SCORES = (("fitted (surface)", "fitted"), ("held-out (fresh seeds)", "held_out_fresh"),
          ("fitted (fresh seeds)", "fitted_fresh"))
Null = namedtuple("Null", "folder case summary rows floors")


def floors(twin):
    """{observable: (relative, absolute)} of a twin's data file: its [floors] entries, and under None the
    [observable] floor_relative that every other observable's points take (calibrate/data_file.hpp)."""
    if not twin.is_file():
        return {None: (0.0, 0.0)}
    with open(twin, "rb") as f:
        data = tomllib.load(f)
    out = {None: (data.get("observable", {}).get("floor_relative", 0.0), 0.0)}
    for kind, entry in data.get("floors", {}).items():
        out[kind] = (entry.get("relative", 0.0), entry.get("absolute", 0.0))
    return out


def nulls(folders):
    """Every null case of the folders, with its fitted points and its data floor (relative)."""
    out = []
    for folder in folders:
        for case in sorted(Path(folder).glob("null-*/summary.json")):
            with open(case) as f:
                summary = json.load(f)
            with open(case.parent / "points.csv", newline="") as f:
                rows = [r for r in csv.DictReader(f)
                        if r["held_out"] == "0" and r["residual_before"] not in ("", "nan")]
            out.append(Null(folder, case.parent.name, summary, rows,
                            floors(Path(folder, "twins", case.parent.name + ".toml"))))
    return out


def statistics_quantiles(ps):
    """The quartiles of a sample (linear interpolation between order statistics)."""
    return np.quantile(ps, [0.25, 0.5, 0.75])


def p_value_lines(cases):
    """Part 1: each score's p-values against a uniform's."""
    yield "| baseline p-value | nulls | below 0.05 (uniform; P at least) | below 0.10 (uniform; P at least) " \
          "| quartiles | KS distance (p) |"
    yield "| :-- | --: | :-- | :-- | :-- | :-- |"
    for name, key in SCORES:
        ps = [c.summary["before"][key]["p"] for c in cases if key in c.summary["before"]]
        n = len(ps)
        if n == 0:
            continue
        cells = []
        for a in (0.05, 0.10):
            k = sum(p < a for p in ps)
            cells.append(f"{k} ({n * a:.1f}; {stats.binom.sf(k - 1, n, a):.3f})")
        q = statistics_quantiles(ps)
        ks = stats.kstest(ps, "uniform")
        yield f"| {name} | {n} | {cells[0]} | {cells[1]} | {q[0]:.2f}, {q[1]:.2f}, {q[2]:.2f} " \
              f"| {ks.statistic:.3f} ({ks.pvalue:.3f}) |"


def low_p_lines(cases, observables):
    """Part 2: the calibrations whose surface p is below 0.05, each observable's sum of squares (points)."""
    yield "| pass | null | surface p | " + " | ".join(f"{o}: sum of squares (points)" for o in observables) + " |"
    yield "| :-- | :-- | --: |" + " --: |" * len(observables)
    for c in cases:
        if c.summary["before"]["fitted"]["p"] >= 0.05:
            continue
        sums = defaultdict(float)
        counts = defaultdict(int)
        for r in c.rows:
            sums[r["observable"]] += float(r["residual_before"]) ** 2
            counts[r["observable"]] += 1
        yield f"| {Path(c.folder).name} | {c.case} | {c.summary['before']['fitted']['p']:.3f} | " + \
            " | ".join(f"{sums[o]:.1f} ({counts[o]})" for o in observables) + " |"


def on_fit_scale(observable, value, se):
    return se if observable in LINEAR else se / abs(value)


def stated_share(row, floor_of):
    """The share of a point's stated variance that is not the data's floor (fit scale)."""
    o, value = row["observable"], float(row["value"])
    e = on_fit_scale(o, value, float(row["se"]))
    se_s = on_fit_scale(o, float(row["before"]), float(row["before_se"]))
    relative, absolute = floor_of.get(o, floor_of[None])
    f = on_fit_scale(o, value, math.hypot(relative * abs(value), absolute))
    return (max(e * e - f * f, 0.0) + se_s * se_s) / (e * e + se_s * se_s)


def clustered_mean(per_case):
    """The ratio mean sum(S)/sum(n) over calibrations [(S, n)] and its se counted over the calibrations."""
    k = len(per_case)
    total, n = sum(s for s, _ in per_case), sum(m for _, m in per_case)
    mean = total / n
    if k < 2:
        return mean, math.nan
    spread = sum((s - mean * m) ** 2 for s, m in per_case) / (k * (k - 1))
    return mean, math.sqrt(spread) / (n / k)


def observable_lines(cases, observables, reference):
    """Part 3: per observable, the residuals' mean square against what the stated se's give it."""
    chi2_normal = reference["chi2 own"][0]
    beyond = reference["chi2 own beyond 6.25"][0], reference["chi2 own beyond 9"][0]
    yield "| observable | points | mean square (se over calibrations) | not floor (share of the stated variance) " \
          f"| expected (x {chi2_normal:.3f}) | beyond 2.5 (reference {100 * beyond[0]:.2f} %) " \
          f"| beyond 3 (reference {100 * beyond[1]:.2f} %) | holds the largest |"
    yield "| :-- | --: | :-- | --: | --: | --: | --: | --: |"
    largest = defaultdict(int)
    for c in cases:
        if c.rows:
            largest[max(c.rows, key=lambda r: abs(float(r["residual_before"])))["observable"]] += 1
    for o in observables:
        per_case, squares, shares = [], [], []
        for c in cases:
            xs = [float(r["residual_before"]) ** 2 for r in c.rows if r["observable"] == o]
            if xs:
                per_case.append((sum(xs), len(xs)))
                squares += xs
                shares += [stated_share(r, c.floors) for r in c.rows if r["observable"] == o]
        mean, se = clustered_mean(per_case)
        share = sum(shares) / len(shares)
        n = len(squares)
        yield f"| {o} | {n} | {mean:.3f} ({se:.3f}) | {share:.3f} | {share * chi2_normal:.3f} " \
              f"| {100 * sum(x > 6.25 for x in squares) / n:.2f} % | {100 * sum(x > 9 for x in squares) / n:.2f} % " \
              f"| {largest[o]} |"


def main():
    folders = sys.argv[1:]
    if not folders or not all(Path(f).is_dir() for f in folders):
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    cases = nulls(folders)
    if not cases:
        print(f"error: no null-* case with summary.json in {' '.join(folders)}", file=sys.stderr)
        sys.exit(2)
    observables = sorted({r["observable"] for c in cases for r in c.rows})
    reference = normal_reference(np.random.default_rng(SEED))
    print(f"{len(cases)} null calibrations in {len(folders)} folders")
    for part in (p_value_lines(cases), low_p_lines(cases, observables),
                 observable_lines(cases, observables, reference)):
        print()
        for line in part:
            print(line)


if __name__ == "__main__":
    main()
