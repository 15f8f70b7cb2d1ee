#!/usr/bin/env python3
"""Where across the gap the spheres leave: the steady outflow per lateral band of the gap.

Reads a study store that still has its crossing rows (the working store of a screen, not the
slim copy: scripts/slim_store.py drops them). For each point named, over the runs of one model
and replicate range: the crossings of the middle half of each run (the steady discharge, the
first and last quarters of its crossings left out), counted by where the sphere's centre crossed
the gap line, in `bands` equal bands of the range a centre can reach, |x| <= (W - d)/2 (a
centre stays d/2 from the tips), and divided by the time that middle half took.
Spheres per second per band: mean over runs ± its standard error (runs are independent replicates).

  scripts/gap_profile.py STORE --model 2d --w-over-d 6 --replicates 12 21 \\
      --point "none=none:" --point "A 4d D7=A:side_mm=31.0, obstruction.distance_mm=54.25"

A point is LABEL=SERIES:TEXT, TEXT a substring of the run's point label ("" matches any).
"""
import argparse
import sqlite3
import sys


def steady_band_flux(db, job_key, reach_m, bands):
    rows = db.execute("select x_m, t_s from crossings where job_key = ? order by t_s", (job_key,)).fetchall()
    if len(rows) < 8:
        return None
    lo, hi = len(rows) // 4, 3 * len(rows) // 4
    duration = rows[hi][1] - rows[lo][1]
    if duration <= 0:
        return None
    counts = [0] * bands
    for x, _ in rows[lo:hi]:
        b = int((x / reach_m + 0.5) * bands)
        counts[min(bands - 1, max(0, b))] += 1
    return [c / duration for c in counts]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("store")
    ap.add_argument("--model", required=True)
    ap.add_argument("--w-over-d", type=float, required=True)
    ap.add_argument("--replicates", type=int, nargs=2, required=True, metavar=("FIRST", "LAST"))
    ap.add_argument("--bands", type=int, default=5)
    ap.add_argument("--point", action="append", required=True, help="LABEL=SERIES:TEXT")
    a = ap.parse_args()
    if a.bands < 1:
        print("error: --bands must be >= 1", file=sys.stderr)
        sys.exit(2)
    try:
        db = sqlite3.connect(f"file:{a.store}?mode=ro", uri=True)
        has_crossings = db.execute("select exists(select 1 from crossings)").fetchone()[0]
    except sqlite3.Error as e:
        print(f"error: {a.store}: not a study store ({e})", file=sys.stderr)
        sys.exit(2)
    if not has_crossings:
        print(f"error: {a.store} has no crossing rows (a slim store?): use the working store", file=sys.stderr)
        sys.exit(2)
    for spec in a.point:
        if "=" not in spec or ":" not in spec.split("=", 1)[1]:
            print(f"error: --point {spec!r}: expected LABEL=SERIES:TEXT", file=sys.stderr)
            sys.exit(2)
    print(f"steady outflow by band of the gap, spheres/s ({a.bands} equal bands of the reach of a sphere's centre, "
          f"|x| <= (W - d)/2), "
          f"model {a.model}, W/d {a.w_over_d:g}, replicates {a.replicates[0]}-{a.replicates[1]}, mean over runs ± se")
    print("| point | runs | " + " | ".join(f"band {i + 1}" for i in range(a.bands)) + " | total |")
    print("|---|---|" + "---|" * (a.bands + 1))
    for spec in a.point:
        label, rest = spec.split("=", 1)
        series, text = rest.split(":", 1)
        runs = db.execute(
            "select job_key, gap_m - diameter_m from runs where model = ? and series = ? and abs(w_over_d - ?) < 0.01 "
            "and replicate between ? and ? and instr(point_label, ?) > 0",
            (a.model, series, a.w_over_d, a.replicates[0], a.replicates[1], text)).fetchall()
        if not runs:
            print(f"error: --point {spec!r} matches no run of model {a.model} at W/d {a.w_over_d:g}", file=sys.stderr)
            sys.exit(2)
        fluxes = [f for f in (steady_band_flux(db, k, g, a.bands) for k, g in runs) if f is not None]
        if len(fluxes) < len(runs):
            print(f"note: {label}: {len(runs) - len(fluxes)} run(s) with fewer than 8 crossings left out", file=sys.stderr)
        if not fluxes:
            print(f"| {label} | 0 | " + " | ".join("" for _ in range(a.bands)) + " | |")
            continue
        n = len(fluxes)
        mean = [sum(f[b] for f in fluxes) / n for b in range(a.bands)]
        # standard error of each band's mean over runs (runs are independent replicates)
        se = [(sum((f[b] - mean[b]) ** 2 for f in fluxes) / (n - 1) / n) ** 0.5 if n > 1 else float("nan")
              for b in range(a.bands)]
        totals = [sum(f) for f in fluxes]
        total_se = (sum((t - sum(mean)) ** 2 for t in totals) / (n - 1) / n) ** 0.5 if n > 1 else float("nan")
        print(f"| {label} | {n} | " + " | ".join(f"{m:.1f} ± {e:.1f}" for m, e in zip(mean, se))
              + f" | {sum(mean):.1f} ± {total_se:.1f} |")


if __name__ == "__main__":
    main()
