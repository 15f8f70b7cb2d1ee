#!/usr/bin/env python3
"""A blind pass against a replay of it (studies/calibration_replay.sh: the same twins and runs, another
binary or other options), twin by twin.

    /usr/bin/python3 calibrate/replay_compare.py results/calibration-blind-pass20 results/calibration-blind-pass20/replay-cdf64f9

Reads both folders' cases.csv (calibrate/blind_summary.py) and summary.json files and prints, for each:
single effects identified, intervals holding the planted value, nulls with an effect added, the
median relative error of the identified single effects' sizes (|size - truth| / |truth - neutral|,
and / |truth|: the two differ where neutral is not 0, e.g. restitution's 0.5),
and the held-out points' excess over the noise after the fit (sqrt(rms^2 - 1) of the whitened
residuals, fresh seeds) summed over the cases found in both; then, over those cases, in how many
the held-out RMS/noise after the fit rose, fell or stayed from the pass to the replay. The fresh-seed
re-score at other fitted values is another draw of the model's noise (12 held-out points: its
RMS/noise has a standard deviation of about 0.2), so a single case's change says little; a count
of rises against falls says more, and where both ended at the same fitted parameters (marked) a
change is that noise alone. Two replays can be compared the same way (the first as PASS: its truth/
is the pass's). Exit 2 on a folder without cases.csv.
"""
import json
import math
import os
import statistics
import sys

from blind_pass import cases_table
from blind_summary import NOT_SINGLE


def rows(folder):
    return {r["case"]: r for r in cases_table(folder)}


def relative_size_error(folder, truth_folder, row, of_value=False):
    """|size - truth| / |truth - neutral| of the planted effect's added size (with `of_value`,
    / |truth|), or None."""
    with open(os.path.join(folder, row["case"], "summary.json"), encoding="utf-8") as f:
        summary = json.load(f)
    with open(os.path.join(truth_folder, "truth", row["case"] + ".json"), encoding="utf-8") as f:
        truth = json.load(f)
    planted = [v for v in truth["planted"] if v["name"] != "free"][0]
    for e in summary["effects"]:
        if e["key"] == planted["key"]:
            scale = abs(planted["value"]) if of_value else abs(planted["value"] - (planted["neutral"] or 0.0))
            return abs(e["value"] - planted["value"]) / scale
    return None


def same_fit(folder_a, folder_b, case, rel=1e-3):
    """Whether both calibrations of `case` ended at the same parameters (within `rel`, relative)."""
    params = []
    for folder in (folder_a, folder_b):
        with open(os.path.join(folder, case, "summary.json"), encoding="utf-8") as f:
            params.append(json.load(f)["after"]["params"])
    if params[0].keys() != params[1].keys():
        return False
    return all(abs(params[0][k] - params[1][k]) <= rel * max(abs(params[0][k]), abs(params[1][k]), 1e-12)
               for k in params[0])


def excess(rms):
    return math.sqrt(max(float(rms) ** 2 - 1.0, 0.0))


def describe(name, folder, table, truth_folder, found_in_both):
    singles = [r for r in table.values() if r["truth"] not in NOT_SINGLE]
    nulls = [r for r in table.values() if r["truth"] == "none"]
    found = [r for r in singles if r["identified"] == "True"]
    errors = [e for e in (relative_size_error(folder, truth_folder, r) for r in found) if e is not None]
    of_value = [e for e in (relative_size_error(folder, truth_folder, r, True) for r in found) if e is not None]
    covered = sum(int(r["n_covered"] or 0) for r in table.values())
    intervals = sum(int(r["n_intervals"] or 0) for r in table.values())
    added = sum(1 for r in nulls if r["added"] not in ("", "-"))
    held = sum(excess(table[c]["heldout_rms_sigma_after"]) for c in found_in_both)
    print(f"{name}: identified {sum(r['identified'] == 'True' for r in singles)} of {len(singles)}; "
          f"intervals holding the planted value {covered} of {intervals}; nulls with an effect added {added} of "
          f"{len(nulls)}; median relative size error {statistics.median(errors):.3f} over {len(errors)} "
          f"(of the planted departure from neutral; {statistics.median(of_value):.3f} of the planted value); "
          f"held-out excess after the fit, summed over the {len(found_in_both)} cases found in both, {held:.1f}")


def main():
    if len(sys.argv) != 3:
        print("usage: replay_compare.py PASS REPLAY", file=sys.stderr)
        sys.exit(2)
    pass_dir, replay_dir = sys.argv[1], sys.argv[2]
    a, b = rows(pass_dir), rows(replay_dir)
    found = lambda r: r["identified"] == "True" or (r["truth"] == "two effects" and r["added"] not in ("", "-"))
    both = sorted(c for c in a if c in b and found(a[c]) and found(b[c]) and a[c]["heldout_rms_sigma_after"]
                  and b[c]["heldout_rms_sigma_after"])
    describe("pass", pass_dir, a, pass_dir, both)
    describe("replay", replay_dir, b, pass_dir, both)
    change = [float(b[c]["heldout_rms_sigma_after"]) - float(a[c]["heldout_rms_sigma_after"]) for c in both]
    print(f"held-out RMS/noise after the fit, pass -> replay, over the {len(both)} cases found in both: rose in "
          f"{sum(d > 0 for d in change)}, fell in {sum(d < 0 for d in change)}, unchanged in {sum(d == 0 for d in change)}")
    same = [c for c in both if same_fit(pass_dir, replay_dir, c)]
    print(f"  (same fit, every parameter within 1e-3 relative, in {len(same)} of them: there a change of the held-out "
          f"RMS/noise is the fresh-seed re-score's noise alone)")
    for c in both:
        print(f"  {c}: {float(a[c]['heldout_rms_sigma_after']):.2f} -> {float(b[c]['heldout_rms_sigma_after']):.2f}"
              f"{' (same fit)' if c in same else ''}")


if __name__ == "__main__":
    main()
