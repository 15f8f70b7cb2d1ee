#!/usr/bin/env python3
"""Rounds of a finished blind pass in which rule 1's held-out route fired, and what they added.

    /usr/bin/python3 calibrate/route_rounds.py results/calibration-blind-pass18 [more passes...]

The route (`gapflow calibrate --held-out-route`, calibrate/decisions.hpp rule 1) writes one log line
when it fires: "the fitted points are within the noise (chi2 p = P) but the held-out points are not
(fresh seeds, chi2 p = Q): NAME (adjusted p = R) tried". The round's outcome is the next log line
that starts "added NAME" or "candidate NAME ... rejected" (with --contenders > 1 the candidate tried
may differ from the one the firing line names: the outcome line names it). A rejected first effect
later kept as a pair is read from summary.json's rounds ("kept as a pair with"), since the log does
not say it. The round's number is 1 + the effects added before the firing. Each calibration's log is
in its report.md. Prints, per firing: the case, its planted effects (from the pass's
truth/CASE.json), the round, the candidate, the outcome, whether what was added is the planted effect
(or a group holding it), and the final verdict; then counts per pass. Folders named replay-* (replays
inside a pass folder) are not the pass's calibrations and are skipped. Exit 2 on a folder without
calibrations.
"""
import json
import os
import re
import sys
from blind_pass import calibrations

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
    """(round, fitted p, held-out p, candidate, adjusted p, outcome line) for each firing, in log order."""
    lines = report_text.splitlines()
    out = []
    for i, line in enumerate(lines):
        m = FIRED.search(line)
        if not m:
            continue
        round_no = 1 + sum(1 for l in lines[:i] if l.startswith("added "))
        outcome = next((l for l in lines[i + 1:] if OUTCOME.match(l)), "no outcome line")
        out.append((round_no, float(m.group(1)), float(m.group(2)), m.group(3), float(m.group(4)), outcome))
    return out


def added_name(outcome, summary):
    """The effect the round added: from its log line, or, for a rejected first effect kept as a pair, from
    summary.json's round decisions."""
    m = OUTCOME.match(outcome)
    if not m:
        return None
    if m.group(2):
        return m.group(2)
    rejected = m.group(3)
    paired = any(r["decision"].startswith(f"candidate {rejected} ") and "kept as a pair with" in r["decision"]
                 for r in summary["rounds"])
    return rejected if paired else None


def main():
    if len(sys.argv) < 2:
        print("usage: route_rounds.py PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    for pass_dir in sys.argv[1:]:
        summaries = [s for _, s in calibrations(pass_dir)]
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
            for round_no, fitted_p, held_p, candidate, p_adj, outcome in rounds:
                added = added_name(outcome, summary)
                group = next((e.get("group", []) for e in summary["effects"] if e["effect"] == added), [])
                hit = "" if added is None or planted is None else \
                    ("planted" if added in planted or any(p in group for p in planted) else "not planted")
                print(f"{pass_dir} {case} (planted: {', '.join(planted) if planted else 'none' if planted == [] else '?'}): "
                      f"round {round_no}: fitted p {fitted_p:g}, held-out p {held_p:g}, {candidate} adjusted p {p_adj:g}; "
                      f"{'added ' + added if added else 'not added'}{(' (' + hit + ')') if hit else ''}; "
                      f"verdict: {summary['verdict']}")
        print(f"{pass_dir}: the route fired in {fired_twins} of {len(summaries)} calibrations")


if __name__ == "__main__":
    main()
