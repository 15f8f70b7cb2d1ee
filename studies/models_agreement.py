#!/usr/bin/python3
"""One table row per report: the "2D against 3D" summary (points, mean ratio, Pearson,
Spearman) read from each report.md given as LABEL=PATH.

    studies/models_agreement.py "J_paper, without=results/flow-vs-distance/report.md" ...
"""
import re
import sys

PATTERN = re.compile(r"Over the (\d+) points with (\S+) defined in both models: mean ratio ([-\d.e]+), "
                     r"Pearson correlation of the mean J ([-\d.e]+), Spearman rank correlation \(ranking agreement\) (-?\d+(?:\.\d+)?(?:e-?\d+)?)")


def main(args):
    print("| comparison | report | points | J_2D/J_3D, mean over points | Spearman (ranking) | Pearson |")
    print("|---|---|---|---|---|---|")
    for arg in args:
        label, path = arg.split("=", 1)
        m = PATTERN.search(open(path).read())
        if not m:
            sys.exit(f"{path}: no '2D against 3D' summary")
        n, j, ratio, pearson, spearman = m.groups()
        print(f"| {label} | `{path}` | {n} | {float(ratio):.3f} | {float(spearman):.3f} | {float(pearson):.3f} |")


if __name__ == "__main__":
    main(sys.argv[1:])
