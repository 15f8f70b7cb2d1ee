#!/usr/bin/python3
"""Whether a blind pass and its control (another loop replayed on the pass's store) start from the same
baseline, twin by twin: a change that acts only once an effect's term is measured (the effect term's noise)
must leave every calibration's baseline as it was, and a difference there is a bug, not a finding. Also,
for the pass, how many added effects had their sizes' correlation counted rather than bounded (summary.json
size_correlation, null where the bound was used; builds from 2c7c6e6 on write it).

    /usr/bin/python3 calibrate/control_baseline.py PASS CONTROL

For every case with a summary.json in both folders: the baseline's fitted free parameters and its fitted
points' chi^2 (summary.json "before"), equal when they differ by at most 1e-9 relative. Prints each case
that differs, then "baseline: N of M calibrations the same", then the size-correlation count. Exit 2 on
usage or when no case is in both folders; 0 otherwise (the count is read, not judged, here)."""
import json
import sys
from pathlib import Path


def summaries(folder):
    """{case: summary.json} of every calibration folder in `folder`."""
    out = {}
    for path in sorted(Path(folder).glob("*/summary.json")):
        with open(path) as f:
            out[path.parent.name] = json.load(f)
    return out


def close(a, b):
    return a == b or abs(a - b) <= 1e-9 * max(abs(a), abs(b))


def baseline_differences(one, other):
    """What differs between two calibrations' baselines, as text (empty: the same)."""
    a, b = one["before"], other["before"]
    out = []
    if set(a["params"]) != set(b["params"]):
        out.append(f"free parameters {sorted(a['params'])} against {sorted(b['params'])}")
    else:
        out += [f"{k} {a['params'][k]!r} against {b['params'][k]!r}" for k in sorted(a["params"])
                if not close(a["params"][k], b["params"][k])]
    if not close(a["fitted"]["chi2"], b["fitted"]["chi2"]):
        out.append(f"fitted chi2 {a['fitted']['chi2']!r} against {b['fitted']['chi2']!r}")
    return out


def size_correlation_count(pass_summaries):
    """(added effects with size_correlation counted, added effects, of them whose summary has the field)."""
    counted = added = known = 0
    for s in pass_summaries.values():
        for e in s.get("effects", []):
            added += 1
            if "size_correlation" in e:
                known += 1
                counted += e["size_correlation"] is not None
    return counted, added, known


def main(args):
    if len(args) != 2 or not all(Path(a).is_dir() for a in args):
        print(__doc__, file=sys.stderr)
        return 2
    mine, control = summaries(args[0]), summaries(args[1])
    both = sorted(set(mine) & set(control))
    if not both:
        print(f"error: no calibration is in both {args[0]} and {args[1]}", file=sys.stderr)
        return 2
    same = 0
    for case in both:
        diff = baseline_differences(mine[case], control[case])
        if diff:
            print(f"{case}: DIFFERS: " + "; ".join(diff))
        else:
            same += 1
    print(f"baseline: {same} of {len(both)} calibrations the same")
    counted, added, known = size_correlation_count(mine)
    print(f"{args[0]}: the sizes' correlation counted for {counted} of {added} added effects"
          + (f" ({added - known} from a build without the field)" if known < added else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
