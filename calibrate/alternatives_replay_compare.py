#!/usr/bin/python3
"""What rule 5 (calibrate/decisions.hpp: alternatives these data do not exclude) changed in a replay.

For every case that both folders hold (<case>/summary.json), compares a replay made with
--alternatives N (AFTER) with the same calibrations made without it (BEFORE; a blind pass itself):
rule 5 fits other candidates beside the one tried and changes nothing the loop decides, so every
summary.json field must be equal but the verdict, the option's record, the added effects' and the
rounds' alternatives, the rounds' fits (rule 5 adds them) and the timing and run counts. The
verdict may change only to "effect found; these data do not exclude another effect in its place",
where AFTER names an alternative and BEFORE said "effect found" (or only added the drag's law
qualifier). One line per case, then the count of cases with other differences (exit 1 if any).

    /usr/bin/python3 calibrate/alternatives_replay_compare.py BEFORE AFTER [CASE ...]
"""
import sys

import law_replay_compare as compare

QUALIFIED = "effect found; these data do not exclude another effect in its place"
# Verdicts rule 5 may qualify: the ones that come after the poor-fit and held-out flags.
QUALIFIABLE = ("effect found",
               "effect found; the drag's law in the speed is not established: a drag of another law may be acting")


def named(summary):
    """The alternatives named for each added effect, as {effect: [names]} (only those with some)."""
    return {e["effect"]: e["alternatives"] for e in summary.get("effects", []) if e.get("alternatives")}


def differences(before, after):
    return compare.other_differences(before, after, allowed={"alternatives"},
                                     allowed_in={"effects": {"alternatives"}, "rounds": {"fits", "alternatives"}})


def verdict_change_allowed(before, after):
    if before["verdict"] == after["verdict"]:
        return not (named(after) and after["verdict"] in QUALIFIABLE)  # a name must qualify the verdict
    return after["verdict"] == QUALIFIED and before["verdict"] in QUALIFIABLE and bool(named(after))


def describe(case, before, after):
    fits = [f"{f['effect']} p {f['fitted_p']:.3g}" for rd in after.get("rounds", []) for f in rd.get("fits", [])
            if "fitted_p" in f]
    change = "unchanged" if before["verdict"] == after["verdict"] else f"'{before['verdict']}' ->"
    alternatives = "; ".join(f"{e} or {', '.join(a)}" for e, a in named(after).items()) or "none named"
    return f"{case}: {change} '{after['verdict']}'; {alternatives}; fits: {', '.join(fits) or 'none'}"


if __name__ == "__main__":
    sys.exit(compare.main(sys.argv[1:], differences, verdict_change_allowed, describe, what="rule 5",
                          not_allowed="the verdict changed otherwise than rule 5 allows", doc=__doc__))
