#!/usr/bin/env python3
"""Rounds of blind passes whose best significant score asked for a size the effect cannot take.

    /usr/bin/python3 calibrate/wrong_direction_rounds.py results/calibration-blind-pass8 [more passes...]

Reads each calibration's report.md (its round tables: score, adjusted p, linearised size) and lists
the rounds where the highest-scoring visible candidate had adjusted p < 0.05 and a linearised size
below its neutral value although its catalogue range ends there (the effects listed below, whose
range lies on one side of neutral: what calibrate/attribution.hpp's size_direction_possible rules
out since fc9cfe0). Replay folders are skipped.
"""
import os
import re
import sys
from blind_pass import calibrations

# Catalogue effects whose range has no room below neutral (calibrate/effect_catalogue.cpp).
ONE_SIDED = {"linear_drag", "spinning_friction", "lateral_tilt", "corner_rounding", "rolling_contact",
             "rolling_resistance"}


def round_rows(text):
    rows = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.split("|")]
        if len(cells) < 10 or "±" not in cells[8]:
            continue
        try:
            rows.append((cells[1], float(cells[5]), float(cells[7]), float(cells[8].split("±")[0])))
        except ValueError:
            pass
    return rows


def main():
    if len(sys.argv) < 2:
        sys.exit("usage: wrong_direction_rounds.py PASS_DIR [PASS_DIR...]")
    total = 0
    for pass_dir in sys.argv[1:]:
        for report in [os.path.join(os.path.dirname(s), "report.md") for _, s in calibrations(pass_dir)]:
            with open(report) as f:
                rounds = re.split(r"^### Round ", f.read(), flags=re.M)[1:]
            for text in rounds:
                rows = round_rows(text)
                if not rows:
                    continue
                effect, score, p_adjusted, linearised = max(rows, key=lambda r: r[1])
                # The table's linearised size is neutral + estimate; every one-sided effect's neutral is
                # its range's lower end (rolling resistance: 0.001 above it, less than a quarter step).
                neutral = 0.001 if effect == "rolling_resistance" else 0.0
                if effect in ONE_SIDED and linearised < neutral and p_adjusted < 0.05:
                    total += 1
                    print(f"{report} round {text.split()[0]}: {effect} score {score} adjusted p {p_adjusted} "
                          f"linearised size {linearised}")
    print(f"{total} round(s)")


if __name__ == "__main__":
    main()
