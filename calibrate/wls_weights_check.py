#!/usr/bin/python3
"""Why the response surface weighs its nodes alike (calibrate/fit.cpp, regress_point).

Five nodes at scaled parameter -1, -0.5, 0, 0.5, 1, each the mean of R normal runs (variance 1
each), a quadratic through them, its value at the centre node. Weighted by each node's own
1/s^2 (the loop until af66c1c), and with every node alike and the variance from each node's own
s^2 (since 87ed018): the variance of the value over draws against the mean variance stated, both
in units of one node's mean's variance. Deterministic (seed 1).

    /usr/bin/python3 calibrate/wls_weights_check.py [DRAWS]
"""
import sys

import numpy as np


def check(replicates, draws, rng):
    x = np.array([-1, -0.5, 0, 0.5, 1.0])
    X = np.vstack([np.ones(5), x, x * x]).T
    at = np.array([1.0, 0.0, 0.0])
    H = np.linalg.solve(X.T @ X, X.T)
    weighted, weighted_stated, alike, alike_stated = [], [], [], []
    for _ in range(draws):
        runs = rng.normal(size=(5, replicates))
        mean, var = runs.mean(1), runs.var(1, ddof=1) / replicates
        cov = np.linalg.inv(X.T @ np.diag(1 / var) @ X)
        weighted.append(at @ cov @ X.T @ np.diag(1 / var) @ mean)
        weighted_stated.append(at @ cov @ at)
        alike.append(at @ H @ mean)
        alike_stated.append(at @ H @ np.diag(var) @ H.T @ at)
    unit = 1 / replicates
    return [np.var(weighted, ddof=1) / unit, np.mean(weighted_stated) / unit,
            np.var(alike, ddof=1) / unit, np.mean(alike_stated) / unit]


def main():
    draws = int(sys.argv[1]) if len(sys.argv) > 1 else 40000
    rng = np.random.default_rng(1)
    print("| runs per node | own 1/s^2 weights: actual | stated | alike, own s^2: actual | stated |")
    print("| --: | --: | --: | --: | --: |")
    for replicates in (6, 12):
        a, b, c, d = check(replicates, draws, rng)
        print(f"| {replicates} | {a:.3f} | {b:.3f} | {c:.3f} | {d:.3f} |")
    print("equal weights, exact: 17/35 = 0.486")


if __name__ == "__main__":
    main()
