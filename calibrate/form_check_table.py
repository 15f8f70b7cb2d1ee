#!/usr/bin/python3
"""The form check (calibrate/form_check.hpp) over a blind pass: per calibration, what was planted and
added, the verdict, the check with the smallest adjusted p, and what each check could see (its
detectable spread: the smallest spread of the effect's size across the column, as a share of the
fitted departure from neutral, flagged with power 0.8; binaries from 98daef1 report it); then the counts a pass's README quotes
(flags on identified twins whose planted effect was the one tried: false alarms for a catalogue
effect; flags on the other calibrations). With REFERENCE (another folder of the same twins, e.g. the
pass itself or a replay without the check), also whether each calibration added the same effects with
the same sizes.

    /usr/bin/python3 calibrate/form_check_table.py PASS [REFERENCE]
"""
import json
import sys
from pathlib import Path

from blind_pass import cases_table


def smallest_check(summary):
    """The check with the smallest adjusted p, as text: its effect and split, the score statistic S with
    its degrees of freedom, and the scale of the rest of the residual with the rest's degrees of freedom
    (p is of S / (dof x scale) against Fisher's F on those two)."""
    checks = summary.get("form_checks", [])
    if not checks:
        return "no check"
    k = min(checks, key=lambda c: c["p_adjusted"])
    return (f"{k['p_adjusted']:.3g} ({k['effect']} split by {k['column']}: S {k['statistic']:.1f} on {k['dof']} dof; "
            f"rest scale {k['scale']:.2f} on {k['rest_dof']} dof)")


def spread_text(check):
    """A check's detectable spread as text: a percentage, 'none' (nothing can be seen), 'no order' (the
    levels have none to trend along) or 'not reported' (a binary before 98daef1)."""
    if "detectable_spread" not in check:
        return "not reported"
    if check.get("trend_ordered") is False:
        return "no order"
    v = check["detectable_spread"]
    return "none" if v is None else f"{100 * v:.0f} %"


def spreads(summary):
    """Each check's detectable spread, by effect and column."""
    checks = summary.get("form_checks", [])
    if not checks:
        return "-"
    several = len({c["effect"] for c in checks}) > 1
    return "; ".join(f"{c['effect'] + ' ' if several else ''}{c['column']} {spread_text(c)}" for c in checks)


def main(folder, reference=None):
    folder = Path(folder)
    flagged_found, flagged_other, found, changed = [], [], 0, []
    print("| case | planted | added | verdict | smallest adjusted p of the form check | detectable spread by column |")
    print("|---|---|---|---|---|---|")
    for row in sorted(cases_table(folder), key=lambda r: r["case"]):
        case = row["case"]
        s = json.loads((folder / case / "summary.json").read_text())
        print(f"| {case} | {row['planted'] or row['truth']} | {row['added'] or '-'} | {s['verdict']} | "
              f"{smallest_check(s)} | {spreads(s)} |")
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
