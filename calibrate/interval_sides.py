#!/usr/bin/env python3
"""Which side of the truth the recovered sizes' 95 % intervals miss on, per blind pass.

    /usr/bin/python3 calibrate/interval_sides.py results/calibration-blind-pass13 [more passes...]

For every planted effect that a calibration added (any twin of the pass), its interval either
holds the planted value, or misses it toward the effect's neutral value (the fitted size is
nearer neutral than the truth) or away from it. A fit without bias misses on both sides about
equally often.
"""
import glob
import json
import os
import sys


def sides(pass_dir):
    covered, toward, away = 0, [], []
    for summary in sorted(glob.glob(os.path.join(pass_dir, "*", "summary.json"))):
        case = os.path.basename(os.path.dirname(summary))
        truth_file = os.path.join(pass_dir, "truth", case + ".json")
        if not os.path.exists(truth_file):
            continue
        with open(truth_file) as f:
            truth = {p["key"]: (p["value"], p["neutral"]) for p in json.load(f)["planted"] if p["name"] != "free"}
        with open(summary) as f:
            effects = json.load(f)["effects"]
        for e in effects:
            if e["key"] not in truth:
                continue
            value, neutral = truth[e["key"]]
            if e["lo95"] <= value <= e["hi95"]:
                covered += 1
            elif abs(e["value"] - neutral) < abs(value - neutral):
                toward.append(f"{case} ({e['key']} {e['value']:.4g} for {value:.4g})")
            else:
                away.append(f"{case} ({e['key']} {e['value']:.4g} for {value:.4g})")
    return covered, toward, away


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: interval_sides.py PASS_DIR [PASS_DIR...]")
    for pass_dir in sys.argv[1:]:
        covered, toward, away = sides(pass_dir)
        print(f"{pass_dir}: {covered} intervals hold the planted value; missed toward neutral {len(toward)}, "
              f"away from it {len(away)}")
        for line in toward:
            print(f"  toward: {line}")
        for line in away:
            print(f"  away: {line}")


if __name__ == "__main__":
    main()
