#!/usr/bin/env python3
"""Draw the figures of a gapflow study report.

    python3 studies/plot_study.py PLOTS.json OUTDIR

PLOTS.json is written by `gapflow report` (studies/report_plots.cpp): it decides what
is drawn, this script only draws it (python3 + matplotlib, Agg backend, nothing else).

Per figure: "lines" (style "errorbar": markers with 95 % error bars, joined;
"markers": the same, not joined; "curve" and "curve_fixed": fitted curves, solid and
dotted; lines of one "group" share a colour), "bands" (a reference value as a
horizontal band mean +- CI) and optionally the identity line. 2D and 3D are told apart
by marker and line style (2D: circles, solid; 3D: squares, dashed). null = missing.
"""
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)

MARKER = {"2d": "o", "3d": "s"}
LINESTYLE = {"2d": "-", "3d": "--"}
BAND_COLOUR = {"2d": "tab:gray", "3d": "tab:brown", "": "tab:gray"}


def num(v):
    return float("nan") if v is None else float(v)


def nums(vs):
    return [num(v) for v in vs]


def error_bars(centre, lo, hi):
    """Asymmetric error bars [below, above]; zero where the interval is unknown.

    Clamped at 0: a mean of equal values can round a hair outside their range."""
    if not lo or not hi:
        return None
    below = [max(0.0, c - l) if math.isfinite(c - l) else 0.0 for c, l in zip(centre, lo)]
    above = [max(0.0, h - c) if math.isfinite(h - c) else 0.0 for c, h in zip(centre, hi)]
    return [below, above]


def colour_of(group, colours):
    """Lines of one group (a series and its fit) share a colour, in order of appearance."""
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    if group not in colours:
        colours[group] = cycle[len(colours) % len(cycle)]
    return colours[group]


def draw_line(ax, line, colours):
    x, y = nums(line["x"]), nums(line["y"])
    if not x:
        return
    model = line.get("model", "")
    style = line.get("style", "errorbar")
    colour = colour_of(line.get("group") or line["label"], colours)
    if style.startswith("curve"):
        ax.plot(x, y, color=colour, linestyle=":" if style == "curve_fixed" else "-", linewidth=1.2,
                label=line["label"])
        return
    joined = style == "errorbar" and len(x) > 1
    ax.errorbar(
        x,
        y,
        yerr=error_bars(y, nums(line.get("ylo", [])), nums(line.get("yhi", []))),
        xerr=error_bars(x, nums(line.get("xlo", [])), nums(line.get("xhi", []))),
        marker=MARKER.get(model, "o"),
        linestyle=LINESTYLE.get(model, "none") if joined else "none",
        color=colour,
        capsize=3,
        markersize=5,
        label=line["label"],
    )


def draw_band(ax, band):
    y, lo, hi = num(band["y"]), num(band["lo"]), num(band["hi"])
    colour = BAND_COLOUR.get(band.get("model", ""), "tab:gray")
    if math.isfinite(lo) and math.isfinite(hi) and hi > lo:
        ax.axhspan(lo, hi, color=colour, alpha=0.2, linewidth=0)
    if math.isfinite(y):
        ax.axhline(y, color=colour, linestyle="-.", linewidth=1, label=band["label"])


def draw_identity(ax):
    lo = min(ax.get_xlim()[0], ax.get_ylim()[0])
    hi = max(ax.get_xlim()[1], ax.get_ylim()[1])
    ax.plot([lo, hi], [lo, hi], color="black", linewidth=0.8, linestyle=":", label="identity")
    ax.set_xlim(lo, hi)
    ax.set_ylim(lo, hi)


def draw_figure(fig_spec, outdir):
    fig, ax = plt.subplots(figsize=(7, 4.5))
    colours = {}
    for line in fig_spec["lines"]:
        draw_line(ax, line, colours)
    for band in fig_spec["bands"]:
        draw_band(ax, band)
    if fig_spec.get("identity_line"):
        draw_identity(ax)
    ax.set_title(fig_spec["title"])
    ax.set_xlabel(fig_spec["xlabel"])
    ax.set_ylabel(fig_spec["ylabel"])
    ax.grid(True, alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    path = os.path.join(outdir, fig_spec["file"])
    tmp = path + ".partial.png"  # renamed when complete: never half a PNG
    fig.savefig(tmp, dpi=120)
    plt.close(fig)
    os.replace(tmp, path)
    print(path)


def main(argv):
    if len(argv) != 3:
        sys.stderr.write(__doc__)
        return 2
    with open(argv[1], encoding="utf-8") as f:
        spec = json.load(f)
    for fig_spec in spec["figures"]:
        draw_figure(fig_spec, argv[2])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
