#!/usr/bin/python3
"""An effect's shift of ln J_mid, paired run by run, and whether it depends on a free parameter.

    /usr/bin/python3 studies/effects/paired_shift.py STORE FREE_KEY EFFECT_KEY

STORE: a study's runs.sqlite whose series sweep FREE_KEY and EFFECT_KEY on a grid. Runs are paired
by replicate: replicate r of every point has the same run.seed and replicate, so the same particle
set (README, "Paired comparisons"); the runs are chaotic, so pairs share little noise, and the
correlation of the pairs is printed. For each series, free value and effect size: the shift
d = ln J(size) - ln J(neutral, the smallest size) with its standard error over the replicates, and
for each size the interaction: the shift at the largest free value less the shift at the smallest,
paired by replicate, with its t. The calibration loop's response surface (calibrate/fit.hpp) takes
the shift as the same at every free value; a t beyond 2 says it is not.
"""
import collections
import json
import math
import sqlite3
import statistics
import sys


def mean_se(values):
    return statistics.mean(values), statistics.stdev(values) / math.sqrt(len(values))


def main(args):
    if len(args) != 3:
        print("usage: paired_shift.py STORE FREE_KEY EFFECT_KEY", file=sys.stderr)
        return 2
    store, free_key, effect_key = args
    try:
        db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
        rows = db.execute("select series, axes_json, replicate, j_mid, n_clogs from runs").fetchall()
    except sqlite3.Error as e:
        print(f"error: {store}: {e}", file=sys.stderr)
        return 2
    ln_j = collections.defaultdict(dict)  # (series, free, size) -> {replicate: ln J_mid}
    runs = collections.defaultdict(list)  # series -> (ln J_mid or None, clogged)
    for series, axes, replicate, j, clogs in rows:
        a = json.loads(axes)
        if free_key not in a or effect_key not in a:
            print(f"error: {store}: a run without {free_key} or {effect_key} in its axes", file=sys.stderr)
            return 2
        runs[series].append((math.log(j) if j is not None and j > 0 else None, clogs > 0))
        if j is not None and j > 0:
            ln_j[(series, a[free_key], a[effect_key])][replicate] = math.log(j)
    for series in sorted({k[0] for k in ln_j}):
        frees = sorted({k[1] for k in ln_j if k[0] == series})
        sizes = sorted({k[2] for k in ln_j if k[0] == series})
        values = [v for v, _ in runs[series] if v is not None]
        print(f"\n{series}: {len(runs[series])} runs, {sum(c for _, c in runs[series])} with a clog, "
              f"{len(runs[series]) - len(values)} without J_mid; ln J_mid's sd over the runs {statistics.stdev(values):.3f}")
        print(f"\nshift of ln J_mid by {effect_key} (mean ± se over paired replicates)\n")
        print(f"| {free_key} | " + " | ".join(f"{s:g}" for s in sizes[1:]) + " |")
        print("| --: |" + " --: |" * (len(sizes) - 1))
        shifts, pairs = {}, []
        for f in frees:
            base = ln_j[(series, f, sizes[0])]
            cells = []
            for s in sizes[1:]:
                moved = ln_j[(series, f, s)]
                shifts[(f, s)] = {r: moved[r] - base[r] for r in moved if r in base}
                pairs += [(base[r], moved[r]) for r in moved if r in base]
                m, se = mean_se(list(shifts[(f, s)].values()))
                cells.append(f"{m:+.4f} ± {se:.4f}")
            print(f"| {f:g} | " + " | ".join(cells) + " |")
        print(f"\npairs' correlation of ln J_mid (each size against its neutral, every free value): "
              f"{statistics.correlation([a for a, _ in pairs], [b for _, b in pairs]):+.2f} over {len(pairs)}")
        lo, hi = frees[0], frees[-1]
        for s in sizes[1:]:
            d = [shifts[(hi, s)][r] - shifts[(lo, s)][r] for r in shifts[(hi, s)] if r in shifts[(lo, s)]]
            m, se = mean_se(d)
            at_lo = statistics.mean(shifts[(lo, s)].values())
            print(f"\n{effect_key} {s:g}: shift at {free_key} {hi:g} less at {lo:g}: {m:+.4f} ± {se:.4f} "
                  f"(t {m / se:+.1f}; {100 * m / at_lo:+.0f} % of the shift at {lo:g})")
        base_lo, base_hi = ln_j[(series, lo, sizes[0])], ln_j[(series, hi, sizes[0])]
        d = [base_hi[r] - base_lo[r] for r in base_hi if r in base_lo]
        m, se = mean_se(d)
        print(f"{free_key} {lo:g} -> {hi:g} at {effect_key} {sizes[0]:g}: ln J_mid {m:+.4f} ± {se:.4f}")
        # On ln J_mid alone, the largest size reads as a move of the free parameter (its slope over the
        # free values at neutral; first-order error propagation): how far the two trade off there.
        slope, slope_se = m / (hi - lo), se / (hi - lo)
        shift, shift_se = mean_se(list(shifts[(lo, sizes[-1])].values()))
        if slope != 0 and shift != 0:
            move = shift / slope
            move_se = abs(move) * math.hypot(shift_se / shift, slope_se / slope)
            print(f"{effect_key} {sizes[-1]:g} at {free_key} {lo:g} acts on ln J_mid as {free_key} moved by "
                  f"{move:+.3f} ± {move_se:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
