#!/usr/bin/python3
"""Could the form check have seen a quadratic drag read as a linear one along the incline?

A drag force per mass k v^2 acts as a linear drag of size k v: the linear size it mimics follows the
spheres' speed. On the board every speed scales as sqrt(g sin(theta) L) (rolling without slip, the
geometry fixed: the only velocity scale), so along the incline the mimicked size follows
sqrt(sin theta). Where the packing at the outlet does not change with the incline, J_mid follows the
outlet speed: the null twins' J_mid at each gap, across the inclines, measures that scaling. The
spread the form check would have to see is (size at the steepest - size at the shallowest) / the
one fitted size, taken here as the mean over the inclines.

Given the check along the incline in CASE's summary (dof, rest dof, its Bonferroni share of alpha,
its detectable spread at power 0.8), its power at that spread follows from the noncentral F:
lambda grows as the spread squared, lambda* at the detectable spread.

    /usr/bin/python3 calibrate/quadratic_drag_visibility.py PASS REPLAY [CASE] [--alpha 0.05]

PASS: a blind pass's folder (twins/ with the null twins' data). REPLAY: a folder of its calibrations
made by a binary that reports detectable_spread (from 98daef1). CASE: outside-quadratic-16 unless
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
            by_gap.setdefault(p["W_over_d"], {})[p[INCLINE]] = p["value"]
        for gap, j in sorted(by_gap.items()):
            if len(j) < 2:
                continue
            lo, hi = min(j), max(j)
            out.append((twin.stem, gap, (j[hi] - j[lo]) / statistics.mean(j.values()), sorted(j)))
    return out


def sqrt_sin_spread(inclines):
    v = [math.sqrt(math.sin(math.radians(t))) for t in inclines]
    return (v[-1] - v[0]) / statistics.mean(v)


def power_at(spread, check, n_checks, alpha):
    """The check's power at `spread`, from its detectable spread at power 0.8."""
    d1, d2 = check["dof"], check["rest_dof"]
    level = alpha / n_checks
    critical = fisher_f.isf(level, d1, d2)
    with warnings.catch_warnings():  # scipy's ncf warns (harmlessly) near lambda 0
        warnings.simplefilter("ignore", RuntimeWarning)
        star = optimize.brentq(lambda lam: ncf.sf(critical, d1, d2, lam) - 0.8, 1e-3, 1e4)
    lam = star * (spread / check["detectable_spread"]) ** 2
    return ncf.sf(critical, d1, d2, lam), level


def main(argv):
    alpha = 0.05
    if "--alpha" in argv:
        i = argv.index("--alpha")
        alpha = float(argv[i + 1])
        del argv[i:i + 2]
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
    inclines = spreads[0][3]
    needed = statistics.median(values)
    print(f"median {needed:.3f} (range {min(values):.3f}-{max(values):.3f}; sqrt(sin theta) predicts "
          f"{sqrt_sin_spread(inclines):.3f})")
    summary = json.loads(Path(replay, case, "summary.json").read_text())
    checks = summary.get("form_checks", [])
    along = [c for c in checks if c["column"] == INCLINE]
    if not along or "detectable_spread" not in along[0] or along[0]["detectable_spread"] is None:
        print(f"error: {case} has no check along {INCLINE} with a detectable spread in {replay}", file=sys.stderr)
        sys.exit(2)
    for c in along:
        power, level = power_at(needed, c, len(checks), alpha)
        ratio = (c["detectable_spread"] / needed) ** 2
        print(f"{case}: {c['effect']} along {INCLINE}: detectable spread {c['detectable_spread']:.3f} "
              f"(power 0.8 at level {level:.4g}, F on {c['dof']} and {c['rest_dof']} dof); adjusted p "
              f"{c['p_adjusted']:.3g}; power at the spread a quadratic drag asks for ({needed:.3f}): {power:.2f}; "
              f"power 0.8 there needs {ratio:.1f} x the information (the whitened noise variance / {ratio:.1f})")


if __name__ == "__main__":
    main(sys.argv[1:])
