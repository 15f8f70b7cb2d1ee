#!/usr/bin/env python3
"""How far from normal a point's replicates are: per study point and observable (on the loop's fit scales,
calibrate/grid_runs.py), the runs' skewness and excess kurtosis (moments about the mean in population form; the
sd with n - 1), the largest |z|, and what that kurtosis does to the variance a point's 6 runs estimate. The loop
reads every point's noise off 6 runs (design v2); with excess kurtosis k the variance of their sample variance is
1 + 5k/12 times a normal sample's (Var s^2 = sigma^4 (2/5 + k/6) for 6 runs; its spread the square root of that),
and a chi^2 over such estimated variances runs above its expectation.

    calibrate/replicate_tails.py STORE        (a study's store, e.g. studies/noise/replicate_tails.toml's)

Exit 2 on a missing store or usage."""
import math
import sqlite3
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from grid_runs import OBSERVABLES, observables  # noqa: E402

_RUNS = """select r.series, r.point, r.point_label,
                  r.j_mid,
                  (select min(t_s) from crossings c where c.job_key = r.job_key),
                  (select avg(x_m) from crossings c where c.job_key = r.job_key),
                  (select count(*) from crossings c where c.job_key = r.job_key),
                  (select avg(x_m * x_m) from crossings c where c.job_key = r.job_key)
           from runs r order by r.series, r.point, r.replicate"""


def cells(store):
    """{(series, point, label): {observable: [fit-scale value per run]}} of a study's store, runs in replicate order."""
    db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    points = {}
    for series, point, label, *measured in db.execute(_RUNS):
        values = points.setdefault((series, point, label), {o: [] for o in OBSERVABLES})
        for o, v in observables(*measured).items():
            values[o].append(v)
    db.close()
    return points


def moments(xs):
    """(sd, skewness, excess kurtosis, largest |z|) of a sample, its moments about the mean (population form)."""
    n = len(xs)
    mean = sum(xs) / n
    m2 = sum((x - mean) ** 2 for x in xs) / n
    if m2 <= 0:
        return 0.0, math.nan, math.nan, math.nan
    m3 = sum((x - mean) ** 3 for x in xs) / n
    m4 = sum((x - mean) ** 4 for x in xs) / n
    return (math.sqrt(m2 * n / (n - 1)), m3 / m2 ** 1.5, m4 / m2 ** 2 - 3,
            max(abs(x - mean) for x in xs) / math.sqrt(m2))


def main():
    if len(sys.argv) != 2 or not Path(sys.argv[1]).is_file():
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    points = cells(sys.argv[1])
    print("| series | point | observable | runs | sd (fit scale) | skewness | excess kurtosis (se) | largest abs z "
          "| Var of a 6-run variance (normal 1) |")
    print("| :-- | :-- | :-- | --: | --: | --: | --: | --: | --: |")
    for (series, _, label), values in sorted(points.items()):
        for o in OBSERVABLES:
            xs = values[o]
            if len(xs) < 4:
                continue
            sd, skew, kurt, zmax = moments(xs)
            if sd == 0:
                continue
            se = math.sqrt(24 / len(xs))  # a normal sample's excess kurtosis: its se, for scale
            print(f"| {series} | {label} | {o} | {len(xs)} | {sd:.4f} | {skew:+.2f} | {kurt:+.2f} ({se:.2f}) "
                  f"| {zmax:.2f} | {1 + 5 * kurt / 12:.2f} |")


if __name__ == "__main__":
    main()
