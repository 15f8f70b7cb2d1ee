#!/usr/bin/env python3
"""Where a blind pass's true free parameter lay against the baseline's surface.

Until f62f98f an effect's joint fit was bounded by the baseline's surface: with one free
parameter, the five grid nodes around the baseline's best node. This lists, for every twin of
each pass folder given, that range (read from the report's baseline log: the grid nodes and the
best one), the true value (truth/<case>.json) and the fitted value after the loop, and counts the
twins whose truth lay outside the range, where the fit could not reach it.

    /usr/bin/python3 calibrate/surface_reach.py results/calibration-blind-pass9 [...]
"""
import json
import re
import sys
from pathlib import Path
from blind_pass import calibrations

NODE = re.compile(r"^  (\S+)=([-+0-9.eE]+): chi2 = [-+0-9.eE]+(  <- best node)?$")
AFTER = re.compile(r"^Parameters before: .*After: (\S+?)=([-+0-9.eE]+?)[,.]?(?: |$)")


def reach(report: Path):
    """(key, lo, hi, fitted after) of one calibration report, or None without one free parameter."""
    nodes, best, key, after = [], None, None, {}
    for line in report.read_text().splitlines():
        m = NODE.match(line)
        if m:
            key = m.group(1)
            nodes.append(float(m.group(2)))
            if m.group(3):
                best = len(nodes) - 1
        m = AFTER.match(line)
        if m:
            after[m.group(1)] = float(m.group(2))
    if best is None or key not in after:
        return None
    first = min(max(best - 2, 0), max(len(nodes) - 5, 0))
    window = nodes[first:first + 5]
    return key, min(window), max(window), after[key]


def main(folders):
    for folder in map(Path, folders):
        outside, total = [], 0
        for case, summary in calibrations(folder):
            report = Path(summary).parent / "report.md"
            truth_file = folder / "truth" / f"{case}.json"
            got = reach(report)
            if got is None or not truth_file.exists():
                continue
            key, lo, hi, after = got
            truth = [p["value"] for p in json.loads(truth_file.read_text())["planted"] if p.get("name") == "free"]
            if not truth:
                continue
            total += 1
            if not lo - 1e-9 <= truth[0] <= hi + 1e-9:
                outside.append(f"{case} (surface {lo:.3g}-{hi:.3g}, truth {truth[0]:.3f}, fitted {after:.3f})")
        print(f"{folder}: truth outside the baseline's surface in {len(outside)} of {total} twins")
        for line in outside:
            print(f"  {line}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    main(sys.argv[1:])
