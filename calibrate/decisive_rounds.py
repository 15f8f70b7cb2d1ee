#!/usr/bin/env python3
"""Rounds of finished blind passes where rule 1's option --decisive-score P would have tried an effect.

    /usr/bin/python3 calibrate/decisive_rounds.py P results/calibration-blind-pass13 [more passes...]

The option changes one thing (calibrate/decisions.cpp, should_attribute): a round that rule 1 stops
because the fitted residual is consistent with the noise, and that has a visible best candidate, is
tried when that candidate's adjusted p is below P. Every such round is written in the calibration's
report.md as "the residual is consistent with the noise (chi2 p = ...): nothing to explain (best
candidate NAME: adjusted p = Q)". A calibration is deterministic, so a pass run without the option
and replayed with it differs only from the first round listed here on; where none is listed, the
replay's decisions are the pass's own. Prints each round with Q < P and a count per pass. Reads the
pass's calibrations only (folders with a summary.json; a replay folder's own calibrations lie a
level deeper). Exit 2 on a folder without calibrations.
"""
import os
import re
import sys
from blind_pass import calibrations

STOPPED = re.compile(r"consistent with the noise \(chi2 p = ([0-9.eE+-]+)\): nothing to explain "
                     r"\(best candidate ([a-z_]+): adjusted p = ([0-9.eE+-]+)\)")


def stopped_rounds(report_text):
    """(chi2 p, candidate, adjusted p) of every round rule 1 stopped with a visible best candidate."""
    seen, rounds = set(), []
    for m in STOPPED.finditer(report_text):  # each decision stands in the round table and the log
        if m.group(0) not in seen:
            seen.add(m.group(0))
            rounds.append((float(m.group(1)), m.group(2), float(m.group(3))))
    return rounds


def main():
    if len(sys.argv) < 3:
        print("usage: decisive_rounds.py P PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    threshold = float(sys.argv[1])
    for pass_dir in sys.argv[2:]:
        reports = [os.path.join(os.path.dirname(s), "report.md") for _, s in calibrations(pass_dir)]
        if not reports:
            print(f"error: no calibrations in {pass_dir}", file=sys.stderr)
            sys.exit(2)
        fired, smallest = 0, None
        for report in reports:
            case = os.path.basename(os.path.dirname(report))
            with open(report, encoding="utf-8") as f:
                rounds = stopped_rounds(f.read())
            for chi2_p, candidate, p_adj in rounds:
                smallest = p_adj if smallest is None else min(smallest, p_adj)
                if p_adj < threshold:
                    fired += 1
                    print(f"{pass_dir} {case}: chi2 p {chi2_p:g}, {candidate} adjusted p {p_adj:g} < {threshold:g}")
        print(f"{pass_dir}: {fired} round(s) the option would try; smallest best adjusted p in a stopped round: "
              f"{smallest if smallest is not None else 'none'}")


if __name__ == "__main__":
    main()
