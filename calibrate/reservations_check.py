#!/usr/bin/python3
"""Issue 13's fourth bar as passes 24 and 25 score it: where rule 5 names an alternative and the drag's law is
not established, and no failed test is said first, the verdict ends with the law's reservation.

    /usr/bin/python3 calibrate/reservations_check.py CASES_CSV

CASES_CSV: a pass's cases.csv (calibrate/blind_summary.py). One line per calibration with both reservations
due, then the count and how many miss the law's.
"""
import csv
import sys

LAW = "the drag's law in the speed is not established: a drag of another law may be acting"


def main(path):
    both = [r for r in csv.DictReader(open(path))
            if r["alternatives"] not in ("", "none") and any(a not in ("", "none") for a in r["alternatives"].split("; "))
            and r["law_undetermined"] == "True" and r["verdict"].startswith("effect found; these data")]
    for r in both:
        print(f"{r['case']}: {'both reservations' if r['verdict'].endswith(LAW) else 'LAW RESERVATION MISSING'}: {r['verdict']}")
    print(f"calibrations with both reservations due: {len(both)}; missing the law's: "
          f"{sum(not r['verdict'].endswith(LAW) for r in both)}")


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    try:
        main(sys.argv[1])
    except OSError as e:
        print(f"error: {e}", file=sys.stderr)
        sys.exit(2)
