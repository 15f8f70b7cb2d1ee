#!/usr/bin/python3
"""One line per variant of run.sh's output files: twins, how each ended, the intervals that hold the
planted spinning friction, the size read over the planted one, and the trade with the friction.

    /usr/bin/python3 results/calibration-interval-coverage/closed-form/summarise.py > results/calibration-interval-coverage/closed-form/summary.md
"""
import glob
import os
import re
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "calibrate"))
from visibility_ceiling import clopper_pearson  # noqa: E402

LINE = re.compile(r"seed +\d+: planted ([\d.]+), friction ([\d.]+) measured ([\d.]+) fitted ([\d.]+); (.*)")
SIZE = re.compile(r"spinning_friction ([\d.]+) \[([\d.]+), ([\d.]+)\]")


counts = [0, 0]  # intervals holding, intervals, over every variant


def variant(path):
    twins = as_drag = nothing = 0
    unfound_excess = []  # the friction fitted less its truth where spinning friction was not added
    share, held, excess, error = [], 0, [], []
    for line in open(path):
        m = LINE.match(line)
        if not m:
            continue
        twins += 1
        planted, truth, measured, fitted = map(float, m.groups()[:4])
        s = SIZE.search(m.group(5))
        if not s:
            as_drag += m.group(5).startswith("linear_drag")
            nothing += "(not found)" in m.group(5) and not m.group(5).startswith("linear_drag")
            unfound_excess.append(fitted - truth)
            continue
        value, lo, hi = map(float, s.groups())
        share.append(value / planted)
        held += lo <= planted <= hi
        excess.append(fitted - truth)
        error.append(measured - truth)
    corr = lambda x, y: f"{statistics.correlation(x, y):+.2f}" if len(x) >= 5 else "-"
    counts[0] += held
    counts[1] += len(share)
    at_end = sum(1 for line in open(path) if (s := SIZE.search(line)) and float(s.group(3)) >= 1.0)
    return (f"| {os.path.basename(path)[:-4]} | {twins} | {len(share)} | {as_drag} | {nothing} | {held} of {len(share)} | "
            f"{at_end} | {statistics.median(share):.2f} | {statistics.median(excess):+.3f} | {corr(share, excess)} | "
            f"{statistics.median(error):+.3f} | {corr(share, error)} | {statistics.median(unfound_excess):+.3f} |")


here = os.path.dirname(os.path.abspath(__file__))
print("| variant | twins | spinning friction added | linear drag added instead | nothing added | "
      "intervals holding the planted size | of them ending at the range's end (1 mm) | "
      "median size / planted | median friction fitted less its truth | correlation of the two | "
      "median measurement less truth | correlation of the size with it | "
      "median friction fitted less its truth where spinning friction was not added |")
print("| :-- | --: | --: | --: | --: | :-- | --: | --: | --: | --: | --: | --: | --: |")
for path in sorted(glob.glob(os.path.join(here, "*.txt"))):
    print(variant(path))
lo, hi = clopper_pearson(*counts)
print(f"\nOver every variant: {counts[0]} of {counts[1]} intervals hold the planted size (exact 95 % interval of "
      f"the rate {100 * lo:.0f}-{100 * hi:.0f} %, as if independent: the variants share their 30 truths and data).")
