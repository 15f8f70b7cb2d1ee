#!/usr/bin/python3
"""What the drag's law check (calibrate/form_check.hpp, "the law in the speed") changed in a replay.

For every case that both folders hold (<case>/summary.json), compares a replay made by a binary with
the law check (AFTER) with one of the same calibrations made by its parent (BEFORE): every
summary.json field but the verdict, the law's own fields and the timing and run counts must be
equal (the check runs after every decision and simulates nothing); the verdict may change only
where BEFORE said "effect found" with a linear drag added. One line per case, then the count of
cases with other differences (exit 1 if any, so that a script can stop on it).

    /usr/bin/python3 calibrate/law_replay_compare.py BEFORE AFTER [CASE ...]
"""
import json
import sys
from pathlib import Path

LAW_FIELDS = {"law_power", "law_undetermined"}
CHECK_LAW_FIELDS = {"law_spread", "law_power"}
# Timing and run counts depend on the machine and on what the store held, not on the decisions.
RUN_FIELDS = {"run_seconds", "cpu_seconds", "wall_seconds", "runs_simulated", "runs_reused", "data_file"}
DRAG = "linear_drag"


# Fields of a state ("before", "after") that later binaries record and earlier ones did not (surface_window:
# a2dddfa): compared where both summaries have them, left out where one does not.
STATE_FIELDS_ADDED_LATER = {"surface_window"}


def comparable_states(before, after):
    """`before` and `after` states with the fields only one of them records left out."""
    drop = {k for k in STATE_FIELDS_ADDED_LATER if (k in before) != (k in after)}
    return without([before], drop)[0], without([after], drop)[0]


def without(items, fields):
    """A list of objects with `fields` left out of each."""
    return [{k: v for k, v in x.items() if k not in fields} for x in items]


def other_differences(before, after, allowed=LAW_FIELDS, allowed_in={"form_checks": CHECK_LAW_FIELDS}):
    """The summary.json fields that differ beyond the verdict, the run fields and `allowed`; a list field
    named in `allowed_in` differs only beyond the fields listed for its objects."""
    out = []
    for key in sorted(set(before) | set(after)):
        if key in allowed | RUN_FIELDS | {"verdict"}:
            continue
        if key in allowed_in:
            if without(before.get(key, []), allowed_in[key]) != without(after.get(key, []), allowed_in[key]):
                out.append(key)
        elif key in ("before", "after") and isinstance(before.get(key), dict) and isinstance(after.get(key), dict):
            b, a = comparable_states(before[key], after[key])
            if b != a:
                out.append(key)
        elif before.get(key) != after.get(key):
            out.append(key)
    return out


def verdict_change_allowed(before, after):
    if before["verdict"] == after["verdict"]:
        return True
    drag_added = any(e["effect"] == DRAG for e in before.get("effects", []))
    return before["verdict"] == "effect found" and drag_added


def describe(case, before, after):
    law = after.get("law_power")
    along = [c for c in after.get("form_checks", []) if c.get("law_power") is not None]
    checks = "; ".join(f"{c['effect']} along {c['column']}: spread asked {c['law_spread']:.3f}, power "
                       f"{c['law_power']:.3f}" for c in along) or "no check asked the law"
    change = "unchanged" if before["verdict"] == after["verdict"] else f"'{before['verdict']}' ->"
    return (f"{case}: {change} '{after['verdict']}'; law_power "
            f"{'-' if law is None else f'{law:.3f}'}, undetermined {after.get('law_undetermined')}; {checks}")


def main(argv, differences=other_differences, allowed=verdict_change_allowed, line=describe, what="the law",
         not_allowed="the verdict changed where no linear drag was found", doc=__doc__):
    """Compares BEFORE and AFTER case by case (argv: BEFORE AFTER [CASE ...]); the other arguments say
    what the change under test may alter (alternatives_replay_compare.py passes its own)."""
    if len(argv) < 2:
        sys.exit(doc)
    before_dir, after_dir = Path(argv[0]), Path(argv[1])
    cases = argv[2:] or sorted(p.parent.name for p in after_dir.glob("*/summary.json")
                               if (before_dir / p.parent.name / "summary.json").is_file())
    if not cases:
        print(f"error: no case with a summary.json in both {before_dir} and {after_dir}", file=sys.stderr)
        sys.exit(2)
    bad = []
    for case in cases:
        paths = [d / case / "summary.json" for d in (before_dir, after_dir)]
        missing = [str(p) for p in paths if not p.is_file()]
        if missing:
            print(f"error: {', '.join(missing)} missing", file=sys.stderr)
            sys.exit(2)
        before, after = (json.loads(p.read_text()) for p in paths)
        print(line(case, before, after))
        other = differences(before, after)
        if other or not allowed(before, after):
            bad.append(case)
            print(f"  DIFFERS: {', '.join(other) or not_allowed}")
    print(f"cases compared: {len(cases)}; with differences beyond {what}: {len(bad)}"
          f"{' (' + ', '.join(bad) + ')' if bad else ''}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
