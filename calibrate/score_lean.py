#!/usr/bin/env python3
"""Whether the first round's scores lean toward the effects' steps on the null twins of blind passes.

    /usr/bin/python3 calibrate/score_lean.py results/calibration-blind-pass{8,9,10,11,12,13,14,15,16,17}
    /usr/bin/python3 calibrate/score_lean.py --cases "null-1 null-2" PASS_DIR   # those cases only

On a null twin (no effect planted: folders null-*) the model is right, so each visible candidate's
linearised size (summary.json rounds[0].candidates[].estimate, in the effect's units) points toward its
step or away from it with equal chance, and the smallest Bonferroni-adjusted p of a round is below x
in at most a share x of the nulls. A score that shares noise with the residual leans toward the step
(calibrate/README.md, step 3; calibrate/effect_responses.hpp, "Shared noise"). Prints, pooled over the
passes given: per candidate, how many of its sizes point toward the step; in all; and how many nulls
have their best adjusted p below 0.001, 0.01, 0.05, 0.1 and 0.2. With --all, every twin is read, not
only the nulls (planted effects lean toward their own steps by design: a check of the script, not of
the loop). With --cases, those cases only. Exit 2 on a folder without such calibrations.
"""
import collections
import json
import sys
from blind_pass import calibrations, take_option


def first_round_candidates(summary_path):
    with open(summary_path, encoding="utf-8") as f:
        summary = json.load(f)
    if not summary["rounds"]:
        return None
    return [c for c in summary["rounds"][0]["candidates"] if c["visible"]]


def main():
    argv = sys.argv[1:]
    cases = take_option(argv, "--cases", "a list of case names")
    only = set(cases.split()) if cases is not None else None
    args = [a for a in argv if a != "--all"]
    pattern = "*" if "--all" in argv or only else "null-*"
    if not args:
        print("usage: score_lean.py [--all | --cases \"CASE...\"] PASS_DIR [PASS_DIR...]", file=sys.stderr)
        sys.exit(2)
    toward, scored = collections.Counter(), collections.Counter()
    best_p = []
    for pass_dir in args:
        summaries = [s for _, s in calibrations(pass_dir, pattern, only)]
        if not summaries:
            print(f"error: no {pattern} calibrations in {pass_dir}", file=sys.stderr)
            sys.exit(2)
        for s in summaries:
            cands = first_round_candidates(s)
            if cands is None:
                continue
            for c in cands:
                scored[c["effect"]] += 1
                toward[c["effect"]] += (c["estimate"] or 0) * c["step"] > 0
            best_p.append(min((c["p_adjusted"] for c in cands), default=1.0))
    which = " ".join(sorted(only)) if only else pattern
    print(f"{len(best_p)} twins ({which}) in {len(args)} folder(s); first round's visible candidates:")
    for effect in sorted(scored):
        print(f"  {effect}: {toward[effect]} of {scored[effect]} sizes toward the step")
    print(f"  all: {sum(toward.values())} of {sum(scored.values())} toward the step")
    for x in (0.001, 0.01, 0.05, 0.1, 0.2):
        n = sum(p < x for p in best_p)
        print(f"  best adjusted p < {x:g}: {n} of {len(best_p)} (a calibrated Bonferroni test: at most {x * len(best_p):.1f})")


if __name__ == "__main__":
    main()
