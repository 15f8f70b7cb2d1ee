#!/usr/bin/python3
"""How often the recovered sizes' 95 % intervals hold the planted value, pooled over blind passes,
by the planted effect's key.

    /usr/bin/python3 calibrate/interval_coverage.py PASS_DIR [PASS_DIR...]

Every interval counts that a calibration gave for a key a twin planted (an effect added as itself;
a planted effect found only as a member of another's group has no interval of its own). Per key and
pooled: the intervals; how many hold the truth (ends included), with the exact 95 % interval of that
rate; how many of the others miss toward the effect's neutral value (the size read nearer neutral
than planted) and how many away from it (calibrate/interval_sides.py lists them); the median of
|z| = |truth - value| / (h / 1.96) over all intervals, h the interval's half on the truth's side (a
Wald reading of an interval that may be asymmetric; 0.67 for intervals that are right); and the
factor the intervals would need to be widened by to hold 95 % of the truths (the 95th percentile of
|z| over 1.96, from 20 intervals on; "inf" where a miss has no half on the truth's side, the fitted
size at its range's end). A second table sets the size read (its departure from neutral over the
planted one: 1 exact, below 1 toward neutral) against the free parameter's fitted excess over its
truth (the particle friction in the blind study), with their Pearson correlation (from 5 sizes on),
and the size against the free parameter's measurement beside the data less its truth (truth.json
"measured"; drawn with the twin, before any fit).
A third table counts intervals (not twins) whose twin's true free parameter lay outside the final
fit's surface window: with one free parameter, the profile minimises the free parameter within five
consecutive nodes of the baseline grid (fit.cpp surface_window), and where the truth's lies outside,
the profile cannot pass through the truth (the pass's `design` file names the data file whose [[free]]
gives the grid). A proxy: the profile at the planted size puts the free parameter where it fits best
for that size, not at its truth. Where summary.json records the window (after.surface_window,
binaries from 2026-11-29 on, none of passes up to 24) it is exact; otherwise approximate: the window
is taken around the fitted value, where fit.cpp takes it around the node the final surface was built
at, which for a first-round fit that did not move (the baseline's best node) can be one node off;
passes before f62f98f bounded every effect's fit by the baseline's window.
The last lines count what was left out: effects added without an interval, planted values at
neutral (no share), twins with other than one free parameter (no excess).

The passes' twins are not independent draws of everything: the cases repeat from pass to pass with
sizes drawn from the same ranges, and up to pass 19 a pass's twins shared one draw of the model's
noise. The binomial interval treats them as independent and is too narrow by an unknown amount.
"""
import collections
import json
import math
import os
import statistics
import sys
import tomllib

from blind_pass import calibrations
from interval_sides import side_of
from visibility_ceiling import clopper_pearson

GRID_MAX = 9       # CalibrationDef::grid_max (calibrate/calibration.hpp)
WINDOW_NODES = 5   # fit.cpp surface_window
MIN_FOR_FACTOR = 20
MIN_FOR_CORRELATION = 5


def free_grids(pass_dir):
    """{key: baseline grid levels} of the pass's design (fit.cpp grid_levels with one free parameter:
    its step from lo, at most GRID_MAX levels, spread evenly if more would be needed); {} without a
    design file or with other than one free parameter."""
    design_file = os.path.join(pass_dir, "design")
    if not os.path.exists(design_file):
        return {}
    with open(design_file) as f:
        data_file = f.read().strip()
    if not os.path.isabs(data_file):  # written relative to the repository's root
        data_file = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), data_file)
    if not os.path.exists(data_file):
        return {}
    with open(data_file, "rb") as f:
        free = tomllib.load(f).get("free", [])
    if len(free) != 1:
        return {}
    lo, hi, step = free[0]["lo"], free[0]["hi"], free[0]["step"]
    levels = math.floor((hi - lo) / step + 1e-9) + 1
    if levels > GRID_MAX:
        levels, step = GRID_MAX, (hi - lo) / (GRID_MAX - 1)
    return {free[0]["key"]: [lo + k * step for k in range(levels)]}


def window_around(grid, value):
    """The (lo, hi) of the surface's window around a fitted value (fit.cpp surface_window)."""
    if len(grid) <= WINDOW_NODES:
        return grid[0], grid[-1]
    nearest = min(range(len(grid)), key=lambda k: abs(grid[k] - value))
    first = min(max(nearest - 2, 0), len(grid) - WINDOW_NODES)
    return grid[first], grid[first + WINDOW_NODES - 1]


def truth_outside_window(grids, fitted, free, recorded=None):
    """Whether the twin's true free parameter lies outside the final fit's surface window (None when
    that cannot be said: no grid, or the free parameter not fitted). `recorded`: summary.json's
    after.surface_window ({key: [lo, hi]}, binaries from 2026-11-29 on), exact where given; else the
    window is reconstructed around the fitted value (approximate, see the module's docstring)."""
    if len(free) != 1:
        return None   # the table is of twins with one free parameter (with more, the surface spans the grid)
    for key, (lo, hi) in (recorded or {}).items():
        if key in free:
            return not lo - 1e-9 <= free[key] <= hi + 1e-9
    for key, grid in grids.items():
        if key in fitted and key in free:
            lo, hi = window_around(grid, fitted[key])
            return not lo - 1e-9 <= free[key] <= hi + 1e-9
    return None


def intervals(pass_dirs, left_out):
    """{key: [interval, ...]} over every interval of a planted key in the passes given. Each interval:
    side ("held", "toward" neutral or "away"), z (|miss| in the interval's se; inf for a miss with no
    half on the truth's side), share (the size's departure from neutral over the planted one: 1 exact,
    below 1 toward neutral; None with the planted value at neutral) and free_excess (the free parameter
    fitted less its truth; None unless the twin has exactly one), measurement_error (the free parameter's
    measurement less its truth) and truth_outside_window (truth_outside_window below). `left_out` counts
    what was skipped."""
    out = {}
    for pass_dir in pass_dirs:
        if not os.path.isdir(pass_dir):
            print(f"error: no folder {pass_dir}", file=sys.stderr)
            sys.exit(2)
        grids = free_grids(pass_dir)
        for case, summary in calibrations(pass_dir):
            truth_file = os.path.join(pass_dir, "truth", case + ".json")
            if not os.path.exists(truth_file):
                continue
            with open(truth_file) as f:
                truth_json = json.load(f)
            planted = truth_json["planted"]
            with open(summary) as f:
                s = json.load(f)
            free = {p["key"]: p["value"] for p in planted if p["name"] == "free"}
            fitted = s.get("after", {}).get("params", {})
            excess = [fitted[k] - v for k, v in free.items() if k in fitted]
            # The free parameter's measurement beside the data less its truth: drawn before any fit.
            measured = truth_json.get("measured", {})
            measurement_error = [measured[k] - v for k, v in free.items() if k in measured]
            effects = {p["key"]: (p["value"], p["neutral"]) for p in planted if p["name"] != "free"}
            for e in s["effects"]:
                if e["key"] not in effects:
                    continue
                if e.get("lo95") is None or e.get("hi95") is None:
                    left_out["effects added without an interval"] += 1
                    continue
                truth, neutral = effects[e["key"]]
                if truth == neutral:
                    left_out["planted values at neutral (no share)"] += 1
                if len(excess) != 1:
                    left_out["sizes of twins without exactly one free parameter (no excess)"] += 1
                out.setdefault(e["key"], []).append({
                    "side": side_of(e, truth, neutral), "z": z_of(e, truth),
                    "share": (e["value"] - neutral) / (truth - neutral) if truth != neutral else None,
                    "free_excess": excess[0] if len(excess) == 1 else None,
                    "measurement_error": measurement_error[0] if len(measurement_error) == 1 else None,
                    "truth_outside_window": truth_outside_window(grids, fitted, free,
                                                                 s.get("after", {}).get("surface_window"))})
    return out


def z_of(e, truth):
    """|truth - value| over the interval's standard error on the truth's side (its half there / 1.96)."""
    half = e["hi95"] - e["value"] if truth > e["value"] else e["value"] - e["lo95"]
    if half > 0:
        return abs(truth - e["value"]) / (half / 1.96)
    return 0.0 if truth == e["value"] else math.inf


def percentile_95(sorted_values):
    """The smallest value at or below which 95 % of them lie."""
    return sorted_values[math.ceil(0.95 * len(sorted_values)) - 1]


def coverage_line(name, entries):
    n = len(entries)
    held = sum(1 for i in entries if i["side"] == "held")
    toward = sum(1 for i in entries if i["side"] == "toward")
    lo, hi = clopper_pearson(held, n)
    zs = sorted(i["z"] for i in entries)
    factor = f"{percentile_95(zs) / 1.96:.1f}" if len(zs) >= MIN_FOR_FACTOR else "-"
    return (f"| {name} | {n} | {held} ({100 * held / n:.0f} %; {100 * lo:.0f}-{100 * hi:.0f} %) | "
            f"{toward} / {n - held - toward} | {statistics.median(zs):.2f} | {factor} |")


def correlation_text(entries, field):
    """Pearson correlation of the share with `field` over the sizes that have both (from 5 on; "-" below)."""
    pairs = [(i["share"], i[field]) for i in entries if i["share"] is not None and i[field] is not None]
    if len(pairs) >= MIN_FOR_CORRELATION and len({x for x, _ in pairs}) > 1 and len({y for _, y in pairs}) > 1:
        return f"{statistics.correlation([x for x, _ in pairs], [y for _, y in pairs]):+.2f}"
    return "-"


def trade_off_line(name, entries):
    """The size read against the free parameter's excess: a size that trades off against the free parameter
    comes out small where the free parameter comes out high (a negative correlation). Both are outputs of
    one fit; the measurement's error is not (drawn with the twin), so a correlation with it says which
    way the trade runs: a measurement that happened to be high drew the free parameter up and the size
    down."""
    shares = [i["share"] for i in entries if i["share"] is not None]
    excesses = [i["free_excess"] for i in entries if i["share"] is not None and i["free_excess"] is not None]
    errors = [i["measurement_error"] for i in entries if i["share"] is not None and i["measurement_error"] is not None]
    excess = f"{statistics.median(excesses):+.3f}" if excesses else "-"
    error = f"{statistics.median(errors):+.3f}" if errors else "-"
    share = f"{statistics.median(shares):.2f}" if shares else "-"
    return (f"| {name} | {len(shares)} | {share} | {excess} | {correlation_text(entries, 'free_excess')} | "
            f"{error} | {correlation_text(entries, 'measurement_error')} |")


def window_line(name, entries):
    """Of the intervals that held and of those that missed, how many had the truth's free parameter
    outside the final fit's surface window (of those where it can be said)."""
    def count(held):
        known = [i for i in entries if (i["side"] == "held") == held and i["truth_outside_window"] is not None]
        return f"{sum(1 for i in known if i['truth_outside_window'])} of {len(known)}"
    return f"| {name} | {count(True)} | {count(False)} |"


def print_table(header, alignment, line, by_key, pooled):
    """A markdown table: the header, one line per planted key (and one over all keys if `pooled`), a blank line."""
    print(header)
    print(alignment)
    for key in sorted(by_key):
        print(line(key, by_key[key]))
    if pooled:
        print(line("all", [i for entries in by_key.values() for i in entries]))
    print()


def main(args):
    if not args:
        print("usage: interval_coverage.py PASS_DIR [PASS_DIR...]", file=sys.stderr)
        return 2
    left_out = collections.Counter()
    by_key = intervals(args, left_out)
    if not by_key:
        print("no interval of a planted key in the passes given")
        return 0
    print_table("| planted key | intervals | hold the truth (exact 95 %) | misses toward neutral / away | "
                "median \\|z\\| (0.67 if right) | widening for 95 % |", "| :-- | --: | :-- | :-: | --: | --: |", coverage_line,
                by_key, pooled=True)
    print_table("| planted key | sizes | median size / planted (from neutral) | median free parameter less its truth | "
                "correlation of the two | median measurement of the free parameter less its truth | "
                "correlation of the size with it |", "| :-- | --: | --: | --: | --: | --: | --: |", trade_off_line, by_key,
                pooled=False)
    print_table("| planted key | held: truth's free parameter outside the final window | "
                "missed: truth's free parameter outside the final window |", "| :-- | --: | --: |", window_line, by_key,
                pooled=True)
    for what in ("effects added without an interval", "planted values at neutral (no share)",
                 "sizes of twins without exactly one free parameter (no excess)"):
        print(f"left out: {what}: {left_out[what]}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
