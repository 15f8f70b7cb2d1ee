#!/usr/bin/python3
"""What a blind pass (or a replay of one) cost and how its identifications were worded, from its
cases.csv (calibrate/blind_summary.py makes it):

    /usr/bin/python3 calibrate/pass_counts.py PASS_OR_REPLAY [...]

For each folder: how many calibrations added an effect; the runs simulated (beyond what its store
held) per calibration that added one, median and range, and over every calibration; the calibrations' own process CPU (cases.csv
process_cpu_s, where the binary records it) and wall, in all and median per calibration with an
effect; and of the single planted effects identified, those whose verdict names an alternative
(rule 5) and those with a plain "effect found" (no reservation of any kind); of those not identified,
those where rule 5 named the planted effect among the alternatives the data do not exclude to an effect
the loop added (the data cannot tell the two apart; counted beside the identifications, never in them;
only where rule 5 was asked).
"""
import csv
import os
import statistics
import sys

from blind_summary import NOT_SINGLE


def number(row, field):
    return float(row[field]) if row.get(field) not in (None, "") else None


def counts(folder):
    with open(os.path.join(folder, "cases.csv"), newline="") as f:
        rows = list(csv.DictReader(f))
    added = [r for r in rows if r["added"]]
    lines = [f"{folder}: {len(rows)} calibrations, {len(added)} added an effect"]
    simulated = sorted(int(r["runs_simulated"]) for r in added if r["runs_simulated"])
    if simulated:
        lines.append(f"  runs simulated per calibration that added an effect: median {statistics.median(simulated):.0f} "
                     f"({simulated[0]}-{simulated[-1]}); over every calibration {sum(int(r['runs_simulated'] or 0) for r in rows)}")
    for field, what in (("process_cpu_s", "process CPU"), ("wall_s", "wall")):
        every = [number(r, field) for r in rows]
        if every and all(v is not None for v in every):
            with_effect = [number(r, field) for r in added]
            median = f"; median per calibration with an effect {statistics.median(with_effect):.0f} s" if with_effect else ""
            lines.append(f"  {what}: {sum(every):.0f} s over every calibration{median}")
    single = [r for r in rows if r["truth"] not in NOT_SINGLE and r["identified"] == "True"]
    named = [r["case"] for r in single if any(a not in ("", "none") for a in r.get("alternatives", "").split("; "))]
    plain = [r["case"] for r in single if r["verdict"] == "effect found"]
    lines.append(f"  single planted effects identified: {len(single)}; with an alternative named (rule 5): {len(named)}"
                 + (f" ({', '.join(named)})" if named else "") + f"; with a plain \"effect found\": {len(plain)}")
    every_single = [r for r in rows if r["truth"] not in NOT_SINGLE]
    as_alternative = [r["case"] for r in every_single if r["identified"] != "True" and planted_named(r)]
    if every_single and any(r.get("alternatives") for r in rows):   # rule 5 asked (a column, not empty)
        lines.append(f"  not identified, the planted effect named as an alternative the data do not exclude (rule 5): "
                     f"{len(as_alternative)}" + (f" ({', '.join(as_alternative)})" if as_alternative else "")
                     + f"; identified or so named: {len(single) + len(as_alternative)} of {len(every_single)}")
    return lines


def planted_named(row):
    """Whether rule 5 named the row's planted effect among the alternatives to an effect the loop added."""
    return any(row["truth"] in names.split(",") for names in row.get("alternatives", "").split("; "))


def main(args):
    if not args:
        print("usage: pass_counts.py PASS_OR_REPLAY [...]", file=sys.stderr)
        return 2
    for folder in args:
        if not os.path.isfile(os.path.join(folder, "cases.csv")):
            print(f"error: {folder} has no cases.csv (calibrate/blind_summary.py makes it)", file=sys.stderr)
            return 2
        print("\n".join(counts(folder)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
