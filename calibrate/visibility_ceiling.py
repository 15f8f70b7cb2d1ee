#!/usr/bin/env python3
"""How far a blind pass's single-effect score is limited by what its data show.

    /usr/bin/python3 calibrate/visibility_ceiling.py results/calibration-blind-pass10 [more passes...]

Reads each pass's cases.csv and, over its single-effect twins (every catalogue effect alone at a
low and a high size), counts: identified (alone or in a reported group that holds it), visible to
the oracle (power >= 0.8 of a score test that knew the planted signature), and identified among the
visible. Which twins are single and which visible is cases.csv's own (its truth and visible columns,
by calibrate/blind_summary.py), so the counts are the pass report's. "Ceiling" is visible / singles: the share a loop would
score that finds exactly what the oracle can see and nothing else. The last line pools the passes
given. Exit 2 on a folder without cases.csv.
"""
import csv
import os
import sys

from blind_summary import NOT_SINGLE


def counts(pass_dir):
    path = os.path.join(pass_dir, "cases.csv")
    if not os.path.isfile(path):
        print(f"error: no cases.csv in {pass_dir}", file=sys.stderr)
        sys.exit(2)
    with open(path, newline="", encoding="utf-8") as f:
        singles = [r for r in csv.DictReader(f) if r["truth"] not in NOT_SINGLE]
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


def main():
    if len(sys.argv) < 2:
        print("usage: visibility_ceiling.py PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    total = {"singles": 0, "identified": 0, "visible": 0, "visible_identified": 0}
    for pass_dir in sys.argv[1:]:
        c = counts(pass_dir)
        print(line(pass_dir, c))
        for k in total:
            total[k] += c[k]
    if len(sys.argv) > 2:
        print(line("pooled", total))


if __name__ == "__main__":
    main()
