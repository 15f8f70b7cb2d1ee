#!/usr/bin/python3
"""Why the model's noise at the baseline fell less than 1/replicates (README, Calibration).

The loop predicts each point through a quadratic in the free parameter, fitted through 5 grid
nodes and weighted by each node's own standard error, estimated from that node's replicates
(calibrate/fit.cpp, regress_point). Two things make the prediction's variance at 2n replicates
differ from half that at n:
  1. the leverage: the baseline falls elsewhere among the nodes in the two fits;
  2. the weights: 1/s^2 from a few replicates is biased high (for normal scatter with k degrees
     of freedom, E[1/s^2] = k/(k-2) / sigma^2), so the fitted surface's variance is understated,
     more at n than at 2n.
This script measures both against the per-point ratio of the model's variance in calibrations of
the same twins at two replicate counts (points.csv, before_se, fitted points), e.g. the
--max-effects 0 calibrations that studies/model_noise_share.sh writes.

  /usr/bin/python3 calibrate/surface_noise_check.py SCAN N1 N2 LO HI STEP [STORE]
  e.g. calibrate/surface_noise_check.py /work/share-scan 6 12 0.1 0.5 0.05 /work/share-check.sqlite

SCAN/N/<case>/ holds one calibration per twin at N model replicates. LO HI STEP: the free
parameter's grid (one free parameter). The Monte Carlo uses normal scatter and fixed seeds.
STORE (optional, the calibrations' run store): the same ratio at the replicate level, for ln J_mid
of every parameter set with N2 replicates, and how far its scatter is from normal.
"""
import collections
import csv
import json
import sqlite3
import statistics
import sys
from pathlib import Path

import numpy as np


def window(grid, x):
    """The 5 grid nodes around the node nearest x (fit.cpp, window)."""
    nearest = int(np.argmin(np.abs(grid - x)))
    first = min(max(nearest - 2, 0), len(grid) - 5)
    return grid[first:first + 5]


def basis(nodes, x):
    mid, half = (nodes[0] + nodes[-1]) / 2, (nodes[-1] - nodes[0]) / 2
    u = (np.asarray(x) - mid) / half
    return np.stack([np.ones_like(u), u, u * u], axis=-1)


def leverage(nodes, x):
    a = basis(nodes, nodes)
    v = basis(nodes, x)
    return float(v @ np.linalg.inv(a.T @ a) @ v)


def weighted_prediction_variance(nodes, x, n, draws):
    """The loop's prediction variance at x from nodes weighted by their own replicates' 1/s^2, in
    units of sigma^2, for the first n replicates of each draw."""
    a = basis(nodes, nodes)
    v = basis(nodes, x)
    s2 = draws[:, :, :n].var(axis=2, ddof=1) / n  # (draw, node)
    ata = np.einsum("dk,ki,kj->dij", 1 / s2, a, a)
    return np.einsum("i,dij,j->d", v, np.linalg.inv(ata), v)


def per_point_ratio(folder1, folder2):
    def se_of(folder):
        out = {}
        for r in csv.DictReader(open(folder / "points.csv")):
            if r["held_out"] == "0" and r["before_se"] not in ("", "nan"):
                key = (r["W_over_d"], r["incline_deg"], r["shape"], r["D_over_d"], r["observable"])
                out[key] = float(r["before_se"])  # in the observable's unit, as points.csv gives it
        return out
    a, b = se_of(folder1), se_of(folder2)
    ratios = [(b[k] / a[k]) ** 2 for k in a if k in b and a[k] > 0]
    return statistics.median(ratios) if ratios else None


def replicate_level(store, n1, n2):
    """ln J_mid per parameter set (a calibration's series and point) with replicates 0..n2-1."""
    db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    runs = collections.defaultdict(dict)
    for series, point, replicate, j in db.execute("SELECT series, point_label, replicate, j_mid FROM runs"):
        runs[(series, point)][replicate] = j
    x = np.array([[np.log(v[k]) for k in range(n2)] for v in runs.values()
                  if all(v.get(k) is not None and v[k] > 0 for k in range(n2))])
    ratio = np.median((x.var(axis=1, ddof=1) / n2) / (x[:, :n1].var(axis=1, ddof=1) / n1))
    z = (x - x.mean(axis=1, keepdims=True)) / x.std(axis=1, ddof=1, keepdims=True)
    normal = np.random.default_rng(1).normal(size=x.shape)
    zn = (normal - normal.mean(axis=1, keepdims=True)) / normal.std(axis=1, ddof=1, keepdims=True)
    kurt = lambda v: float(np.mean(v ** 4) / np.mean(v ** 2) ** 2 - 3)
    rn = np.median((normal.var(axis=1, ddof=1) / n2) / (normal[:, :n1].var(axis=1, ddof=1) / n1))
    print(f"replicate level, ln J_mid over {len(x)} parameter sets with {n2} replicates: median of "
          f"var({n2})/{n2} over var(first {n1})/{n1} = {ratio:.3f} (normal: {rn:.3f}); pooled excess kurtosis "
          f"within a set {kurt(z.ravel()):+.2f} (normal, same shape: {kurt(zn.ravel()):+.2f})")


def main():
    if len(sys.argv) == 8:
        replicate_level(sys.argv.pop(), int(sys.argv[2]), int(sys.argv[3]))
    if len(sys.argv) != 7:
        sys.exit(__doc__)
    scan, n1, n2 = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
    lo, hi, step = map(float, sys.argv[4:7])
    grid = np.round(np.arange(lo, hi + step / 2, step), 10)
    draws = np.random.default_rng(20261127).normal(size=(20000, 5, max(n1, n2)))  # replicates 1..n1 shared
    print(f"{'case':22s} {'baseline':>15s} {'leverage':>8s} {'with weights':>12s} {'measured':>8s}")
    rows = []
    for s1 in sorted((scan / str(n1)).glob("*/summary.json")):
        case = s1.parent.name
        s2 = scan / str(n2) / case / "summary.json"
        if not s2.exists():
            continue
        p1 = next(iter(json.load(open(s1))["before"]["params"].values()))
        p2 = next(iter(json.load(open(s2))["before"]["params"].values()))
        w1, w2 = window(grid, p1), window(grid, p2)
        lev = (n1 / n2) * leverage(w2, p2) / leverage(w1, p1)
        weighted = np.median(weighted_prediction_variance(w2, p2, n2, draws) /
                             weighted_prediction_variance(w1, p1, n1, draws))
        measured = per_point_ratio(s1.parent, s2.parent)
        if measured is None:
            continue
        rows.append((lev, weighted, measured))
        print(f"{case:22s} {p1:7.3f}->{p2:6.3f} {lev:8.2f} {weighted:12.2f} {measured:8.2f}")
    lev, weighted, measured = (statistics.median(c) for c in zip(*rows))
    bias = {n: float(np.mean(weighted_prediction_variance(grid[2:7], grid[4], n, draws)) /
                     leverage(grid[2:7], grid[4]) * n) for n in (n1, n2)}
    print(f"\nthe model's variance per point at {n2} over {n1} replicates, median over {len(rows)} twins "
          f"(each twin: the median over its fitted points):")
    print(f"  {n1}/{n2} x the leverage ratio: {lev:.2f}; with the weights' bias too: {weighted:.2f}; "
          f"measured: {measured:.2f}")
    print("the weighted surface's variance over the true one at the middle node, mean over the draws: " +
          ", ".join(f"{bias[n]:.2f} at {n} replicates" for n in (n1, n2)))


if __name__ == "__main__":
    main()
