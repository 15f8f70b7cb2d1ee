#!/usr/bin/python3
"""The form check (calibrate/form_check.hpp) over a blind pass: per calibration, what was planted and
added, the verdict, and the check with the smallest adjusted p; then the counts a pass's README quotes
(flags on identified twins whose planted effect was the one tried: false alarms for a catalogue
effect; flags on the other calibrations). With REFERENCE (another folder of the same twins, e.g. the pass itself or a replay
without the check), also whether each calibration added the same effects with the same sizes.

    /usr/bin/python3 calibrate/form_check_table.py PASS [REFERENCE]
"""
import csv
import json
import sys
from pathlib import Path


def main(folder, reference=None):
    folder = Path(folder)
    with open(folder / "cases.csv", newline="") as f:
        cases = {r["case"]: r for r in csv.DictReader(f)}
    flagged_found, flagged_other, found, changed = [], [], 0, []
    print("| case | planted | added | verdict | smallest adjusted p (effect, split by, statistic / scale on dof) |")
    print("|---|---|---|---|---|")
    for case, row in sorted(cases.items()):
        s = json.loads((folder / case / "summary.json").read_text())
        checks = s.get("form_checks", [])
        best = min(checks, key=lambda k: k["p_adjusted"]) if checks else None
        text = (f"{best['p_adjusted']:.3g} ({best['effect']}, {best['column']}, {best['statistic']:.1f} / "
                f"{best['scale']:.2f} on {best['dof']})" if best else "no check")
        print(f"| {case} | {row['planted'] or row['truth']} | {row['added'] or '-'} | {s['verdict']} | {text} |")
        # A false alarm only where the planted effect itself was tried (not another for its group).
        tried_planted = row["identified"] == "True" and row["tried_planted"] == "True"
        found += tried_planted
        if s.get("form_differs"):
            (flagged_found if tried_planted else flagged_other).append(case)
        if reference is not None:
            ref = json.loads((Path(reference) / case / "summary.json").read_text())
            if ref["effects"] != s["effects"]:
                changed.append(case)
    print()
    print(f"identified single or two-effect twins, the planted effect tried, flagged (false alarms for a catalogue effect): "
          f"{len(flagged_found)} of {found} {flagged_found}")
    print(f"other calibrations flagged: {flagged_other}")
    if reference is not None:
        print(f"effects or sizes differing from {reference}: {changed or 'none'}")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    main(*sys.argv[1:])
