#!/usr/bin/python3
"""Do the form check's false alarms follow the planted effect's signal? (calibrate/form_check.hpp)

For each replay folder given (a blind pass's calibrations with the form check in their summary.json,
e.g. results/calibration-blind-pass21/replay-formcheck), takes the twins whose planted effects were
all identified and tried themselves (cases.csv `tried_planted`: a flag there is a false alarm for a
catalogue effect) and prints, by the signal the planted effects add to their data (cases.csv
`signal_chi2`, lambda: the chi^2 beyond what the free parameters absorb, from the truth), the check
with the smallest adjusted p and whether it flags (adjusted p < 0.05). Then the flag rate below and
above the median lambda, and a one-sided Mann-Whitney test that the flagged twins' lambda is larger
(scipy). A relative error of the effect's modelled response (its interpolation between measured
sizes, its finite-difference noise) would leave a misfit growing with lambda, at a fixed share of
the effect: the check reads any such misfit as a size differing across the design.

    /usr/bin/python3 calibrate/form_check_signal.py REPLAY [REPLAY ...]
"""
import json
import statistics
import sys
from pathlib import Path

from scipy.stats import mannwhitneyu

from blind_pass import cases_table

LEVEL = 0.05


def rows_of(folder):
    """(folder, case, lambda, smallest check) of the twins whose planted effects were tried themselves."""
    out = []
    for row in cases_table(folder):
        if row["tried_planted"] != "True" or not row["signal_chi2"]:
            continue
        checks = json.loads((Path(folder) / row["case"] / "summary.json").read_text()).get("form_checks", [])
        if not checks:
            continue
        smallest = min(checks, key=lambda c: c["p_adjusted"])
        out.append((Path(folder).parent.name, row["case"], float(row["signal_chi2"]), smallest))
    return out


def main(folders):
    if not folders:
        sys.exit(__doc__)
    rows = sorted((r for f in folders for r in rows_of(f)), key=lambda r: r[2])
    if not rows:
        print("error: no twin with its planted effects tried and a form check", file=sys.stderr)
        sys.exit(2)
    print("| pass | case | lambda | smallest adjusted p | split by | S / dof | flags |")
    print("|---|---|---|---|---|---|---|")
    for source, case, lam, c in rows:
        print(f"| {source} | {case} | {lam:.0f} | {c['p_adjusted']:.3g} | {c['column']} | "
              f"{c['statistic']:.1f} / {c['dof']} | {'yes' if c['p_adjusted'] < LEVEL else ''} |")
    median = statistics.median(r[2] for r in rows)
    flagged = [r for r in rows if r[3]["p_adjusted"] < LEVEL]
    low = [r for r in rows if r[2] <= median]
    high = [r for r in rows if r[2] > median]
    count = lambda part: sum(r[3]["p_adjusted"] < LEVEL for r in part)
    print(f"\ntwins: {len(rows)}; flagged: {len(flagged)}; median lambda {median:.0f}")
    print(f"lambda <= median: {count(low)} of {len(low)} flagged; above: {count(high)} of {len(high)}")
    by_observable = sum(r[3]["column"] == "observable" for r in flagged)
    print(f"flags whose smallest check splits by observable: {by_observable} of {len(flagged)}")
    if flagged and len(flagged) < len(rows):
        test = mannwhitneyu([r[2] for r in flagged], [r[2] for r in rows if r not in flagged], alternative="greater")
        print(f"Mann-Whitney, flagged twins' lambda larger: U = {test.statistic:.0f}, one-sided p = {test.pvalue:.3g}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
