#!/usr/bin/python3
"""Where the fresh seeds' chi^2 exceeds the response surface's, point by point (a diagnostic; it decides
nothing). Reads each calibration's points.csv, whose fresh columns (before_fresh, after_fresh and their se:
direct simulation on fresh seeds at the state's parameters) binaries from a2dddfa on write.

    /usr/bin/python3 calibrate/fresh_points.py [--cases "CASE..."] FOLDER [FOLDER...]

FOLDER: a blind pass or a replay of one (its <case>/points.csv and summary.json); --cases: only these
calibrations of each (a control replayed on some of a pass's twins, compared with the pass on the same). On the fit scale (log for
every observable but exit_offset, clog_share and ln_s_plus_1: calibrate/data_file.cpp default_scale; a data
file that sets another scale is not read here), with y the data, s the surface's prediction, f the fresh
runs', e, se_s, se_f their standard errors, v_s = e^2 + se_s^2, v_f = e^2 + se_f^2 and d = f - s, each point's
chi^2 gap splits exactly as

    (y - f)^2 / v_f - (y - s)^2 / v_s = (y - s)^2 (1/v_f - 1/v_s)      the stated variances differ
                                       + d^2 / v_f                      surface and fresh runs disagree
                                       - 2 d (y - s) / v_f              cross term

Where the surface is exact and the data, the surface and the fresh runs have independent errors of the stated
sizes, the parts average v_s / v_f - 1, (se_s^2 + se_f^2) / v_f and -2 se_s^2 / v_f (the surface's own error is
in both d and y - s), which sum to 0; each is given in brackets, "expected", from the stated se of each point
(the fresh se is estimated from the model's replicates, which raises the observed disagreement above its
expectation a little: about +0.04 to +0.17 per point as se_f^2 / e^2 goes from 0.5 to 2 at 6 replicates; the
other two parts' expectations are exact given it). Where the
model misfits (a baseline without its missing effect) the residual y - s is not noise and the parts are not
so expected. Read against the expectation: a fit that found where the surface's own errors meet the data
(optimism: s pulled toward y on the fitted points) raises the cross term above its expectation there and
not on the held-out points; a surface whose errors exceed its stated se raises the disagreement on both.
Per state (baseline, final) and side (fitted, held-out): points, the gap and each part per point (means over
every point of every calibration), the disagreement's and cross term's excess over their expectations as a mean over the
calibrations with its standard error, and the median ratio of the surface's stated se to the fresh runs' (a
quadratic through several nodes' runs predicts more tightly than the same number of runs at one point, so a
ratio near 1 says the stated se holds more than the quadratic's own: the effects' terms, a lack-of-fit
widening); then the final state apart for the calibrations that added an effect (their surface carries the
effects' terms) and those that added none (the baseline's quadratic alone); then per observable. A check line: the fitted points' chi^2 rebuilt here,
plus the measured free parameters' term, against summary.json's (largest difference over the calibrations;
surface and fresh).
"""
import csv
import json
import math
import os
import statistics
import sys
from collections import defaultdict

from blind_pass import calibrations, require_cases, take_cases

LINEAR = {"exit_offset", "clog_share", "ln_s_plus_1"}   # calibrate/data_file.cpp default_scale


def on_fit_scale(observable, value, se):
    """(value, se) on the fit scale of the observable."""
    if observable in LINEAR:
        return value, se
    return math.log(value), se / value


def number(text):
    return float(text) if text not in ("", None) else None


def point_parts(row, state):
    """The point's chi^2 gap, its three parts and each part's expectation, the ratio of the surface's se to the
    fresh runs', and both chi^2 terms (for the check), or None where the surface or the fresh runs gave no value
    (or the file has no fresh columns)."""
    s, se_s = number(row.get(state)), number(row.get(state + "_se"))
    f, se_f = number(row.get(state + "_fresh")), number(row.get(state + "_fresh_se"))
    if None in (s, se_s, f, se_f):
        return None
    obs = row["observable"]
    y, e = on_fit_scale(obs, float(row["value"]), float(row["se"]))
    s, se_s = on_fit_scale(obs, s, se_s)
    f, se_f = on_fit_scale(obs, f, se_f)
    v_s, v_f, d = e * e + se_s * se_s, e * e + se_f * se_f, f - s
    parts = {"variances": (y - s) ** 2 * (1 / v_f - 1 / v_s), "disagreement": d * d / v_f,
             "cross": -2 * d * (y - s) / v_f, "expected variances": v_s / v_f - 1,
             "expected disagreement": (se_s ** 2 + se_f ** 2) / v_f, "expected cross": -2 * se_s ** 2 / v_f}
    parts["gap"] = parts["variances"] + parts["disagreement"] + parts["cross"]
    parts["se_ratio"] = se_s / se_f if se_f > 0 else math.nan
    parts["surface_chi2"], parts["fresh_chi2"] = (y - s) ** 2 / v_s, (y - f) ** 2 / v_f
    return parts


def measured_term(summary, state):
    """The measured free parameters' chi^2 at the state's parameters (part of the fitted points' chi^2)."""
    params = summary.get(state, {}).get("params", {})
    return sum(((params[m["key"]] - m["measured"]) / m["se"]) ** 2
               for m in summary.get("measured_free", []) if m["key"] in params and m.get("se"))


def collect(folder, cases=None):
    """{(state, side): [parts...]}, {(state, observable): [parts...]} over the fitted and held-out points of
    every calibration with fresh columns, the calibrations read, and the check's largest differences."""
    by_side, by_observable = defaultdict(list), defaultdict(list)
    read, worst = 0, {"surface": 0.0, "fresh": 0.0}
    for case, summary_path in calibrations(folder, cases=cases):
        points_path = os.path.join(os.path.dirname(summary_path), "points.csv")
        if not os.path.exists(points_path):
            continue
        with open(points_path, newline="") as f:
            rows = list(csv.DictReader(f))
        if not rows or "after_fresh" not in rows[0]:
            continue
        with open(summary_path) as f:
            summary = json.load(f)
        read += 1
        for state in ("before", "after"):
            fitted = {"surface": measured_term(summary, state), "fresh": measured_term(summary, state)}
            complete = True
            for row in rows:
                parts = point_parts(row, state)
                if parts is None:
                    complete = False
                    continue
                side = "held-out" if row["held_out"] == "1" else "fitted"
                parts["case"], parts["added"] = case, bool(summary.get("effects"))
                by_side[(state, side)].append(parts)
                by_observable[(state, row["observable"])].append(parts)
                if side == "fitted":
                    fitted["surface"] += parts["surface_chi2"]
                    fitted["fresh"] += parts["fresh_chi2"]
            if complete:
                recorded = {"surface": summary[state]["fitted"]["chi2"], "fresh": summary[state]["fitted_fresh"]["chi2"]}
                for k in worst:
                    worst[k] = max(worst[k], abs(fitted[k] - recorded[k]))
    return by_side, by_observable, read, worst


def mean(parts, key):
    return sum(p[key] for p in parts) / len(parts)


def report(folder, cases=None):
    by_side, by_observable, read, worst = collect(folder, cases)
    only = f" (of the {len(cases)} cases asked)" if cases is not None else ""
    print(f"{folder}: {read} calibrations with fresh values per point{only}")
    if not read:
        return
    print(f"  check: fitted chi^2 rebuilt here (with the measured parameters' term) against summary.json, largest "
          f"difference: surface {worst['surface']:.3f}, fresh {worst['fresh']:.3f}")
    print("| state | points | n | gap per point | variances (expected) | disagreement (expected) | cross (expected) | "
          "disagreement excess, per calibration | cross excess, per calibration | se_s / se_f, median |")
    print("| :-- | :-- | --: | --: | --: | --: | --: | --: | --: | --: |")
    for state, label in (("before", "baseline"), ("after", "final")):
        for side in ("fitted", "held-out"):
            parts = by_side.get((state, side), [])
            if parts:
                print(f"| {label} | {side} | {len(parts)} | {row_cells(parts)} |")
    print("| final state | points | calibrations | n | gap per point | variances (expected) | disagreement (expected) | "
          "cross (expected) | disagreement excess, per calibration | cross excess, per calibration | se_s / se_f, median |")
    print("| :-- | :-- | :-- | --: | --: | --: | --: | --: | --: | --: | --: |")
    for side in ("fitted", "held-out"):
        for added, label in ((True, "an effect added"), (False, "none added")):
            parts = [p for p in by_side.get(("after", side), []) if p["added"] == added]
            if parts:
                print(f"| final | {side} | {label} | {len(parts)} | {row_cells(parts)} |")
    print("| state | observable | n | gap per point | variances (expected) | disagreement (expected) | cross (expected) | "
          "disagreement excess, per calibration | cross excess, per calibration | se_s / se_f, median |")
    print("| :-- | :-- | --: | --: | --: | --: | --: | --: | --: | --: |")
    for state, label in (("before", "baseline"), ("after", "final")):
        for (at, observable), parts in sorted(by_observable.items()):
            if at == state:
                print(f"| {label} | {observable} | {len(parts)} | {row_cells(parts)} |")


def row_cells(parts):
    """The gap and each part with its expectation, per point; then the disagreement's and the cross term's
    excess over their expectations with its standard error over the calibrations (a calibration's points
    share its fit and surface, so they are not independent: each calibration's mean excess is one value)."""
    cells = [f"{mean(parts, 'gap'):+.3f}"]
    for part in ("variances", "disagreement", "cross"):
        cells.append(f"{mean(parts, part):+.3f} ({mean(parts, 'expected ' + part):+.3f})")
    for part in ("disagreement", "cross"):
        cells.append(excess_text(parts, part))
    ratios = [p["se_ratio"] for p in parts if not math.isnan(p["se_ratio"])]
    cells.append(f"{statistics.median(ratios):.3f}" if ratios else "-")
    return " | ".join(cells)


def excess_text(parts, part):
    """The mean over calibrations of each one's mean excess of `part` over its expectation, +- its standard
    error (none with fewer than two calibrations)."""
    by_case = defaultdict(list)
    for p in parts:
        by_case[p["case"]].append(p[part] - p["expected " + part])
    means = [sum(v) / len(v) for v in by_case.values()]
    centre = sum(means) / len(means)
    if len(means) < 2:
        return f"{centre:+.3f}"
    se = math.sqrt(sum((m - centre) ** 2 for m in means) / (len(means) - 1) / len(means))
    return f"{centre:+.3f} ± {se:.3f}"


def main(args):
    cases = take_cases(args)
    folders = args
    if not folders:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        sys.exit(2)
    for folder in folders:
        if not os.path.isdir(folder):
            print(f"error: no folder {folder}", file=sys.stderr)
            sys.exit(2)
    for folder in folders:
        require_cases(folder, cases)
    for folder in folders:
        report(folder, cases)


if __name__ == "__main__":
    main(sys.argv[1:])
