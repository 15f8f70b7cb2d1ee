#!/usr/bin/env python3
"""Rounds of a finished blind pass in which rule 1's held-out route fired, and what they added.

    /usr/bin/python3 calibrate/route_rounds.py results/calibration-blind-pass18 [more passes...]

The route (`gapflow calibrate --held-out-route`, calibrate/decisions.hpp rule 1) writes one log line
when it fires: "the fitted points are within the noise (chi2 p = P) but the held-out points are not
(fresh seeds, chi2 p = Q): NAME (adjusted p = R) tried". The round's outcome is the next log line
that starts "added NAME", "candidate NAME ... rejected" or, for two contenders, names the tried one.
Each calibration's log is in its report.md. Prints, per firing: the case, its planted effects (from
the pass's truth/CASE.json), the candidate tried, the outcome, whether what was added is the planted
effect (or a group holding it), and the final verdict; then counts per pass. Exit 2 on a folder
without calibrations.
"""
import glob
import json
import os
import re
import sys

FIRED = re.compile(r"the fitted points are within the noise \(chi2 p = ([0-9.eE+-]+)\) but the held-out points "
                   r"are not \(fresh seeds, chi2 p = ([0-9.eE+-]+)\): ([a-z_]+) \(adjusted p = ([0-9.eE+-]+)\) tried")
OUTCOME = re.compile(r"^(?:with [a-z_]+ in place \(a pair\): )?(added ([a-z_]+)|candidate ([a-z_]+) .*rejected)")


def planted_effects(pass_dir, case):
    """Catalogue names planted in a twin (empty for a null; 'set' for an out-of-catalogue change)."""
    path = os.path.join(pass_dir, "truth", case + ".json")
    if not os.path.exists(path):
        return None
    with open(path, encoding="utf-8") as f:
        truth = json.load(f)
    return [p["name"] for p in truth.get("planted", []) if p.get("name") != "free"]


def firings(report_text):
    """(fitted p, held-out p, candidate, adjusted p, outcome line) for each firing, in log order."""
    lines = report_text.splitlines()
    out = []
    for i, line in enumerate(lines):
        m = FIRED.search(line)
        if not m:
            continue
        outcome = next((l for l in lines[i + 1:] if OUTCOME.match(l)), "no outcome line")
        out.append((float(m.group(1)), float(m.group(2)), m.group(3), float(m.group(4)), outcome))
    return out


def main():
    if len(sys.argv) < 2:
        print("usage: route_rounds.py PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    for pass_dir in sys.argv[1:]:
        summaries = sorted(glob.glob(os.path.join(pass_dir, "*", "summary.json")))
        if not summaries:
            print(f"error: no calibrations in {pass_dir}", file=sys.stderr)
            sys.exit(2)
        fired_twins = 0
        for s in summaries:
            case_dir = os.path.dirname(s)
            case = os.path.basename(case_dir)
            with open(os.path.join(case_dir, "report.md"), encoding="utf-8") as f:
                rounds = firings(f.read())
            if not rounds:
                continue
            fired_twins += 1
            with open(s, encoding="utf-8") as f:
                summary = json.load(f)
            planted = planted_effects(pass_dir, case)
            for fitted_p, held_p, candidate, p_adj, outcome in rounds:
                added = OUTCOME.match(outcome)
                added_name = added.group(2) if added else None
                group = next((e.get("group", []) for e in summary["effects"] if e["effect"] == added_name), [])
                hit = "" if added_name is None or planted is None else \
                    ("planted" if added_name in planted or any(p in group for p in planted) else "not planted")
                print(f"{pass_dir} {case} (planted: {', '.join(planted) if planted else 'none' if planted == [] else '?'}): "
                      f"fitted p {fitted_p:g}, held-out p {held_p:g}, {candidate} adjusted p {p_adj:g}; "
                      f"{'added ' + added_name if added_name else 'not added'} {('(' + hit + ')') if hit else ''}; "
                      f"verdict: {summary['verdict']}")
        print(f"{pass_dir}: the route fired in {fired_twins} of {len(summaries)} calibrations")


if __name__ == "__main__":
    main()
