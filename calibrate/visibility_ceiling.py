#!/usr/bin/env python3
"""How far a blind pass's single-effect score is limited by what its data show.

    /usr/bin/python3 calibrate/visibility_ceiling.py results/calibration-blind-pass10 [more passes...]

Reads each pass's cases.csv and, over its single-effect twins (every catalogue effect alone at a
low and a high size), counts: identified (alone or in a reported group that holds it), visible to
the oracle (power >= 0.8 of a score test that knew the planted signature), and identified among the
visible. Which twins are single and which visible is cases.csv's own (its truth and visible columns,
by calibrate/blind_summary.py), so the counts are the pass report's. "Ceiling" is visible / singles: the share a loop would
score that finds exactly what the oracle can see and nothing else. The last line pools the passes
given, with a 95 % Clopper-Pearson interval on the identified share (the twins taken as independent
trials: up to pass 19 every twin of a pass fitted one draw of the model's noise, so that interval is
too narrow for them). `--by-case` adds, per case over the passes given, how often it was identified
and how often visible: where the misses are. Exit 2 on a folder without cases.csv.

    /usr/bin/python3 calibrate/visibility_ceiling.py --by-case results/calibration-blind-pass{10,12,13,14,15,16,17,18,19}

`--gates` says where the single effects were won or lost in the first round, from each
calibration's summary.json: whether rule 1's chi^2 gate passed (the fitted points' chi^2 beyond the
noise at the baseline), whether the planted effect's own score was significant there, and whether
it was identified; and, among the twins stopped at the gate, how many a decisive-score route at
adjusted p 1e-4, 1e-3, 1e-2 would have tried, and in how many the planted effect had that best
score (model-free, unlike --rule-1's --decisive); with `--by-case`, per case.

    /usr/bin/python3 calibrate/visibility_ceiling.py --gates --by-case results/calibration-blind-pass{10,12,13,14,15,16,17,18,19,20}

`--rule-1` adds the ceiling of a loop bound by the issue's rule 1: it attributes only when the
fitted points' chi^2 is beyond the noise (p < 0.05) AND the best score is significant. For each
single-effect twin, with its oracle's lambda (truth/<case>.json `signal`: the chi^2 the planted
effect adds over the fitted points beyond the free parameter's refit), the residual is taken as
linear: its component along the known signature is Z + sqrt(lambda), the other dof - 1 components
central, so the score statistic S = (Z + sqrt(lambda))^2 and the chi^2 is S + R with R ~
chi^2(dof - 1) independent of S (dof: fitted points + measured free parameters - free
parameters). The chance of passing both gates is P(S > critical and S + R > chi^2_0.95(dof)),
the score's critical value the oracle's own (Bonferroni over every applicable effect). Its sum
over the twins is what an oracle bound by rule 1 identifies on average; per pass, the chance that
it identifies at least 90 % of the single effects (the issue's bar) follows from those chances
(independent twins: a Poisson-binomial). A model, and a biased one: on passes 10, 12-20 it
predicts 156 of the 180 twins past the chi^2 gate where the calibrations had 162, because where the
gate decides (lambda 10-50) the loop's chi^2 excess runs about 1.4 lambda (oracle_scale.py), and
pass 10's and most of 12-13's lambda predate the remade oracle. --scale and --decisive inherit it;
--scale also ignores the noise floor (floor_relative), which more runs do not lower, so it
overstates what they buy. With `--remade NAME`, a twin's truth is read from
PASS/NAME/truth/ where that holds it (the oracle remade for passes 12-15: `resignal`). With
`--by-case` too, the rule-1 oracle's expectation and the loop's count per case. With `--scale K`,
every lambda is multiplied by K first: the same twins with the noise's variance divided by K (K
times the data's runs and the model's replicates), a projection of what more runs would buy. With
`--decisive P`, the oracle also tries a best score whose adjusted p is below P where the chi^2 is
within the noise (the loop's `--decisive-score P`, off by default): what relaxing rule 1 so would buy.

    /usr/bin/python3 calibrate/visibility_ceiling.py --rule-1 --remade resignal results/calibration-blind-pass{10,12,13,14,15,16,17,18,19,20}
"""
import collections
import json
import math
import os
import sys

import numpy as np
from scipy.stats import beta, chi2, norm

from blind_pass import cases_table, number_option, take_option
from blind_summary import NOT_SINGLE


def single_rows(pass_dir):
    return [r for r in cases_table(pass_dir) if r["truth"] not in NOT_SINGLE]


def clopper_pearson(k, n, level=0.95):
    """The exact binomial interval for k successes of n."""
    a = (1 - level) / 2
    lo = beta.ppf(a, k, n - k + 1) if k > 0 else 0.0
    hi = beta.ppf(1 - a, k + 1, n - k) if k < n else 1.0
    return lo, hi


def counts(pass_dir):
    singles = single_rows(pass_dir)
    visible = [r for r in singles if r["visible"] == "True"]
    return {
        "singles": len(singles),
        "identified": sum(r["identified"] == "True" for r in singles),
        "visible": len(visible),
        "visible_identified": sum(r["identified"] == "True" for r in visible),
    }


# One single-effect twin's first round: rule 1's chi^2 gate passed (the fitted points' chi^2 p < alpha
# at the baseline); the planted effect's own score significant (visible, adjusted p < alpha);
# identified; the best visible score's adjusted p, and whether that best is the planted effect.
Gates = collections.namedtuple("Gates", "case gate planted identified best_p best_is_planted")


def first_round_gates(pass_dir, alpha=0.05):
    """Per single-effect twin, from its calibration's summary.json: its Gates."""
    out = []
    for r in single_rows(pass_dir):
        path = os.path.join(pass_dir, r["case"], "summary.json")
        if not os.path.isfile(path):
            print(f"error: no {path} (--gates reads the calibrations' summaries)", file=sys.stderr)
            sys.exit(2)
        with open(path, encoding="utf-8") as f:
            summary = json.load(f)
        gate = summary["before"]["fitted"]["p"] < alpha
        first = summary["rounds"][0]["candidates"] if summary.get("rounds") else []
        planted = any(c["effect"] == r["truth"] and c["visible"] and c["p_adjusted"] < alpha for c in first)
        visible = [c for c in first if c["visible"]]
        best = min(visible, key=lambda c: c["p_adjusted"]) if visible else None
        out.append(Gates(r["case"], gate, planted, r["identified"] == "True",
                         best["p_adjusted"] if best else 1.0, best is not None and best["effect"] == r["truth"]))
    return out


def gates_report(pass_dirs, with_cases):
    rows = [row for pass_dir in pass_dirs for row in first_round_gates(pass_dir)]
    n = len(rows)
    passed = [r for r in rows if r.gate]
    stopped = [r for r in rows if not r.gate]
    both = [r for r in passed if r.planted]
    print(f"first round, single effects ({n}): rule 1's chi^2 gate passed in {len(passed)} "
          f"({100 * len(passed) / n:.0f} %), and in those the planted effect's score significant in {len(both)}; "
          f"identified {sum(r.identified for r in rows)}: {sum(r.identified for r in both)} of the {len(both)}, "
          f"{sum(r.identified for r in passed if not r.planted)} of the {len(passed) - len(both)} others past the gate, "
          f"{sum(r.identified for r in stopped)} of the {len(stopped)} stopped at it "
          f"({sum(r.planted for r in stopped)} of those with the planted score significant)")
    # What the decisive-score route (--decisive-score P: the best score tried where the chi^2 is
    # within the noise) would have tried among the twins stopped at the gate, and how often the
    # planted effect was that best score.
    for p in (1e-4, 1e-3, 1e-2):
        tried = [r for r in stopped if r.best_p < p]
        print(f"  stopped at the gate with the best score's adjusted p < {p:g}: {len(tried)} "
              f"(the planted effect that best score in {sum(r.best_is_planted for r in tried)})")
    if with_cases:
        cases = {}
        for r in rows:
            c = cases.setdefault(r.case, [0, 0, 0, 0])
            c[0] += 1
            c[1] += r.gate
            c[2] += r.gate and r.planted
            c[3] += r.identified
        print("case: twins; chi^2 gate passed; and the planted score significant; identified")
        for name, (k, g, gp, i) in sorted(cases.items(), key=lambda item: (item[1][3] - item[1][0], item[0])):
            print(f"  {name}: {k}; {g}; {gp}; {i}")


def rule1_power(lam, dof, critical, alpha=0.05, decisive=0.0):
    """P(S > critical and S + R > chi^2_{1-alpha}(dof)), S = (Z + sqrt(lam))^2, R ~ chi^2(dof - 1).

    With `decisive` > 0 (the loop's --decisive-score: a best score whose Bonferroni-adjusted p is
    below it is tried whatever the chi^2 says), the chi^2 gate is also passed where S alone is
    beyond that adjusted level (the same Bonferroni factor as `critical`'s)."""
    z = np.linspace(-12.0, 12.0, 24001)
    s = (z + math.sqrt(max(lam, 0.0))) ** 2
    rest = chi2.sf(np.maximum(chi2.isf(alpha, dof) - s, 0.0), dof - 1)
    if decisive > 0:
        candidates = alpha / chi2.sf(critical, 1)
        rest = np.where(s > chi2.isf(decisive / candidates, 1), 1.0, rest)
    return float(np.trapz(norm.pdf(z) * np.where(s > critical, rest, 0.0), z))


def at_least(chances, k):
    """P(at least k successes) of independent trials with the given chances (Poisson-binomial)."""
    dist = [1.0]
    for p in chances:
        dist = [(dist[j] if j < len(dist) else 0.0) * (1 - p) + (dist[j - 1] * p if j > 0 else 0.0)
                for j in range(len(dist) + 1)]
    return sum(dist[k:])


def rule1_chances(pass_dir, remade=None, scale=1.0, decisive=0.0):
    """Per single-effect twin: the chance that an oracle bound by rule 1 attributes its effect."""
    out = []
    for r in single_rows(pass_dir):
        path = os.path.join(pass_dir, "truth", r["case"] + ".json")
        if remade and os.path.isfile(os.path.join(pass_dir, remade, "truth", r["case"] + ".json")):
            path = os.path.join(pass_dir, remade, "truth", r["case"] + ".json")
        if not os.path.isfile(path):
            print(f"error: no {path} (--rule-1 reads the twins' truth)", file=sys.stderr)
            sys.exit(2)
        with open(path, encoding="utf-8") as f:
            t = json.load(f)
        sig = t.get("signal") or {}
        if sig.get("chi2") is None:  # no oracle for this twin: nothing it could see
            out.append(0.0)
            continue
        free = sum(1 for v in t["planted"] if v["name"] == "free")
        measured = sum(1 for v in (t.get("measured") or {}).values() if v is not None and math.isfinite(v))
        out.append(rule1_power(scale * sig["chi2"], sig["points"] + measured - free, sig["critical"], decisive=decisive))
    return out


def rule1_by_case(pass_dirs, remade, scale, decisive):
    cases = {}
    for pass_dir in pass_dirs:
        for r, chance in zip(single_rows(pass_dir), rule1_chances(pass_dir, remade, scale, decisive)):
            c = cases.setdefault(r["case"], {"n": 0, "expected": 0.0, "identified": 0})
            c["n"] += 1
            c["expected"] += chance
            c["identified"] += r["identified"] == "True"
    print("case: rule 1's oracle, expected identified; the loop, identified")
    for name, c in sorted(cases.items(), key=lambda item: (item[1]["expected"], item[0])):
        print(f"  {name}: {c['expected']:.1f} of {c['n']}; {c['identified']} of {c['n']}")


def rule1_line(name, chances):
    n = len(chances)
    bar = math.ceil(0.9 * n - 1e-9)
    return (f"{name}: rule 1's two gates, an oracle: expected identified {sum(chances):.1f} of {n} "
            f"({100 * sum(chances) / n:.0f} %); both gates' chance >= 0.8 in {sum(c >= 0.8 for c in chances)}; "
            f"chance of >= {bar} of {n} {at_least(chances, bar):.2f}")


def line(name, c):
    pct = lambda a, b: f"{100 * a / b:.0f} %" if b else "-"
    return (f"{name}: identified {c['identified']} of {c['singles']} ({pct(c['identified'], c['singles'])}); "
            f"visible {c['visible']} (ceiling {pct(c['visible'], c['singles'])}); "
            f"identified among the visible {c['visible_identified']} of {c['visible']} "
            f"({pct(c['visible_identified'], c['visible'])})")


def by_case(pass_dirs):
    cases = {}
    for pass_dir in pass_dirs:
        for r in single_rows(pass_dir):
            c = cases.setdefault(r["case"], {"n": 0, "identified": 0, "visible": 0, "visible_identified": 0})
            c["n"] += 1
            c["identified"] += r["identified"] == "True"
            c["visible"] += r["visible"] == "True"
            c["visible_identified"] += r["visible"] == "True" and r["identified"] == "True"
    print("case: identified of passes; visible; identified among the visible")
    for name, c in sorted(cases.items(), key=lambda item: (item[1]["identified"] - item[1]["n"], item[0])):
        print(f"  {name}: {c['identified']} of {c['n']}; visible {c['visible']}; "
              f"{c['visible_identified']} of {c['visible']}")


def main():
    args = sys.argv[1:]
    with_cases = "--by-case" in args
    with_rule1 = "--rule-1" in args
    with_gates = "--gates" in args
    remade = take_option(args, "--remade", "a folder name (e.g. resignal)")
    scale = number_option(args, "--scale", "a positive number (the factor on every lambda)",
                          lambda v: v > 0 and math.isfinite(v))
    decisive = number_option(args, "--decisive", "an adjusted p in (0, 0.05) (the loop's --decisive-score)",
                             lambda v: 0 < v < 0.05)
    if not with_rule1 and (remade is not None or scale is not None or decisive is not None):
        print("error: --remade, --scale and --decisive go with --rule-1", file=sys.stderr)
        sys.exit(2)
    scale = 1.0 if scale is None else scale
    decisive = 0.0 if decisive is None else decisive
    pass_dirs = [a for a in args if a not in ("--by-case", "--rule-1", "--gates")]
    if not pass_dirs:
        print("usage: visibility_ceiling.py [--by-case] [--gates] [--rule-1 [--remade NAME] [--scale K] [--decisive P]] PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    total = {"singles": 0, "identified": 0, "visible": 0, "visible_identified": 0}
    for pass_dir in pass_dirs:
        c = counts(pass_dir)
        print(line(pass_dir, c))
        for k in total:
            total[k] += c[k]
    if len(pass_dirs) > 1:
        lo, hi = clopper_pearson(total["identified"], total["singles"])
        print(line("pooled", total) + f"; identified share 95 % interval [{100 * lo:.1f}, {100 * hi:.1f}] %")
    if with_cases:
        by_case(pass_dirs)
    if with_gates:
        gates_report(pass_dirs, with_cases)
    if with_rule1:
        pooled = []
        for pass_dir in pass_dirs:
            chances = rule1_chances(pass_dir, remade, scale, decisive)
            print(rule1_line(pass_dir, chances))
            pooled += chances
        if with_cases:
            rule1_by_case(pass_dirs, remade, scale, decisive)
        if len(pass_dirs) > 1:
            n, expected = len(pooled), sum(pooled)
            print(f"pooled: rule 1's two gates, an oracle: expected identified {expected:.1f} of {n} "
                  f"({100 * expected / n:.0f} %); both gates' chance >= 0.8 in {sum(c >= 0.8 for c in pooled)}")


if __name__ == "__main__":
    main()
