#!/usr/bin/python3
"""How the model's replicates correlate between the baseline grid's nodes, by observable and by how far
apart the nodes are, from a blind pass's run store (a diagnostic of calibrate/node_correlation.hpp).

    /usr/bin/python3 calibrate/node_correlation_check.py PASS_DIR

Every twin of the pass calibrates one free parameter on a grid lo, lo + step, ..., hi (its data file in
PASS_DIR/twins/), each node run on the same seeds (common random numbers). For every twin, design
point and node, the replicates' values of each observable (J_mid, the time to the first crossing and
the spread of the crossings' positions on a log scale, the mean position on a linear one, as the loop's
fit scales have them) are centred at that node; their correlation between two nodes m steps apart is
then pooled over the twins' points (the centred products summed, over the root of the summed squares).
Only the grid's own runs count (a series of one key=value on the grid, on the data file's seed), not the
effect responses' nor the fits' re-scores on other seeds.
"""
import collections
import math

from grid_runs import OBSERVABLES, grid_level, one_parameter_twins, open_pass, runs


def main(pass_dir, db):
    sums = collections.defaultdict(lambda: [0.0, 0.0, 0.0, 0])  # (observable, m) -> sab, saa, sbb, pairs
    twins = list(one_parameter_twins(pass_dir))
    for study, key, lo, step, seed in twins:
        values = collections.defaultdict(dict)   # (point, level) -> replicate -> {observable: value}
        for parts, point, rep, run_seed, v in runs(db, study, key):
            level = grid_level(parts[0][1], lo, step)
            if len(parts) == 1 and level is not None and run_seed == seed:
                values[(point, level)][rep] = v
        for point in sorted({p for p, _ in values}):
            nodes = sorted(level for p, level in values if p == point)
            for obs in OBSERVABLES:
                centred = {}
                for node in nodes:
                    reps = {r: v[obs] for r, v in values[(point, node)].items() if obs in v}
                    if len(reps) < 3: continue
                    mean = sum(reps.values()) / len(reps)
                    centred[node] = {r: x - mean for r, x in reps.items()}
                ordered = sorted(centred)
                for a in range(len(ordered)):
                    for b in range(a + 1, len(ordered)):
                        s = sums[(obs, ordered[b] - ordered[a])]
                        x, y = centred[ordered[a]], centred[ordered[b]]
                        for r in x.keys() & y.keys():
                            s[0] += x[r] * y[r]; s[1] += x[r] ** 2; s[2] += y[r] ** 2; s[3] += 1
    print(f"{pass_dir.name}: {len(twins)} twins; the replicates' correlation between grid nodes m steps apart, "
          "pooled over the twins' points (replicate pairs in brackets)")
    steps = sorted({m for _, m in sums})
    print("observable     " + "".join(f"{'m=' + str(m):>16}" for m in steps))
    for obs in OBSERVABLES:
        cells = []
        for m in steps:
            sab, saa, sbb, n = sums.get((obs, m), (0, 0, 0, 0))
            cells.append(f"{sab / math.sqrt(saa * sbb):+.3f} ({n})".rjust(16) if saa > 0 and sbb > 0 else " " * 16)
        print(f"{obs:<15}" + "".join(cells))


if __name__ == "__main__":
    main(*open_pass(__doc__))
