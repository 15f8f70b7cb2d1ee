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
Reads only the store; writes to stdout. Debian's /usr/bin/python3 with python3-scipy, python3-numpy.
"""
import argparse
import json
import math
import sqlite3
import statistics
import sys

import numpy
import scipy.stats


def t975(df):
    return float(scipy.stats.t.ppf(0.975, df)) if df > 0 else float("inf")


def mean_var(xs):
    """Mean and variance of the mean."""
    return statistics.fmean(xs), statistics.variance(xs) / len(xs)


def ratio(a, b):
    """mean(a)/mean(b), its standard error (delta method) and Welch degrees of freedom."""
    ma, va = mean_var(a)
    mb, vb = mean_var(b)
    r = ma / mb
    ea, eb = va / mb**2, r**2 * vb / mb**2  # the two terms of se^2
    df = (ea + eb) ** 2 / (ea**2 / (len(a) - 1) + eb**2 / (len(b) - 1))
    return r, math.sqrt(ea + eb), df


def verdict(diff, half, tol):
    if abs(diff) + half <= tol:
        return "converged"
    if abs(diff) - half > tol:
        return "diverged"
    return "within" if abs(diff) <= tol else "outside"


def load(store, model):
    con = sqlite3.connect(f"file:{store}?mode=ro", uri=True)
    rows = con.execute("SELECT series, axes_json, j_paper FROM runs WHERE model = ?", (model,)).fetchall()
    data = {}
    for series, axes, jp in rows:
        dt = json.loads(axes)["model.bullet.time_step_s" if model == "3d" else "model.box2d.time_step_s"]
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
            dse = (r / ref_r) * math.sqrt((se / r) ** 2 + (ref_se / ref_r) ** 2)
            ddf = (se**2 + ref_se**2) ** 2 / (se**4 / df + ref_se**4 / ref_df)
            h = t975(ddf) * dse
            rel, v = f"{100 * d:+.2f} ± {100 * h:.2f} %", verdict(d, h, a.tolerance)
            jd, jse, jdf = ratio(b["j"], b0)
            jh = t975(jdf) * jse
            jrel, jv = f"{100 * (jd - 1):+.2f} ± {100 * jh:.2f} %", verdict(jd - 1, jh, a.tolerance)
        print(f"| {dt * 1000:g} ms | {c['n']} ({len(c['j'])}) / {b['n']} ({len(b['j'])}) "
              f"| {mb:.2f} ± {t975(len(b['j']) - 1) * math.sqrt(vb):.2f} "
              f"| {mc:.2f} ± {t975(len(c['j']) - 1) * math.sqrt(vc):.2f} "
              f"| {r:.4f} ± {t975(df) * se:.4f} | {rel} | {v} | {jrel} | {jv} |")
    # First-order fit R(dt) = R0 + R0 b dt, weighted least squares on the step means.
    X = numpy.column_stack([numpy.ones(len(xs)), xs])
    W = numpy.diag(ws)
    cov = numpy.linalg.inv(X.T @ W @ X)
    coef = cov @ X.T @ W @ numpy.array(ys)
    resid = numpy.array(ys) - X @ coef
    chi2 = float(resid @ W @ resid)
    dof = len(xs) - 2
    if dof > 0 and chi2 / dof > 1:
        cov = cov * chi2 / dof
    q = t975(dof) if dof > 0 else float("inf")
    r0, slope = coef
    b = slope / r0
    b_se = math.sqrt(cov[1, 1]) / r0
    print()
    print(f"First-order fit over {len(xs)} steps (weighted least squares; covariance widened by chi2/dof when > 1, "
          f"Student-t with {dof} dof): R(0) = {r0:.4f} ± {q * math.sqrt(cov[0, 0]):.4f}, step error "
          f"{100 * b:+.2f} ± {100 * q * b_se:.2f} % per ms (chi2/dof = {chi2:.1f}/{dof}).")


if __name__ == "__main__":
    main()
