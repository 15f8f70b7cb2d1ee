#!/usr/bin/env python3
"""Does the oracle's signal (truth "signal": lambda) measure what the loop sees?

    /usr/bin/python3 calibrate/oracle_scale.py PASS [PASS...] [--new RESIGNAL_OUT] [--remade SUB]

For every 2D twin of the passes, lambda (the chi^2 its planted effects add beyond what the free
parameter absorbs, in noise units; gapflow twin) is set against the loop's own view of the same
data: its baseline fit's chi^2 beyond its degrees of freedom (summary.json before.fitted). Without
a planted effect that excess is noise, mean about 0 (the nulls' mean is printed and subtracted);
with one it should be lambda on average, if lambda is in the loop's noise units. Printed: the mean
excess and mean lambda by size of lambda with their ratio, and the ratio over all twins with
lambda >= 10 (sum of excess less the nulls' mean, over the sum of lambda: the largest dominate;
and the median of the twins' own ratios). With --new (one pass), the same with the
lambdas of RESIGNAL_OUT/truth (studies/blind_resignal.sh: the twins made again by another
gapflow). Each block ends with the single effects identified (PASS/cases.csv), visible
(oracle power >= 0.8: the ceiling calibrate/visibility_ceiling.py reports) and identified among
the visible, under that block's lambda; with --new, a line per twin follows. With --remade SUB
(any number of passes), a second block pools the passes with each twin's lambda taken from
PASS/SUB/truth where it was remade there, and from the pass's own truth elsewhere.
Exit 2 on a folder without calibrations.
"""
import csv
import glob
import json
import math
import os
import statistics
import sys

from blind_summary import NOT_SINGLE, VISIBLE_POWER, truth_label
from blind_pass import calibrations, take_option

BINS = ((0, 10), (10, 50), (50, math.inf))


def twins(pass_dir, truth_dir=None):
    """(case, lambda or 0 without a planted effect, oracle power or None, baseline excess, single,
    identified by the pass)."""
    truth_dir = truth_dir or os.path.join(pass_dir, "truth")
    identified = {}  # the pass's own verdict per twin (calibrate/blind_summary.py's cases.csv)
    if os.path.exists(os.path.join(pass_dir, "cases.csv")):
        with open(os.path.join(pass_dir, "cases.csv"), newline="") as f:
            identified = {r["case"]: r["identified"] for r in csv.DictReader(f)}
    out = []
    for case, summary_file in calibrations(pass_dir):
        truth_file = os.path.join(truth_dir, case + ".json")
        old_truth_file = os.path.join(pass_dir, "truth", case + ".json")
        if not os.path.exists(old_truth_file):
            continue
        with open(old_truth_file) as f:
            old = json.load(f)
        if old["model"] != "2d":
            continue
        planted = [p for p in old["planted"] if p["name"] != "free"]
        if planted and not os.path.exists(truth_file):
            continue  # not remade (yet)
        truth = old
        if planted:
            with open(truth_file) as f:
                truth = json.load(f)
        with open(summary_file) as f:
            fitted = json.load(f)["before"]["fitted"]
        signal = truth.get("signal")
        if planted and not signal:
            continue  # a planted effect without a measured signal: nothing to compare
        single = truth_label(old)[0] not in NOT_SINGLE  # as the pass's cases.csv counts it
        out.append((case, signal["chi2"] if signal else 0.0, signal["oracle_power"] if signal else None,
                    fitted["chi2"] - fitted["dof"], single, identified.get(case) == "True"))
    return out


def mean_se(values):
    if not values:
        return float("nan"), float("nan")
    se = statistics.stdev(values) / math.sqrt(len(values)) if len(values) > 1 else float("nan")
    return statistics.mean(values), se


def report(label, rows):
    nulls = [r[3] for r in rows if r[2] is None]
    null_mean, null_se = mean_se(nulls)
    print(f"{label}: {len(rows)} twins; without a planted effect ({len(nulls)}): mean excess {null_mean:.1f} "
          f"(se {null_se:.1f})")
    base = null_mean if nulls else 0.0
    for lo, hi in BINS:
        b = [r for r in rows if r[2] is not None and lo <= r[1] < hi]
        if not b:
            continue
        ex, ex_se = mean_se([r[3] for r in b])
        lam = statistics.mean(r[1] for r in b)
        print(f"  lambda in [{lo:g}, {hi:g}): {len(b)} twins, mean lambda {lam:.1f}, mean excess {ex:.1f} (se {ex_se:.1f}); "
              f"(mean excess - nulls' mean) / mean lambda {(ex - base) / lam if lam > 0 else float('nan'):.2f}")
    big = [r for r in rows if r[2] is not None and r[1] >= 10]
    if big:
        ratio = sum(r[3] - base for r in big) / sum(r[1] for r in big)
        median = statistics.median((r[3] - base) / r[1] for r in big)
        print(f"  lambda >= 10 ({len(big)} twins): (excess - nulls' mean) / lambda, summed {ratio:.2f}, "
              f"median per twin {median:.2f}")
    singles = [r for r in rows if r[4] and r[2] is not None]
    visible = [r for r in singles if r[2] >= VISIBLE_POWER]
    found = sum(1 for r in singles if r[5])
    found_visible = sum(1 for r in visible if r[5])
    print(f"  single effects: identified {found} of {len(singles)}; visible (oracle power >= {VISIBLE_POWER}) "
          f"{len(visible)} of {len(singles)} (the ceiling); identified among the visible {found_visible} of {len(visible)}")


def main():
    args = sys.argv[1:]
    remade_sub = take_option(args, "--remade", "a subfolder name")
    new = take_option(args, "--new", "a folder")
    if not args or (new and len(args) != 1):
        print("usage: oracle_scale.py PASS [PASS...] [--new RESIGNAL_OUT] [--remade SUB] (--new with one pass)",
              file=sys.stderr)
        sys.exit(2)
    rows = []
    for pass_dir in args:
        r = twins(pass_dir)
        if not r:
            print(f"error: no calibrations in {pass_dir}", file=sys.stderr)
            sys.exit(2)
        rows += r
    report("the passes' own lambda" if not new else f"{args[0]}: its own lambda", rows)
    if remade_sub:
        # Each pass's remade truths where there are any (the others keep their own lambda).
        pooled = []
        for pass_dir in args:
            sub = os.path.join(pass_dir, remade_sub, "truth")
            done = {os.path.basename(f)[:-5] for f in glob.glob(os.path.join(sub, "*.json"))}
            # twins(pass_dir, sub) holds the remade twins and those without a planted effect.
            pooled += twins(pass_dir, sub) + [r for r in twins(pass_dir) if r[0] not in done and r[2] is not None]
        report(f"the same passes, lambda of PASS/{remade_sub}/truth where remade", pooled)
    if new:
        remade = twins(args[0], os.path.join(new, "truth"))
        done = {r[0] for r in remade}
        report(f"the same twins, lambda of {new}", remade)
        if len(done) < len(rows):
            report("the passes' own lambda, the same twins", [r for r in rows if r[0] in done])
        old = {r[0]: r for r in rows}
        print("per twin with a planted effect: lambda (oracle power) before -> remade; the loop's baseline excess")
        for r in remade:
            if r[2] is not None:
                o = old[r[0]]
                print(f"  {r[0]}: {o[1]:.1f} ({o[2]:.2f}) -> {r[1]:.1f} ({r[2]:.2f}); excess {r[3]:.1f}")


if __name__ == "__main__":
    main()
