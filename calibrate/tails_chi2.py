#!/usr/bin/python3
"""What the replicates' tails do to the loop's chi^2, and whether pooling each point's noise over the surface's
nodes helps: the loop's construction replayed on runs drawn from one study point's many replicates
(studies/noise/replicate_tails.toml: 150 runs at each of 18 design-v2 points), set beside the same construction
on normal samples. A sample variance is unbiased whatever the distribution, but 1/s^2 is not, and with heavy
tails s^2 scatters more (calibrate/replicate_tails.py): every chi^2 built on estimated variances then runs
above its expectation by more than a normal sample's.

    calibrate/tails_chi2.py STORE [--draws N]

Each draw takes 46 of a point's runs without replacement, on the loop's fit scales (calibrate/grid_runs.py):
- the surface: 5 nodes of 6 runs (blind design v2's replicates), the response taken flat across them and the
  nodes independent (the real nodes share seeds; calibrate/node_correlation.hpp counts that apart), the
  equally weighted quadratic through them (calibrate/fit.cpp) read at its middle node, s = sum w_j m_j with
  w = (-3, 12, 17, 12, -3)/35; its stated variance se_s^2 = sum w_j^2 v_j / 6 from each node's own sample
  variance v_j (the loop today), or sum w_j^2 vbar / 6 from the variance pooled over the 5 nodes (30 runs;
  the remedy, exact here where the noise is the same at every node);
- the data: 10 runs (the blind twins' count), y their mean, e^2 = their sample variance / 10;
- fresh runs: 6, f their mean, se_f^2 = their sample variance / 6 (calibrate/fresh_points.py's re-score).
Per draw, the loop's chi^2 of the point, (y - s)^2 / (e^2 + se_s^2), and fresh_points.py's disagreement less
its stated expectation, (f - s)^2 / v_f - (se_s^2 + se_f^2) / v_f with v_f = e^2 + se_f^2. Both would
average 1 and 0 were every variance known; estimated from a normal sample's few runs they average more, given
in the "normal" columns (the same draws' construction on standard normal samples; the scale does not
matter). "tails" is the point's mean less the normal one: what the distribution's shape adds, with
the draws' Monte Carlo se. The draws reuse one point's 150 runs, so a single run far out weighs in many
draws: the point's own sample bounds what this can tell (its kurtosis is itself uncertain). The data's floor
(floor_relative) is left out, and so is the surface's lack-of-fit widening (the response is flat here).
The normal reference is itself a Monte Carlo mean (1 000 000 draws): its se is added in quadrature to the
tails' se. The per-observable summary also gives how often the point's chi^2 exceeds 3.84 and 9 (1 degree of
freedom's 5 % and 0.27 % with known variances), as a check of the tail beside the mean.

Then per observable, the mean over the points of the tails' excess (its se from the points' spread), each
variant. Exit 2 on a missing store or usage. Deterministic (a fixed seed)."""
import argparse
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from grid_runs import OBSERVABLES  # noqa: E402
from replicate_tails import cells  # noqa: E402

NODES, PER_NODE, DATA, FRESH = 5, 6, 10, 6
TAKEN = NODES * PER_NODE + DATA + FRESH
REFERENCE_DRAWS, REFERENCE_CHUNK = 1_000_000, 100_000
SEED = 20261129
MEANS = ("chi2 own", "disagreement own", "chi2 pooled", "disagreement pooled")   # per point and in the summary
TAILS = ("chi2 own beyond 3.84", "chi2 own beyond 6.25", "chi2 own beyond 9")    # in the summary only


def quadratic_weights():
    """The row of the equally weighted quadratic's hat matrix at the middle of 5 equally spaced nodes:
    (-3, 12, 17, 12, -3)/35, its squares summing to the leverage 17/35."""
    x = np.linspace(-1, 1, NODES)
    design = np.vstack([np.ones(NODES), x, x * x]).T
    return design[NODES // 2] @ np.linalg.solve(design.T @ design, design.T)


MIDDLE = quadratic_weights()


def statistics_of(draws):
    """Per draw (rows of TAKEN values): the loop's chi^2 and the fresh disagreement's excess, with the surface's
    variance from each node's own runs and from the 5 nodes' pooled runs; and whether the first exceeds 3.84,
    6.25 (a whitened residual beyond 2.5) and 9. Returns {name: per-draw values}."""
    nodes = draws[:, :NODES * PER_NODE].reshape(len(draws), NODES, PER_NODE)
    data = draws[:, NODES * PER_NODE:NODES * PER_NODE + DATA]
    fresh = draws[:, NODES * PER_NODE + DATA:]
    m, v = nodes.mean(axis=2), nodes.var(axis=2, ddof=1)
    s = m @ MIDDLE
    se_s2 = {"own": (v @ MIDDLE ** 2) / PER_NODE,
             "pooled": v.mean(axis=1) * (MIDDLE ** 2).sum() / PER_NODE}
    y, e2 = data.mean(axis=1), data.var(axis=1, ddof=1) / DATA
    f, se_f2 = fresh.mean(axis=1), fresh.var(axis=1, ddof=1) / FRESH
    v_f = e2 + se_f2
    out = {}
    for name, ss in se_s2.items():
        out[f"chi2 {name}"] = (y - s) ** 2 / (e2 + ss)
        out[f"disagreement {name}"] = (f - s) ** 2 / v_f - (ss + se_f2) / v_f
    for limit in (3.84, 6.25, 9):
        out[f"chi2 own beyond {limit}"] = (out["chi2 own"] > limit).astype(float)
    return out


def normal_reference(rng):
    """{name: (mean, its Monte Carlo se)} of every statistic on standard normal samples."""
    sums = {}
    for _ in range(REFERENCE_DRAWS // REFERENCE_CHUNK):
        for name, xs in statistics_of(rng.standard_normal((REFERENCE_CHUNK, TAKEN))).items():
            total, squares = sums.get(name, (0.0, 0.0))
            sums[name] = (total + xs.sum(), squares + (xs * xs).sum())
    out = {}
    for name, (total, squares) in sums.items():
        mean = total / REFERENCE_DRAWS
        out[name] = (mean, math.sqrt(max(squares / REFERENCE_DRAWS - mean * mean, 0) / REFERENCE_DRAWS))
    return out


def resampled(values, draws, rng):
    """`draws` rows of TAKEN of `values` each, without replacement within a row."""
    xs = np.asarray(values, dtype=float)
    order = rng.random((draws, len(xs))).argsort(axis=1)[:, :TAKEN]
    return xs[order]


def point_rows(points, normal, draws, rng):
    """The per-point table's lines, and {observable: {name: [each point's mean less the normal one]}}."""
    lines = ["| series | point | observable | " + " | ".join(f"{n}: mean (normal) tails ± se" for n in MEANS) + " |",
             "| :-- | :-- | :-- |" + " --: |" * len(MEANS)]
    excess = {o: {n: [] for n in MEANS + TAILS} for o in OBSERVABLES}
    for (series, _, label), values in sorted(points.items()):
        for o in OBSERVABLES:
            if len(values[o]) < TAKEN:
                continue
            per_draw = statistics_of(resampled(values[o], draws, rng))
            cells = []
            for n in MEANS + TAILS:
                mean, se = per_draw[n].mean(), per_draw[n].std(ddof=1) / math.sqrt(draws)
                excess[o][n].append(mean - normal[n][0])
                if n in MEANS:
                    cells.append(f"{mean:.3f} ({normal[n][0]:.3f}) {mean - normal[n][0]:+.3f} ± {se:.3f}")
            lines.append(f"| {series} | {label} | {o} | " + " | ".join(cells) + " |")
    return lines, excess


def summary_rows(excess, normal):
    """Per observable: the mean over the points of each statistic's excess over normal samples, its se from the
    points' spread and the reference's own Monte Carlo se in quadrature; the tail rates in percent."""
    names = MEANS + TAILS
    lines = ["| observable | points | " + " | ".join(n.replace("beyond", "share beyond") + (" (%)" if n in TAILS else "")
                                                   for n in names) + " |",
             "| :-- | --: |" + " --: |" * len(names),
             "| normal samples | | " + " | ".join(f"{normal[n][0] * (100 if n in TAILS else 1):.3f} ± "
                                                  f"{normal[n][1] * (100 if n in TAILS else 1):.3f}" for n in names)
             + " |"]
    for o in OBSERVABLES:
        k = len(excess[o][MEANS[0]])
        if k == 0:
            continue
        cells = []
        for n in names:
            xs = excess[o][n]
            se = math.hypot(np.std(xs, ddof=1) / math.sqrt(k) if k > 1 else math.nan, normal[n][1])
            scale = 100 if n in TAILS else 1
            cells.append(f"{scale * np.mean(xs):+.3f} ± {scale * se:.3f}")
        lines.append(f"| {o} | {k} | " + " | ".join(cells) + " |")
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("store")
    parser.add_argument("--draws", type=int, default=4000, help="draws per point and observable (4000)")
    try:
        args = parser.parse_args()
    except SystemExit:
        sys.exit(2)
    if not Path(args.store).is_file() or args.draws < 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    rng = np.random.default_rng(SEED)
    normal = normal_reference(rng)
    lines, excess = point_rows(cells(args.store), normal, args.draws, rng)
    print("\n".join(lines))
    print()
    print("Per observable, the tails' excess over normal samples averaged over the points (the tail shares in "
          "percentage points); first row, the normal samples' own values:")
    print()
    print("\n".join(summary_rows(excess, normal)))


if __name__ == "__main__":
    main()
