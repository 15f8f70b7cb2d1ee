#!/usr/bin/python3
"""Case A (issue 14): the 2D model's error against the 3D data, by group of points,
before and after the calibration loop, from the calibration's own points.csv.

    studies/case_a_summary.py results/calibration/case_a > results/calibration/case_a/groups.md

Groups: the fitted points; held out: the gap not used in the fit (W/d 6), the size not
used in the fit (large spheres) and the obstruction cases (W = 33 mm, with and without the
A). Error = RMS over the group of ln(J_2D / J_3D) (the fit's own log scale; x100 ~ %),
and of the residual in units of the data's standard error; J_2D/J_3D per point.
"""
import csv
import math
import sys


def group_of(row):
    if row["held_out"] == "0":
        return "fitted (small, medium at W/d 4, 5, 8)"
    if row["shape"] != "none" or abs(float(row["W_over_d"]) - 4.258) < 0.01:
        return "held out: obstruction cases (W = 33 mm, medium)"
    if row["size"] == "large":
        return "held out: size not fitted (large, W/d 4-8)"
    return "held out: gap not fitted (W/d 6, small and medium)"


def rms(xs):
    return math.sqrt(sum(x * x for x in xs) / len(xs)) if xs else float("nan")


def main(folder):
    rows = list(csv.DictReader(open(f"{folder}/points.csv")))
    groups = {}
    for r in rows:
        groups.setdefault(group_of(r), []).append(r)
    print("| points | n | RMS ln(J_2D/J_3D) before | after | RMS residual/se before | after |")
    print("|---|---|---|---|---|---|")
    held_before, held_after = [], []
    for name in sorted(groups, key=lambda g: (g.startswith("held"), g)):
        g = groups[name]
        lb = [math.log(float(r["before"]) / float(r["value"])) for r in g]
        la = [math.log(float(r["after"]) / float(r["value"])) for r in g]
        if name.startswith("held"):
            held_before += lb
            held_after += la
        print(f"| {name} | {len(g)} | {rms(lb):.3f} | {rms(la):.3f} | "
              f"{rms([float(r['residual_before']) for r in g]):.1f} | {rms([float(r['residual_after']) for r in g]):.1f} |")
    b, a = rms(held_before), rms(held_after)
    print(f"| **all held out** | {len(held_before)} | {b:.3f} | {a:.3f} | | |")
    print(f"\nHeld-out RMS ln(J_2D/J_3D): {b:.3f} before, {a:.3f} after: "
          f"{100 * (1 - a / b):.0f} % smaller.\n")
    print("| size | W/d | shape | D (mm) | held out | J_3D (1/s) | J_2D/J_3D before | after |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        v = float(r["value"])
        print(f"| {r['size']} | {float(r['W_over_d']):.2f} | {r['shape']} | {r['D_mm'] if r['shape'] != 'none' else ''} | "
              f"{'yes' if r['held_out'] == '1' else 'no'} | {v:.1f} | {float(r['before']) / v:.3f} | {float(r['after']) / v:.3f} |")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "results/calibration/case_a")
