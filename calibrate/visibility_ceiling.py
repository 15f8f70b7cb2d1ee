#!/usr/bin/env python3
"""How far a blind pass's single-effect score is limited by what its data show.

    /usr/bin/python3 calibrate/visibility_ceiling.py results/calibration-blind-pass10 [more passes...]

Reads each pass's cases.csv and, over its single-effect twins (every catalogue effect alone at a
low and a high size), counts: identified (alone or in a reported group that holds it), visible to
the oracle (power >= 0.8 of a score test that knew the planted signature), and identified among the
visible. Which twins are single and which visible is cases.csv's own (its truth and visible columns,
by calibrate/blind_summary.py), so the counts are the pass report's. "Ceiling" is visible / singles: the share a loop would
score that finds exactly what the oracle can see and nothing else. The last line pools the passes
given, with a 95 % Clopper-Pearson interval on the identified share (the twins taken as independent
trials: up to pass 19 every twin of a pass fitted one draw of the model's noise, so that interval is
too narrow for them). `--by-case` adds, per case over the passes given, how often it was identified
and how often visible: where the misses are. Exit 2 on a folder without cases.csv.

    /usr/bin/python3 calibrate/visibility_ceiling.py --by-case results/calibration-blind-pass{10,12,13,14,15,16,17,18,19}
"""
import csv
import os
import sys

from scipy.stats import beta

from blind_summary import NOT_SINGLE


def single_rows(pass_dir):
    path = os.path.join(pass_dir, "cases.csv")
    if not os.path.isfile(path):
        print(f"error: no cases.csv in {pass_dir}", file=sys.stderr)
        sys.exit(2)
    with open(path, newline="", encoding="utf-8") as f:
        return [r for r in csv.DictReader(f) if r["truth"] not in NOT_SINGLE]


def clopper_pearson(k, n, level=0.95):
    """The exact binomial interval for k successes of n."""
    a = (1 - level) / 2
    lo = beta.ppf(a, k, n - k + 1) if k > 0 else 0.0
    hi = beta.ppf(1 - a, k + 1, n - k) if k < n else 1.0
    return lo, hi


def counts(pass_dir):
    singles = single_rows(pass_dir)
    visible = [r for r in singles if r["visible"] == "True"]
    return {
        "singles": len(singles),
        "identified": sum(r["identified"] == "True" for r in singles),
        "visible": len(visible),
        "visible_identified": sum(r["identified"] == "True" for r in visible),
    }


def line(name, c):
    pct = lambda a, b: f"{100 * a / b:.0f} %" if b else "-"
    return (f"{name}: identified {c['identified']} of {c['singles']} ({pct(c['identified'], c['singles'])}); "
            f"visible {c['visible']} (ceiling {pct(c['visible'], c['singles'])}); "
            f"identified among the visible {c['visible_identified']} of {c['visible']} "
            f"({pct(c['visible_identified'], c['visible'])})")


def by_case(pass_dirs):
    cases = {}
    for pass_dir in pass_dirs:
        for r in single_rows(pass_dir):
            c = cases.setdefault(r["case"], {"n": 0, "identified": 0, "visible": 0, "visible_identified": 0})
            c["n"] += 1
            c["identified"] += r["identified"] == "True"
            c["visible"] += r["visible"] == "True"
            c["visible_identified"] += r["visible"] == "True" and r["identified"] == "True"
    print("case: identified of passes; visible; identified among the visible")
    for name, c in sorted(cases.items(), key=lambda item: (item[1]["identified"] - item[1]["n"], item[0])):
        print(f"  {name}: {c['identified']} of {c['n']}; visible {c['visible']}; "
              f"{c['visible_identified']} of {c['visible']}")


def main():
    args = sys.argv[1:]
    with_cases = "--by-case" in args
    pass_dirs = [a for a in args if a != "--by-case"]
    if not pass_dirs:
        print("usage: visibility_ceiling.py [--by-case] PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    total = {"singles": 0, "identified": 0, "visible": 0, "visible_identified": 0}
    for pass_dir in pass_dirs:
        c = counts(pass_dir)
        print(line(pass_dir, c))
        for k in total:
            total[k] += c[k]
    if len(pass_dirs) > 1:
        lo, hi = clopper_pearson(total["identified"], total["singles"])
        print(line("pooled", total) + f"; identified share 95 % interval [{100 * lo:.1f}, {100 * hi:.1f}] %")
    if with_cases:
        by_case(pass_dirs)


if __name__ == "__main__":
    main()
