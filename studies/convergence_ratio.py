#!/usr/bin/python3
"""Convergence of a ratio J/J_0 against the time step, from a study store with two series.

Usage: studies/convergence_ratio.py STORE.sqlite --reference STEP_S [--model 3d] [--tolerance 0.01]
                                    [--cell cylinder] [--base none]

For every time step: J_paper of the cell series and of the baseline series (mean, 95 % Student-t
interval), R = J/J_0 with its delta-method 95 % interval (Welch degrees of freedom; the two arms
are independent runs), R against R at the reference step with a 95 % interval (independent
settings), and the verdict against the tolerance as in convergence_table.py. Below the table: the
absolute J_0 against its reference, for comparison (how much of the step error the ratio cancels),
and a first-order fit R(dt) = R(0) (1 + b dt) over all steps.

Runs that did not empty have no J_paper; their count is printed, never silently dropped.
Reads only the store; writes to stdout. Debian's /usr/bin/python3 with python3-scipy (t quantile).
"""
import argparse
import math
import pathlib
import sqlite3
import statistics
import sys

from convergence_table import t975, verdict, weighted_line  # as in the step tables


def mean_var(xs):
    """Mean and variance of the mean."""
    return statistics.fmean(xs), statistics.variance(xs) / len(xs)


def ratio(a, b):
    """mean(a)/mean(b), its standard error (delta method) and Welch degrees of freedom."""
    ma, va = mean_var(a)
    mb, vb = mean_var(b)
    r = ma / mb
    ea, eb = va / mb**2, r**2 * vb / mb**2  # the two terms of se^2
    den = ea**2 / (len(a) - 1) + eb**2 / (len(b) - 1)
    df = (ea + eb) ** 2 / den if den > 0 else float("inf")
    return r, math.sqrt(ea + eb), df


def load(store, model):
    """{(series, time step in s): {"j": [J_paper of runs that emptied], "n": runs}}."""
    path = pathlib.Path(store).resolve()
    if not path.is_file():
        sys.exit(f"{store}: no such store")
    try:
        con = sqlite3.connect(f"{path.as_uri()}?mode=ro", uri=True)
        rows = con.execute("SELECT series, time_step_s, j_paper FROM runs WHERE model = ?", (model,)).fetchall()
    except sqlite3.Error as e:
        sys.exit(f"{store}: not a gapflow store ({e})")
    data = {}
    for series, dt, jp in rows:
        d = data.setdefault((series, dt), {"j": [], "n": 0})
        d["n"] += 1
        if jp is not None:
            d["j"].append(jp)
    return data


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store")
    ap.add_argument("--reference", type=float, required=True, help="reference time step, s")
    ap.add_argument("--model", default="3d")
    ap.add_argument("--tolerance", type=float, default=0.01)
    ap.add_argument("--cell", default="cylinder")
    ap.add_argument("--base", default="none")
    a = ap.parse_args()
    data = load(a.store, a.model)
    steps = sorted({dt for (_, dt) in data})
    for dt in steps:
        for s in (a.cell, a.base):
            if (s, dt) not in data or len(data[(s, dt)]["j"]) < 2:
                sys.exit(f"{a.store}: series '{s}' at step {dt} s has fewer than 2 runs with J_paper")
    if a.reference not in steps:
        sys.exit(f"{a.store}: no runs at the reference step {a.reference} s (steps: {steps})")
    ref_r, ref_se, ref_df = ratio(data[(a.cell, a.reference)]["j"], data[(a.base, a.reference)]["j"])
    b0 = data[(a.base, a.reference)]["j"]
    print(f"Reference: {a.reference * 1000:g} ms; tolerance +-{a.tolerance * 100:g} %; J in particles/s, 95 % intervals.")
    print()
    print(f"| step | runs (with J) {a.cell} / {a.base} | J_0 /s | J /s | J/J_0 | J/J_0 vs reference | verdict | J_0 vs reference | verdict |")
    print("|---|---|---|---|---|---|---|---|---|")
    xs, ys, ws = [], [], []
    for dt in steps:
        c, b = data[(a.cell, dt)], data[(a.base, dt)]
        r, se, df = ratio(c["j"], b["j"])
        mc, vc = mean_var(c["j"])
        mb, vb = mean_var(b["j"])
        xs.append(dt * 1000), ys.append(r), ws.append(1 / se**2)
        if dt == a.reference:
            rel, jrel = "reference", "reference"
            v, jv = "-", "-"
        else:
            d = r / ref_r - 1  # independent settings: relative errors add in quadrature
            rv, rv_ref = (se / r) ** 2, (ref_se / ref_r) ** 2
            dse = (r / ref_r) * math.sqrt(rv + rv_ref)
            ddf = (rv + rv_ref) ** 2 / (rv**2 / df + rv_ref**2 / ref_df)
            h = t975(ddf) * dse
            rel, v = f"{100 * d:+.2f} ± {100 * h:.2f} %", verdict(d, h, a.tolerance)
            jd, jse, jdf = ratio(b["j"], b0)
            jh = t975(jdf) * jse
            jrel, jv = f"{100 * (jd - 1):+.2f} ± {100 * jh:.2f} %", verdict(jd - 1, jh, a.tolerance)
        print(f"| {dt * 1000:g} ms | {c['n']} ({len(c['j'])}) / {b['n']} ({len(b['j'])}) "
              f"| {mb:.2f} ± {t975(len(b['j']) - 1) * math.sqrt(vb):.2f} "
              f"| {mc:.2f} ± {t975(len(c['j']) - 1) * math.sqrt(vc):.2f} "
              f"| {r:.4f} ± {t975(df) * se:.4f} | {rel} | {v} | {jrel} | {jv} |")
    # First-order fit R(dt) = R(0) (1 + b dt), weighted least squares on the step means.
    if len(xs) < 3:
        print("\nFirst-order fit: fewer than 3 steps.")
        return
    r0, r0h, b, bh, chi2, dof = weighted_line(xs, ys, ws)
    print()
    print(f"First-order fit over {len(xs)} steps (weighted least squares, 95 % intervals; covariance widened by "
          f"chi2/dof when > 1, then Student-t with {dof} dof): R(0) = {r0:.4f} ± {r0h:.4f}, step error "
          f"{100 * b:+.2f} ± {100 * bh:.2f} % per ms (chi2/dof = {chi2:.1f}/{dof}).")

if __name__ == "__main__":
    main()
