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
import sqlite3
import sys
import tomllib
from pathlib import Path

OBSERVABLES = ("j_mid", "front_arrival", "exit_offset", "exit_spread")


def run_values(db, study, key, seed):
    """{(point, node value): {replicate: {observable: fit-scale value}}} of one twin's runs on its data file's seed."""
    q = """select r.series, r.point, r.replicate, r.j_mid,
                  (select min(t_s) from crossings c where c.job_key = r.job_key),
                  (select avg(x_m) from crossings c where c.job_key = r.job_key),
                  (select count(*) from crossings c where c.job_key = r.job_key),
                  (select avg(x_m * x_m) from crossings c where c.job_key = r.job_key)
           from runs r where r.study = ? and r.series like ? and r.series not like '%,%' and r.base_seed = ?"""
    out = collections.defaultdict(dict)
    for series, point, rep, j_mid, first, mean_x, n, mean_x2 in db.execute(q, (f"calibrate:{study}", f"{key}=%", seed)):
        value = float(series.split("=", 1)[1])
        v = {}
        if j_mid and j_mid > 0: v["j_mid"] = math.log(j_mid)
        if first and first > 0: v["front_arrival"] = math.log(first)
        if n and n >= 1: v["exit_offset"] = mean_x * 1e3
        if n and n >= 2:
            var = (mean_x2 - mean_x * mean_x) * n / (n - 1)
            if var > 0: v["exit_spread"] = math.log(math.sqrt(var) * 1e3)
        out[(point, value)][rep] = v
    return out


def main(pass_dir):
    pass_dir = Path(pass_dir)
    db = sqlite3.connect(f"file:{pass_dir / 'runs.sqlite'}?mode=ro", uri=True)
    sums = collections.defaultdict(lambda: [0.0, 0.0, 0.0, 0])  # (observable, m) -> sab, saa, sbb, pairs
    twins = sorted((pass_dir / "twins").glob("*.toml"))
    for twin in twins:
        spec = tomllib.loads(twin.read_text())
        free = spec["free"]
        if len(free) != 1: continue
        key, lo, step = free[0]["key"], free[0]["lo"], free[0]["step"]
        on_grid = lambda v: abs((v - lo) / step - round((v - lo) / step)) < 1e-6  # not a fit re-scored on fresh seeds
        values = {k: v for k, v in run_values(db, twin.stem, key, spec["model"]["seed"]).items() if on_grid(k[1])}
        points = sorted({p for p, _ in values})
        for point in points:
            nodes = sorted(v for p, v in values if p == point)
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
                        m = round((ordered[b] - ordered[a]) / step)
                        s = sums[(obs, m)]
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
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    folder = Path(sys.argv[1])
    if not (folder / "runs.sqlite").is_file() or not (folder / "twins").is_dir():
        print(f"error: {folder} is not a blind pass with its store (runs.sqlite and twins/ expected)", file=sys.stderr)
        sys.exit(2)
    main(folder)
