#!/usr/bin/python3
"""Could the form check have seen a quadratic drag read as a linear one along the incline?

A drag force per mass k v^2 acts as a linear drag of size k v: the linear size it mimics follows the
spheres' speed. To first order every speed on the board scales as sqrt(g sin(theta) L): rolling
without slip from rest in a fixed geometry, with the friction and rolling resistance that oppose it
(about mu cos(theta), small beside sin(theta) on these inclines) left out. Along the incline the
mimicked size then follows sqrt(sin theta). The null twins' J_mid at each gap, across the inclines,
tests that scaling where it is easiest to measure, at the outlet (at a fixed packing J follows the
outlet speed; an outlet-controlled discharge scales so too, so this tests the outlet, not the path
upstream where the drag also acts).

The spread the form check would have to see is (size at the steepest - size at the shallowest) / the
one fitted size. The fitted size is a weighted mean of the levels' sizes (weighted toward the levels
where the drag's sensitivity is largest), so the spread is given against the mean over the
inclines, and against the sizes at the shallowest and the steepest as bounds.

Given the check along the incline in CASE's summary (dof, rest dof, the level its spread was computed
at, its detectable spread at power 0.8 at the stated noise), its power at a spread follows from the
noncentral F: lambda grows as the spread squared, lambda* at the detectable spread. It is given at
the stated noise and at the rest of the residual's own scale (lambda / scale).

    /usr/bin/python3 calibrate/quadratic_drag_visibility.py PASS REPLAY [CASE]

PASS: a blind pass's folder (twins/ with the null twins' data). REPLAY: a folder of its calibrations
made by a binary that reports detectable_spread and spread_level. CASE: outside-quadratic-16 unless
named.
"""
import json
import math
import statistics
import sys
import tomllib
import warnings
from pathlib import Path

from scipy import optimize
from scipy.stats import f as fisher_f
from scipy.stats import ncf

INCLINE = "incline_deg"
LINEAR_DRAG = "linear_drag"


def incline_spreads(pass_dir):
    """Per null twin and gap: (J_mid at the steepest incline - at the shallowest) / mean over the
    inclines, on the points without an obstruction."""
    out = []
    for twin in sorted(Path(pass_dir, "twins").glob("null-*.toml")):
        data = tomllib.loads(twin.read_text())
        default = data["observable"]["kind"]
        by_gap = {}
        for p in data["point"]:
            if p.get("shape", "none") != "none" or p.get("observable", default) != "j_mid":
                continue
            at = by_gap.setdefault(p["W_over_d"], {})
            if p[INCLINE] in at:
                print(f"error: {twin}: two j_mid points at W_over_d {p['W_over_d']}, {INCLINE} {p[INCLINE]}",
                      file=sys.stderr)
                sys.exit(2)
            at[p[INCLINE]] = p["value"]
        for gap, j in sorted(by_gap.items()):
            if len(j) < 2:
                continue
            lo, hi = min(j), max(j)
            out.append((twin.stem, gap, (j[hi] - j[lo]) / statistics.mean(j.values()), sorted(j)))
    return out


def sqrt_sin_spreads(inclines):
    """sqrt(sin theta)'s spread over the inclines against the mean, the shallowest and the steepest."""
    v = [math.sqrt(math.sin(math.radians(t))) for t in inclines]
    return [(v[-1] - v[0]) / ref for ref in (statistics.mean(v), v[0], v[-1])]


def power_at(spread, check, scale=1.0):
    """The check's power at `spread` (noise variance `scale` x the stated), from its detectable spread
    at power 0.8 at the stated noise."""
    d1, d2 = check["dof"], check["rest_dof"]
    critical = fisher_f.isf(check["spread_level"], d1, d2)
    with warnings.catch_warnings():  # scipy's ncf warns (harmlessly) near lambda 0
        warnings.simplefilter("ignore", RuntimeWarning)
        star = optimize.brentq(lambda lam: ncf.sf(critical, d1, d2, lam) - 0.8, 1e-3, 1e4)
    lam = star * (spread / check["detectable_spread"]) ** 2 / scale
    return ncf.sf(critical, d1, d2, lam)


def main(argv):
    if len(argv) not in (2, 3):
        sys.exit(__doc__)
    pass_dir, replay = argv[0], argv[1]
    case = argv[2] if len(argv) == 3 else "outside-quadratic-16"
    spreads = incline_spreads(pass_dir)
    if not spreads:
        print(f"error: no null twin with j_mid at two or more inclines in {pass_dir}/twins", file=sys.stderr)
        sys.exit(2)
    for name, gap, s, inclines in spreads:
        print(f"{name} W/d {gap:g}: J_mid spread across inclines {inclines} = {s:.3f}")
    values = [s for *_, s, _ in spreads]
    needed = statistics.median(values)
    mean_ref, low_ref, high_ref = sqrt_sin_spreads(spreads[0][3])
    print(f"median {needed:.3f} (range {min(values):.3f}-{max(values):.3f}; sqrt(sin theta) predicts "
          f"{mean_ref:.3f} against the mean, {high_ref:.3f} against the steepest, {low_ref:.3f} against the shallowest)")
    summary = json.loads(Path(replay, case, "summary.json").read_text())
    # Only a linear drag's check asks this question: another effect's size need not follow the speed.
    along = [c for c in summary.get("form_checks", []) if c["column"] == INCLINE and c["effect"] == LINEAR_DRAG]
    if not along or any(c.get("detectable_spread") is None or "spread_level" not in c for c in along):
        added = ", ".join(e["effect"] for e in summary.get("effects", [])) or "nothing"
        print(f"error: {case} in {replay} has no check of {LINEAR_DRAG} along {INCLINE} with a detectable spread "
              f"(added: {added}; verdict: {summary.get('verdict', '?')})", file=sys.stderr)
        sys.exit(2)
    for c in along:
        ratio = (c["detectable_spread"] / needed) ** 2
        bounds = ", ".join(f"{power_at(needed * ref / mean_ref, c):.2f}" for ref in (high_ref, low_ref))
        print(f"{case}: {c['effect']} along {INCLINE}: detectable spread {c['detectable_spread']:.3f} "
              f"(power 0.8 at level {c['spread_level']:.4g} at the stated noise, F on {c['dof']} and {c['rest_dof']} "
              f"dof); adjusted p {c['p_adjusted']:.3g}; power at the spread a quadratic drag asks for ({needed:.3f}): "
              f"{power_at(needed, c):.2f} at the stated noise ({bounds} against the steepest and the shallowest "
              f"incline's size), {power_at(needed, c, c['scale']):.2f} at the residual's own scale {c['scale']:.2f}; "
              f"power 0.8 there at the stated noise needs {ratio:.1f} x the information (the whitened noise variance "
              f"/ {ratio:.1f})")


if __name__ == "__main__":
    main(sys.argv[1:])
