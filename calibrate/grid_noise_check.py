#!/usr/bin/python3
"""Two checks of the model's noise at a blind pass's baseline grid, per observable, from its run store (a
diagnostic of why the response surface at the baseline disagrees with direct simulation on fresh seeds by more
than its stated se; results/calibration-blind-pass24/replay-node-variance/README.md):

    /usr/bin/python3 calibrate/grid_noise_check.py PASS_DIR

1. Lack of fit: the equally weighted quadratic through every window of 5 consecutive grid nodes (as the loop's
   surface, calibrate/fit.cpp), its residual sum of squares over what the nodes' own noise leaves about it,
   tr((I - X H) diag(se^2)), pooled over the windows, points and twins (2 degrees of freedom a window). Where
   the quadratic follows the nodes within their noise, about nu/(nu - 2) with nu the effective degrees of
   freedom of that noise estimate (each node's se from its own few runs; about 1.12 for five nodes of 6); below
   it where the nodes share error (the first crossing's: calibrate/node_correlation_check.py), above where the
   response curves beyond a quadratic.
2. Fresh against grid runs: the per-run variance of each design point's runs on another seed than the grid's, at
   one parameter value (the fits' re-scores on fresh seeds, and the references of signatures on seeds of their
   own; 6 runs and more) over the variance of the same point's grid runs
   (every node's runs about their node's mean, pooled); mean and median over those re-scores (an F ratio:
   mean about 1 and median below it when the noise is alike).
3. An effect's shifts (J_mid, the first crossing, the exit offset): where an effect was moved at three or more grid nodes on the grid's seeds (a signature
   or a response size, series "key=value, effect=size"), its paired differences from the grid's runs (same
   point, replicate and seed), their variance pooled over the nodes over the pooled within-node variance, summed
   over the sizes and points. The loop's shift se comes from the differences pooled over the nodes
   (calibrate/effect_responses.cpp); above 1, the shift's change from node to node enters it as noise.
Observables on the loop's fit scales: J_mid, the first crossing's time and the crossings' spread log, their
mean position (the exit offset, mm) linear. Twins with one free parameter only.
"""
import collections
import statistics

import numpy as np

from grid_runs import OBSERVABLES, grid_level, one_parameter_twins, open_pass, runs


def shift_spread(twin_runs, lo, step, grid_seed, spread):
    """Adds, per observable, the shifts' variance pooled over the nodes and the within-node one to spread[obs]."""
    runs_at = collections.defaultdict(dict)      # (level, effect, point) -> replicate -> {obs: value}, grid's seed
    moved = collections.defaultdict(set)         # effect -> grid levels moved
    for parts, point, rep, seed, v in twin_runs:
        level = grid_level(parts[0][1], lo, step)
        if seed != grid_seed or level is None or len(parts) > 2: continue   # paired with the grid's runs: its seed
        effect = (parts[1][0], round(parts[1][1], 9)) if len(parts) == 2 else None
        runs_at[(level, effect, point)][rep] = v
        if effect: moved[effect].add(level)
    for effect, levels in moved.items():
        if len(levels) < 3: continue
        points = {k[2] for k in runs_at if k[1] == effect}
        for obs in OBSERVABLES:
            for point in points:
                by_node = []
                for level in sorted(levels):
                    base = runs_at.get((level, None, point), {})
                    d = [v[obs] - base[rep][obs] for rep, v in runs_at.get((level, effect, point), {}).items()
                         if obs in v and obs in base.get(rep, {})]
                    if len(d) >= 2: by_node.append(d)
                if len(by_node) < 3: continue
                within = sum(np.var(d, ddof=1) * (len(d) - 1) for d in by_node) / sum(len(d) - 1 for d in by_node)
                if within > 0:
                    spread[obs][0] += np.var([x for d in by_node for x in d], ddof=1)
                    spread[obs][1] += within
                    spread[obs][2] += 1


def lack_of_fit(grid, lack):
    """Adds each 5-node window's residual sum over its noise, and 2 dof, to lack[obs]."""
    for (obs, point), nodes in grid.items():
        levels = sorted(k for k, reps in nodes.items() if len(reps) >= 3)
        for first in range(len(levels) - 4):
            window = levels[first:first + 5]
            y = np.array([np.mean(nodes[k]) for k in window])
            var = np.array([np.var(nodes[k], ddof=1) / len(nodes[k]) for k in window])
            x = np.array(window, float)
            X = np.vstack([np.ones(5), x, x * x]).T
            H = np.linalg.solve(X.T @ X, X.T)
            residual = X @ (H @ y) - y
            noise = np.trace((np.eye(5) - X @ H) @ np.diag(var)) / 2
            if noise > 0:
                lack[obs][0] += residual @ residual / noise
                lack[obs][1] += 2


def main(pass_dir, db):
    lack = collections.defaultdict(lambda: [0.0, 0])
    ratios = collections.defaultdict(list)
    spread = collections.defaultdict(lambda: [0.0, 0.0, 0])
    for study, key, lo, step, seed in one_parameter_twins(pass_dir):
        twin_runs = runs(db, study, key)
        grid = collections.defaultdict(lambda: collections.defaultdict(list))   # (obs, point) -> level -> values
        other = collections.defaultdict(list)                                    # (obs, point, value, seed) -> values
        for parts, point, _, run_seed, v in twin_runs:
            if len(parts) != 1: continue
            level = grid_level(parts[0][1], lo, step)
            for obs, x in v.items():
                if level is not None and run_seed == seed: grid[(obs, point)][level].append(x)
                else: other[(obs, point, parts[0][1], run_seed)].append(x)
        lack_of_fit(grid, lack)
        shift_spread(twin_runs, lo, step, seed, spread)
        for (obs, point, _, _), xs in other.items():
            nodes = [reps for reps in grid[(obs, point)].values() if len(reps) >= 2]
            within = sum(np.var(r, ddof=1) * (len(r) - 1) for r in nodes)
            dof = sum(len(r) - 1 for r in nodes)
            if len(xs) >= 6 and dof >= 20 and within > 0:
                ratios[obs].append(np.var(xs, ddof=1) / (within / dof))
    print(f"{pass_dir.name}: per observable, (1) the 5-node quadratic's lack of fit over the grid (dof), "
          "(2) runs on other seeds: per-run variance over the grid's, mean, median (groups), (3) an effect's shifts: "
          "variance pooled over the nodes over the within-node one (sizes x points)")
    for obs in OBSERVABLES:
        s, dof = lack[obs]
        r = ratios[obs]
        total, within, n = spread[obs]
        cells = [f"{s / dof:7.3f} ({dof:4d})" if dof else f"{'-':>7} ({dof:4d})",
                 f"{statistics.mean(r):9.3f}{statistics.median(r):7.3f} ({len(r)})" if r else f"{'-':>9}{'-':>7} (0)",
                 f"{total / within:9.3f} ({n})" if within else f"{'-':>9} (0)"]
        print(f"{obs:<15}" + "".join(cells))


if __name__ == "__main__":
    main(*open_pass(__doc__))
