"""A blind pass folder (studies/calibration_blind.sh): which calibrations are the pass's own.

Shared by the analysis scripts (blind_summary.py's siblings), so that each counts the same twins."""
import csv
import glob
import os
import sys


def calibrations(pass_dir, pattern="*", cases=None):
    """(case, path of its summary.json) for each of the pass's calibrations, sorted by case: the folders
    PASS_DIR/<case> matching PATTERN with a summary.json, but not a replay (replay-*: a case calibrated
    again with another setting, kept beside the pass, is not one of its twins); only CASES if given."""
    out = []
    for summary in sorted(glob.glob(os.path.join(pass_dir, pattern, "summary.json"))):
        case = os.path.basename(os.path.dirname(summary))
        if case.startswith("replay-") or (cases is not None and case not in cases):
            continue
        out.append((case, summary))
    return out


def take_cases(args):
    """--cases "CASE..." taken from args: the set named, or None without the option; exit 2 on an empty list."""
    named = take_option(args, "--cases", "a list of case names")
    cases = set(named.split()) if named is not None else None
    if cases == set():
        print("error: --cases needs at least one case name", file=sys.stderr)
        sys.exit(2)
    return cases


def require_cases(folder, cases):
    """Exit 2 when `folder` lacks a calibration named in `cases` (None: nothing asked)."""
    missing = sorted(cases - {case for case, _ in calibrations(folder)}) if cases is not None else []
    if missing:
        print(f"error: {folder} has no calibration {', '.join(missing)}", file=sys.stderr)
        sys.exit(2)


def take_option(args, name, what):
    """The value after `name` in args (both removed), or None; exit 2 where the value is missing."""
    if name not in args:
        return None
    k = args.index(name)
    if k + 1 >= len(args):
        print(f"error: {name} needs {what}", file=sys.stderr)
        sys.exit(2)
    value = args[k + 1]
    del args[k:k + 2]
    return value


def number_option(args, name, what, valid):
    """The number after `name` in args (both removed), or None; exit 2 where it is missing, not a
    number or not `valid`."""
    text = take_option(args, name, what)
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not valid(value):
        print(f"error: {name} needs {what}, not '{text}'", file=sys.stderr)
        sys.exit(2)
    return value


def cases_table(folder):
    """A pass's (or replay's) cases.csv rows (calibrate/blind_summary.py); exit 2 where it has none."""
    path = os.path.join(folder, "cases.csv")
    if not os.path.isfile(path):
        print(f"error: no cases.csv in {folder}", file=sys.stderr)
        sys.exit(2)
    with open(path, newline="", encoding="utf-8") as f:
        return list(csv.DictReader(f))
