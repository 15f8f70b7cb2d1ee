#!/usr/bin/env python3
"""Which side of the truth the recovered sizes' 95 % intervals miss on, per blind pass.

    /usr/bin/python3 calibrate/interval_sides.py results/calibration-blind-pass13 [more passes...]

For every planted effect that a calibration added (any twin of the pass), its interval either
holds the planted value, or misses it toward the effect's neutral value (the fitted size is
nearer neutral than the truth) or away from it. A fit without bias misses on both sides about
equally often. Each miss also says how far the fit left the free parameter from its measurement
(in the measurement's standard errors, as summary.json's measured_free gives them), and the last
lines compare that
distance between the intervals that held and those that missed, over all passes given.
"""
import json
import os
import statistics
import sys
from blind_pass import calibrations


def friction_sigmas(summary):
    """How far the fit left the free parameter from its measurement, in the measurement's standard
    errors, both as the calibration read them (summary.json "measured_free"); None without one."""
    for m in summary.get("measured_free", []):
        fitted = summary["after"]["params"].get(m["key"])
        if fitted is not None and m["se"] > 0:
            return (fitted - m["measured"]) / m["se"]
    return None


def side_of(e, truth, neutral):
    """Where an added effect's interval (summary.json lo95, hi95) stands to the planted value: "held" (ends
    included), "toward" (the size nearer neutral than the truth) or "away"."""
    if e["lo95"] <= truth <= e["hi95"]:
        return "held"
    return "toward" if abs(e["value"] - neutral) < abs(truth - neutral) else "away"


def sides(pass_dir):
    """(intervals holding the truth, misses toward neutral, misses away), each miss a line, and the free
    parameter's distance from its measurement (in its standard errors) for each interval, by side."""
    covered, toward, away = 0, [], []
    far = {"covered": [], "toward": [], "away": []}
    for case, summary in calibrations(pass_dir):
        truth_file = os.path.join(pass_dir, "truth", case + ".json")
        if not os.path.exists(truth_file):
            continue
        with open(truth_file) as f:
            truth_json = json.load(f)
        truth = {p["key"]: (p["value"], p["neutral"]) for p in truth_json["planted"] if p["name"] != "free"}
        with open(summary) as f:
            summary_json = json.load(f)
        sigmas = friction_sigmas(summary_json)
        note = f"; free parameter {sigmas:+.1f} se from its measurement" if sigmas is not None else ""
        for e in summary_json["effects"]:
            if e["key"] not in truth:
                continue
            value, neutral = truth[e["key"]]
            side = side_of(e, value, neutral)
            if side == "held":
                covered += 1
                side = "covered"
            else:
                (toward if side == "toward" else away).append(
                    f"{case} ({e['key']} {e['value']:.4g} for {value:.4g}{note})")
            if sigmas is not None:
                far[side].append(sigmas)
    return covered, toward, away, far


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: interval_sides.py PASS_DIR [PASS_DIR...]")
    pooled = {"covered": [], "toward": [], "away": []}
    for pass_dir in sys.argv[1:]:
        covered, toward, away, far = sides(pass_dir)
        print(f"{pass_dir}: {covered} intervals hold the planted value; missed toward neutral {len(toward)}, "
              f"away from it {len(away)}")
        for line in toward:
            print(f"  toward: {line}")
        for line in away:
            print(f"  away: {line}")
        for side in pooled:
            pooled[side] += far[side]
    # Is a miss the fit's free parameter straying from its measurement (a missing effect pulls it away,
    # and the effect's joint fit starts there)? Compare the misses with the intervals that held.
    for side, values in pooled.items():
        if values:
            beyond = sum(1 for v in values if abs(v) > 2)
            print(f"{side}: {len(values)} interval(s); free parameter more than 2 se from its measurement in "
                  f"{beyond}; median |distance| {statistics.median(abs(v) for v in values):.2f} se")


if __name__ == "__main__":
    main()
