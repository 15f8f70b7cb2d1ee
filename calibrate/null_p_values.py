#!/usr/bin/python3
"""Are the loop's p-values what they say on the blind passes' null twins (no planted effect, so the baseline
model is the truth and every p-value of its baseline fit should be uniform)? A diagnostic; it decides nothing.

    /usr/bin/python3 calibrate/null_p_values.py PASS_DIR [PASS_DIR...]

Reads each pass's null cases (folders null-*; summary.json, points.csv). Part 1: the baseline fit's p-values
as the loop computed them (summary.json "before": the fitted points on the response surface, which rule 1's
gate and rule 5 read; the held-out points on fresh seeds, which the held-out test reads; and the fitted points
on fresh seeds), each as the count below 0.05 and 0.10 against the count a uniform p gives (with its binomial
tail probability: the chance of at least that many), the quartiles, and the Kolmogorov-Smirnov distance to
uniform with its p. Part 2, per observable: the fitted points' whitened baseline residuals (points.csv
residual_before, the surface's), their mean square (1 where the stated se holds; the sample variances' own
scatter raises it a little, about 1.08-1.10 at 10 data runs and 6 model replicates: calibrate/tails_chi2.py's
"normal" column), the share beyond 2.5 (a normal's 1.24 %) and beyond 3 (0.27 %), and how often the observable
holds the calibration's largest residual. Exit 2 on usage or a folder without null cases."""
import csv
import json
import math
import sys
from collections import defaultdict
from pathlib import Path

from scipy import stats

SCORES = (("fitted (surface)", "fitted"), ("held-out (fresh seeds)", "held_out_fresh"),
          ("fitted (fresh seeds)", "fitted_fresh"))


def nulls(folders):
    """[(folder, case, summary, fitted point rows)] of every null case."""
    out = []
    for folder in folders:
        for case in sorted(Path(folder).glob("null-*/summary.json")):
            with open(case) as f:
                summary = json.load(f)
            with open(case.parent / "points.csv", newline="") as f:
                rows = [r for r in csv.DictReader(f)
                        if r["held_out"] == "0" and r["residual_before"] not in ("", "nan")]
            out.append((folder, case.parent.name, summary, rows))
    return out


def p_value_lines(cases):
    yield "| baseline p-value | nulls | below 0.05 (uniform; P at least) | below 0.10 (uniform; P at least) " \
          "| quartiles | KS distance (p) |"
    yield "| :-- | --: | :-- | :-- | :-- | :-- |"
    for name, key in SCORES:
        ps = sorted(c[2]["before"][key]["p"] for c in cases if key in c[2]["before"])
        n = len(ps)
        if n == 0:
            continue
        cells = []
        for a in (0.05, 0.10):
            k = sum(p < a for p in ps)
            cells.append(f"{k} ({n * a:.1f}; {stats.binom.sf(k - 1, n, a):.3f})")
        q = [ps[min(n - 1, int(round(f * (n - 1))))] for f in (0.25, 0.5, 0.75)]
        ks = stats.kstest(ps, "uniform")
        yield f"| {name} | {n} | {cells[0]} | {cells[1]} | {q[0]:.2f}, {q[1]:.2f}, {q[2]:.2f} " \
              f"| {ks.statistic:.3f} ({ks.pvalue:.3f}) |"


def observable_lines(cases):
    squares = defaultdict(list)
    largest = defaultdict(int)
    for _, _, _, rows in cases:
        if not rows:
            continue
        for r in rows:
            squares[r["observable"]].append(float(r["residual_before"]) ** 2)
        top = max(rows, key=lambda r: abs(float(r["residual_before"])))
        largest[top["observable"]] += 1
    yield "| observable | points | mean square (se) | beyond 2.5 (normal 1.24 %) | beyond 3 (normal 0.27 %) " \
          "| holds the largest |"
    yield "| :-- | --: | :-- | --: | --: | --: |"
    for o in sorted(squares):
        xs = squares[o]
        n = len(xs)
        mean = sum(xs) / n
        se = math.sqrt(sum((x - mean) ** 2 for x in xs) / (n - 1) / n) if n > 1 else math.nan
        yield f"| {o} | {n} | {mean:.3f} ({se:.3f}) | {100 * sum(x > 6.25 for x in xs) / n:.2f} % " \
              f"| {100 * sum(x > 9 for x in xs) / n:.2f} % | {largest[o]} |"


def main():
    folders = sys.argv[1:]
    if not folders or not all(Path(f).is_dir() for f in folders):
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    cases = nulls(folders)
    if not cases:
        print(f"error: no null-* case with summary.json in {' '.join(folders)}", file=sys.stderr)
        sys.exit(2)
    print(f"{len(cases)} null calibrations in {len(folders)} folders")
    print()
    for line in p_value_lines(cases):
        print(line)
    print()
    for line in observable_lines(cases):
        print(line)


if __name__ == "__main__":
    main()
