#!/usr/bin/python3
"""An effect's shift of ln J_mid, paired run by run, and whether it depends on a free parameter.

    /usr/bin/python3 studies/effects/paired_shift.py STORE FREE_KEY EFFECT_KEY

STORE: a study's runs.sqlite (one model) whose series sweep FREE_KEY and EFFECT_KEY on a grid.
Runs are paired by replicate: replicate r of every point has the same base seed and replicate, so
the same particle set (README, "Paired comparisons"); the runs are chaotic, so pairs share little
noise, and the pairs' correlation within each cell is printed. For each series:
- the runs, how many clogged, ln J_mid's spread over them;
- per free value and effect size, the shift d = ln J(size) - ln J(neutral, the smallest size), mean
  ± se over the replicates;
- per size, the interaction: the shift at the largest free value less at the smallest, paired by
  replicate, with its t (the calibration loop's response surface, calibrate/fit.hpp, takes the
  shift as the same at every free value);
- the free parameter's own slope at neutral, and at each free value the largest size read as a move
  of the free parameter (shift over slope; its se by first-order propagation with the covariance of
  shift and slope over the replicates they share: both subtract the same neutral runs at the lowest
  free value). On ln J_mid alone the two then trade off at that rate.
"""
import collections
import json
import math
import sqlite3
import statistics
import sys


def mean_se(values):
    return statistics.mean(values), statistics.stdev(values) / math.sqrt(len(values))


def t_text(m, se):
    return f"t {m / se:+.1f}" if se > 0 else "t -"


def load(store, free_key, effect_key):
    """({(series, free, size): {replicate: ln J_mid}}, {series: [(free, size, ln J_mid or None, clogged)]}); exit 2
    on a store that is not one, a run without the keys in its axes, or more than one model."""
    try:
        db = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
        rows = db.execute("select series, axes_json, replicate, j_mid, n_clogs, model from runs").fetchall()
    except sqlite3.Error as e:
        print(f"error: {store}: {e}", file=sys.stderr)
        sys.exit(2)
    models = {r[5] for r in rows}
    if len(models) > 1:
        print(f"error: {store} holds runs of {len(models)} models ({', '.join(sorted(models))}); allowed: one",
              file=sys.stderr)
        sys.exit(2)
    ln_j = collections.defaultdict(dict)
    runs = collections.defaultdict(list)
    for series, axes, replicate, j, clogs, _ in rows:
        a = json.loads(axes)
        if free_key not in a or effect_key not in a:
            print(f"error: {store}: a run without {free_key} or {effect_key} in its axes", file=sys.stderr)
            sys.exit(2)
        value = math.log(j) if j is not None and j > 0 else None
        runs[series].append((a[free_key], a[effect_key], value, clogs > 0))
        if value is not None:
            ln_j[(series, a[free_key], a[effect_key])][replicate] = value
    return ln_j, runs


def within_cell_correlation(cells):
    """Correlation of paired (neutral, moved) ln J_mid, each cell centred on its own means."""
    xs, ys = [], []
    for pairs in cells:
        if len(pairs) < 2:
            continue
        mx, my = statistics.mean(a for a, _ in pairs), statistics.mean(b for _, b in pairs)
        xs += [a - mx for a, _ in pairs]
        ys += [b - my for _, b in pairs]
    return statistics.correlation(xs, ys) if len(xs) > 2 else float("nan")


def exchange(shift, slope):
    """shift / slope and its se over the replicates both have (first-order, with their covariance)."""
    common = sorted(set(shift) & set(slope))
    if len(common) < 2:
        return None
    a, b = [shift[r] for r in common], [slope[r] for r in common]
    ma, mb = statistics.mean(a), statistics.mean(b)
    if ma == 0 or mb == 0:
        return None
    n = len(common)
    var_a, var_b = statistics.variance(a) / n, statistics.variance(b) / n
    cov = statistics.covariance(a, b) / n
    move = ma / mb
    rel = var_a / ma ** 2 + var_b / mb ** 2 - 2 * cov / (ma * mb)
    return move, abs(move) * math.sqrt(max(rel, 0.0))


def report_series(series, ln_j, runs, free_key, effect_key):
    frees = sorted({k[1] for k in ln_j if k[0] == series})
    sizes = sorted({k[2] for k in ln_j if k[0] == series})
    values = [v for _, _, v, _ in runs if v is not None]
    spread = f"{statistics.stdev(values):.3f}" if len(values) > 1 else "-"
    print(f"\n{series}: {len(runs)} runs, {sum(c for *_, c in runs)} with a clog, "
          f"{len(runs) - len(values)} without J_mid; ln J_mid's sd over the runs {spread}")
    if len(frees) < 2 or len(sizes) < 2:
        print("  (needs two free values and two sizes)")
        return
    print(f"\nruns with a clog, of all at each point\n")
    print(f"| {free_key} | " + " | ".join(f"{s:g}" for s in sizes) + " |")
    print("| --: |" + " --: |" * len(sizes))
    for f in frees:
        cells = [[c for ff, ss, _, c in runs if ff == f and ss == s] for s in sizes]
        print(f"| {f:g} | " + " | ".join(f"{sum(c)} of {len(c)}" for c in cells) + " |")
    print(f"\nshift of ln J_mid by {effect_key} (mean ± se over paired replicates)\n")
    print(f"| {free_key} | " + " | ".join(f"{s:g}" for s in sizes[1:]) + " |")
    print("| --: |" + " --: |" * (len(sizes) - 1))
    shifts, cells = {}, []
    for f in frees:
        base = ln_j.get((series, f, sizes[0]), {})
        row = []
        for s in sizes[1:]:
            moved = ln_j.get((series, f, s), {})
            shifts[(f, s)] = {r: moved[r] - base[r] for r in moved if r in base}
            cells.append([(base[r], moved[r]) for r in moved if r in base])
            d = list(shifts[(f, s)].values())
            row.append(f"{statistics.mean(d):+.4f} ± {mean_se(d)[1]:.4f}" if len(d) > 1 else "-")
        print(f"| {f:g} | " + " | ".join(row) + " |")
    print(f"\npairs' correlation of ln J_mid within each cell (each size against its neutral): "
          f"{within_cell_correlation(cells):+.2f}")
    lo, hi = frees[0], frees[-1]
    for s in sizes[1:]:
        d = [shifts[(hi, s)][r] - shifts[(lo, s)][r] for r in shifts[(hi, s)] if r in shifts[(lo, s)]]
        if len(d) < 2:
            continue
        m, se = mean_se(d)
        at_lo, at_lo_se = mean_se(list(shifts[(lo, s)].values()))
        share = f"; {100 * m / at_lo:+.0f} % of the shift at {lo:g}" if abs(at_lo) > 2 * at_lo_se else ""
        print(f"\n{effect_key} {s:g}: shift at {free_key} {hi:g} less at {lo:g}: {m:+.4f} ± {se:.4f} "
              f"({t_text(m, se)}{share})")
    base_lo, base_hi = ln_j.get((series, lo, sizes[0]), {}), ln_j.get((series, hi, sizes[0]), {})
    slope = {r: (base_hi[r] - base_lo[r]) / (hi - lo) for r in base_hi if r in base_lo}
    if len(slope) < 2:
        return
    m, se = mean_se(list(slope.values()))
    print(f"\n{free_key} {lo:g} -> {hi:g} at {effect_key} {sizes[0]:g}: ln J_mid {m * (hi - lo):+.4f} ± "
          f"{se * (hi - lo):.4f}")
    for f in frees:
        moved = exchange(shifts[(f, sizes[-1])], slope)
        if moved:
            print(f"{effect_key} {sizes[-1]:g} at {free_key} {f:g} acts on ln J_mid as {free_key} moved by "
                  f"{moved[0]:+.3f} ± {moved[1]:.3f}")


def main(args):
    if len(args) != 3:
        print("usage: paired_shift.py STORE FREE_KEY EFFECT_KEY", file=sys.stderr)
        return 2
    store, free_key, effect_key = args
    ln_j, runs = load(store, free_key, effect_key)
    for series in sorted(runs):
        report_series(series, ln_j, runs[series], free_key, effect_key)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
