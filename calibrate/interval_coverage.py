#!/usr/bin/python3
"""How often the recovered sizes' 95 % intervals hold the planted value, pooled over blind passes,
by the planted effect's key.

    /usr/bin/python3 calibrate/interval_coverage.py PASS_DIR [PASS_DIR...]

Every interval counts that a calibration gave for a key a twin planted (an effect added as itself;
a planted effect found only as a member of another's group has no interval of its own). Per key and
pooled: the intervals, how many hold the truth (with the exact 95 % interval of that rate), how
many of the others miss toward the effect's neutral value (the size read smaller than planted) and
how many away from it (calibrate/interval_sides.py lists them), the median miss in the interval's own standard errors, |z| = |truth - value| / (h / 1.96) with h the
interval's half on the truth's side (a Wald reading of an interval that may be asymmetric), and the
factor the intervals would need to be widened by to hold 95 % of the truths (the 95th percentile of
|z| over 1.96; only from 20 intervals on). Intervals whose half on the truth's side is zero (the
fitted size at a range end) count in the coverage, not in |z|. A second table sets the size read
(its departure from neutral over the planted one: 1 exact, below 1 toward neutral) against the free
parameter's fitted excess over its truth (the particle friction in the blind study), with their
Pearson correlation (from 5 sizes on): an effect that trades off against the free parameter is read
small where the free parameter is read high.

The passes' twins are not independent draws of everything: the cases repeat from pass to pass with
the same planted sizes, and up to pass 19 a pass's twins shared one draw of the model's noise. The
binomial interval treats them as independent and is too narrow by an unknown amount.
"""
import json
import os
import statistics
import sys

from blind_pass import calibrations
from visibility_ceiling import clopper_pearson

MIN_FOR_FACTOR = 20
MIN_FOR_CORRELATION = 5


def intervals(pass_dirs):
    """{key: [interval, ...]} over every interval of a planted key in the passes given. Each interval:
    side ("held", "toward" neutral or "away"), z (|miss| in the interval's se; None at a range end),
    share (the size's departure from neutral over the planted one: 1 exact, below 1 toward neutral) and
    free_excess (the free parameter fitted less its truth; None where the twin planted none)."""
    out = {}
    for pass_dir in pass_dirs:
        if not os.path.isdir(pass_dir):
            print(f"error: no folder {pass_dir}", file=sys.stderr)
            sys.exit(2)
        for case, summary in calibrations(pass_dir):
            truth_file = os.path.join(pass_dir, "truth", case + ".json")
            if not os.path.exists(truth_file):
                continue
            with open(truth_file) as f:
                planted = json.load(f)["planted"]
            with open(summary) as f:
                s = json.load(f)
            free = {p["key"]: p["value"] for p in planted if p["name"] == "free"}
            fitted = s.get("after", {}).get("params", {})
            excess = [fitted[k] - v for k, v in free.items() if k in fitted]
            effects = {p["key"]: (p["value"], p["neutral"]) for p in planted if p["name"] != "free"}
            for e in s["effects"]:
                if e["key"] not in effects or e.get("lo95") is None or e.get("hi95") is None:
                    continue
                truth, neutral = effects[e["key"]]
                half = e["hi95"] - e["value"] if truth > e["value"] else e["value"] - e["lo95"]
                if e["lo95"] <= truth <= e["hi95"]:
                    side = "held"
                else:
                    side = "toward" if abs(e["value"] - neutral) < abs(truth - neutral) else "away"
                out.setdefault(e["key"], []).append({
                    "side": side, "z": abs(truth - e["value"]) / (half / 1.96) if half > 0 else None,
                    "share": (e["value"] - neutral) / (truth - neutral),
                    "free_excess": excess[0] if excess else None})
    return out


def coverage_line(name, entries):
    n = len(entries)
    held = sum(1 for i in entries if i["side"] == "held")
    toward = sum(1 for i in entries if i["side"] == "toward")
    lo, hi = clopper_pearson(held, n)
    zs = sorted(i["z"] for i in entries if i["z"] is not None)
    median = f"{statistics.median(zs):.2f}" if zs else "-"
    factor = f"{zs[min(len(zs) - 1, int(0.95 * len(zs)))] / 1.96:.1f}" if len(zs) >= MIN_FOR_FACTOR else "-"
    return (f"| {name} | {n} | {held} ({100 * held / n:.0f} %; {100 * lo:.0f}-{100 * hi:.0f} %) | "
            f"{toward} / {n - held - toward} | {median} | {factor} |")


def trade_off_line(name, entries):
    """The size read against the free parameter's excess: a size that trades off against the free parameter
    comes out small where the free parameter comes out high (a negative correlation)."""
    shares = [i["share"] for i in entries]
    pairs = [(i["share"], i["free_excess"]) for i in entries if i["free_excess"] is not None]
    r = "-"
    if len(pairs) >= MIN_FOR_CORRELATION and len({x for x, _ in pairs}) > 1 and len({y for _, y in pairs}) > 1:
        r = f"{statistics.correlation([x for x, _ in pairs], [y for _, y in pairs]):+.2f}"
    excess = f"{statistics.median(y for _, y in pairs):+.3f}" if pairs else "-"
    return f"| {name} | {len(entries)} | {statistics.median(shares):.2f} | {excess} | {r} |"


def main(args):
    if not args:
        print("usage: interval_coverage.py PASS_DIR [PASS_DIR...]", file=sys.stderr)
        return 2
    by_key = intervals(args)
    if not by_key:
        print("no interval of a planted key in the passes given")
        return 0
    print("| planted key | intervals | hold the truth (exact 95 %) | misses toward neutral / away | "
          "median miss, interval's se | widening for 95 % |")
    print("| :-- | --: | :-- | :-: | --: | --: |")
    for key in sorted(by_key):
        print(coverage_line(key, by_key[key]))
    print(coverage_line("all", [i for entries in by_key.values() for i in entries]))
    print()
    print("| planted key | sizes | median size / planted (from neutral) | median free parameter less its truth | "
          "correlation of the two |")
    print("| :-- | --: | --: | --: | --: |")
    for key in sorted(by_key):
        print(trade_off_line(key, by_key[key]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
