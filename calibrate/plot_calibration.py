#!/usr/bin/env python3
"""Figures of one calibration (gapflow calibrate): reads points.csv and summary.json
in the folder given, writes data_vs_model.png, residuals.png, candidate_scores.png."""
import csv
import json
import math
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def number(s):
    try:
        return float(s)
    except ValueError:
        return None


def main(folder):
    folder = Path(folder)
    rows = list(csv.DictReader(open(folder / "points.csv")))
    summary = json.load(open(folder / "summary.json"))
    fixed = {"observable", "held_out", "value", "se", "before", "before_se", "after", "after_se", "residual_before",
             "residual_after", "before_fresh", "before_fresh_se", "after_fresh", "after_fresh_se"}
    design = [c for c in rows[0].keys() if c not in fixed]
    numeric = [c for c in design if all(number(r[c]) is not None for r in rows)]
    labels = [c for c in design if c not in numeric]
    # One row of panels per observable (a data file may measure several on the same runs).
    observables = list(dict.fromkeys(r.get("observable", summary["observable"]) for r in rows))

    # Data and model before/after against each numeric design column; other columns split the series.
    ncol = max(1, len(numeric))
    fig, axes = plt.subplots(len(observables), ncol, figsize=(5.5 * ncol, 4.2 * len(observables)), squeeze=False)
    for oi, observable in enumerate(observables):
        obs_rows = [r for r in rows if r.get("observable", observable) == observable]
        for ax, col in zip(axes[oi], numeric or design[:1]):
            groups = {}
            for r in obs_rows:
                key = tuple(r[c] for c in labels) + tuple(r[c] for c in numeric if c != col)
                groups.setdefault(key, []).append(r)
            for gi, (key, rs) in enumerate(sorted(groups.items())):
                rs = sorted(rs, key=lambda r: number(r[col]) or 0)
                x = [number(r[col]) for r in rs]
                tag = ", ".join(f"{c}={v}" for c, v in zip(labels + [c for c in numeric if c != col], key))
                colour = f"C{gi % 10}"
                for r, xi in zip(rs, x):
                    ax.errorbar(xi, float(r["value"]), yerr=1.96 * float(r["se"]),
                                fmt="o" if r["held_out"] == "0" else "s",
                                mfc=colour if r["held_out"] == "0" else "white", color=colour, capsize=2)
                for which, style in (("before", ":"), ("after", "-")):
                    pts = [(xi, number(r[which])) for r, xi in zip(rs, x) if number(r[which]) is not None]
                    if pts:
                        ax.plot(*zip(*pts), style, color=colour, label=f"{which}: {tag}" if tag else which)
            ax.set_xlabel(col)
            ax.set_ylabel(observable)
            ax.grid(alpha=0.3)
    axes[0][0].legend(fontsize=6)
    fig.suptitle(f"{summary['data']}: data (95 % bars; open = held out) and {summary['model']} model before (dotted) / after (solid)",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(folder / "data_vs_model.png", dpi=110)
    plt.close(fig)

    # Whitened residuals per point.
    fig, ax = plt.subplots(figsize=(7, 3.8))
    idx = range(len(rows))
    ax.axhspan(-1.96, 1.96, color="0.9")
    ax.plot(idx, [float(r["residual_before"]) for r in rows], "o", mfc="white", label="before")
    ax.plot(idx, [float(r["residual_after"]) for r in rows], "o", label="after")
    ax.set_xticks(list(idx))
    ax.set_xticklabels([("*" if r["held_out"] == "1" else "") + "/".join([r[c] for c in design] +
                                                                      ([r["observable"]] if len(observables) > 1 else []))
                        for r in rows],
                       rotation=60, fontsize=6)
    ax.set_ylabel("(data - model) / total se")
    ax.set_title("residuals (* = held out; band: +-1.96)", fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(folder / "residuals.png", dpi=110)
    plt.close(fig)

    # Candidate scores of the first round.
    rounds = summary.get("rounds", [])
    if rounds:
        cands = rounds[0]["candidates"]
        fig, ax = plt.subplots(figsize=(7, 3.8))
        names = [c["effect"] for c in cands]
        scores = [c["score"] if c["visible"] and c["score"] is not None else 0 for c in cands]
        colours = ["C3" if c["effect"] == rounds[0]["best"] else ("C0" if c["visible"] else "0.7") for c in cands]
        ax.bar(names, scores, color=colours)
        n_visible = max(1, sum(1 for c in cands if c["visible"]))
        # chi^2_1 threshold at alpha = 0.05 / n (Bonferroni): z^2 with z from the normal quantile.
        from statistics import NormalDist
        z = NormalDist().inv_cdf(1 - 0.025 / n_visible)
        ax.axhline(z * z, color="k", ls="--", lw=0.8, label=f"5 % after Bonferroni over {n_visible}")
        ax.set_ylabel("score statistic (chi^2_1)")
        ax.set_title("round 1 candidates (grey: not visible at their step; red: best)", fontsize=9)
        ax.tick_params(axis="x", rotation=45, labelsize=7)
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(folder / "candidate_scores.png", dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    main(sys.argv[1])
