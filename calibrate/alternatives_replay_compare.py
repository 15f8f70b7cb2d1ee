#!/usr/bin/python3
"""What rule 5 (calibrate/decisions.hpp: alternatives these data do not exclude) changed in a replay.

For every case that both folders hold (<case>/summary.json), compares a replay made with
--alternatives N (AFTER) with the same calibrations made without it (BEFORE; a blind pass itself):
rule 5 fits other candidates beside the one tried and changes nothing the loop decides, so every
summary.json field must be equal but the verdict, the option's record, the added effects' and the
rounds' alternatives, the rounds' fits (rule 5 adds them after those rule 4 made, which must stay as
they were) and the timing and run counts; each round's alternatives must be what its fits give (with
one contender: every fit but the one tried, not at neutral, fitted p >= 0.05), and each added effect's
those of its round less the effects added. The
verdict may change only to "effect found; these data do not exclude another effect in its place",
where AFTER names an alternative and BEFORE said "effect found" or added only the drag's law
qualifier; that qualifier is then kept after the rule's. With --pass23-wording the rule's wording
alone may replace the qualifier, as the binaries of blind pass 23's replay (before 21de738) did. One line per case, then the count of cases with other differences (exit 1 if any).

    /usr/bin/python3 calibrate/alternatives_replay_compare.py [--pass23-wording] BEFORE AFTER [CASE ...]
"""
import sys

import law_replay_compare as compare

FOUND = "effect found"
QUALIFIED = FOUND + "; these data do not exclude another effect in its place"
LAW = "; the drag's law in the speed is not established: a drag of another law may be acting"
# Verdicts rule 5 may qualify (the ones that come after the poor-fit and held-out flags), and what each may become.
QUALIFIABLE = (FOUND, FOUND + LAW)
QUALIFIED_AS = {FOUND: (QUALIFIED,), FOUND + LAW: (QUALIFIED + LAW,)}
PASS23_WORDING = {FOUND: (QUALIFIED,), FOUND + LAW: (QUALIFIED,)}  # rule 5's wording replaced the law's


def named(summary):
    """The alternatives named for each added effect, as {effect: [names]} (only those with some)."""
    return {e["effect"]: e["alternatives"] for e in summary.get("effects", []) if e.get("alternatives")}


ALPHA = 0.05  # the loop's level (CalibrationDef::alpha; the blind passes run the default)
FITTED = {"fitted_chi2", "fitted_dof", "fitted_p"}


def expected_alternatives(rd):
    """Rule 5 recomputed from a round's fits: every fit but the one tried, not at neutral, fitted p >= alpha."""
    return [f["effect"] for f in rd.get("fits", []) if f["effect"] != rd.get("best") and not f.get("at_neutral")
            and f.get("fitted_p") is not None and f["fitted_p"] >= ALPHA]


def rule_5_inconsistencies(before, after):
    """What rule 5 wrote that its own fits do not bear out, or fits it changed that rule 4 made."""
    out = []
    rounds_before, rounds_after = before.get("rounds", []), after.get("rounds", [])
    for k, rd in enumerate(rounds_after):
        fits_before = compare.without(rounds_before[k].get("fits", []), FITTED) if k < len(rounds_before) else []
        if compare.without(rd.get("fits", [])[:len(fits_before)], FITTED) != fits_before:
            out.append(f"round {k + 1}: the fits rule 4 made changed")
        named = rd.get("alternatives", [])
        if after.get("contenders", 1) < 2 and named != expected_alternatives(rd):
            out.append(f"round {k + 1}: alternatives {named} where its fits give {expected_alternatives(rd)}")
        if not set(named) <= {f["effect"] for f in rd.get("fits", [])}:
            out.append(f"round {k + 1}: an alternative that was not fitted")
    added = {e["effect"] for e in after.get("effects", [])}
    for e in after.get("effects", []):
        rounds = [rd for rd in rounds_after if rd.get("best") == e["effect"]]
        from_round = [n for n in (rounds[-1].get("alternatives", []) if rounds else []) if n not in added]
        if e.get("alternatives", []) != from_round:
            out.append(f"{e['effect']}: alternatives {e.get('alternatives', [])} where its round gives {from_round}")
    return out


def differences(before, after):
    return compare.other_differences(before, after, allowed={"alternatives"},
                                     allowed_in={"effects": {"alternatives"}, "rounds": {"fits", "alternatives"}}) + \
        rule_5_inconsistencies(before, after)


def verdict_change_allowed(before, after):
    if before["verdict"] == after["verdict"]:
        return not (named(after) and after["verdict"] in QUALIFIABLE)  # a name must qualify the verdict
    return after["verdict"] in QUALIFIED_AS.get(before["verdict"], ()) and bool(named(after))


def describe(case, before, after):
    fits = [f"{f['effect']} p {'-' if f['fitted_p'] is None else format(f['fitted_p'], '.3g')}"
            for rd in after.get("rounds", []) for f in rd.get("fits", []) if "fitted_p" in f]
    change = "unchanged" if before["verdict"] == after["verdict"] else f"'{before['verdict']}' ->"
    alternatives = "; ".join(f"{e} or {', '.join(a)}" for e, a in named(after).items()) or "none named"
    return f"{case}: {change} '{after['verdict']}'; {alternatives}; fits: {', '.join(fits) or 'none'}"


if __name__ == "__main__":
    args = sys.argv[1:]
    if "--pass23-wording" in args:
        args.remove("--pass23-wording")
        QUALIFIED_AS = PASS23_WORDING
    sys.exit(compare.main(args, differences, verdict_change_allowed, describe, what="rule 5",
                          not_allowed="the verdict changed otherwise than rule 5 allows", doc=__doc__))
