"""A blind pass folder (studies/calibration_blind.sh): which calibrations are the pass's own.

Shared by the analysis scripts (blind_summary.py's siblings), so that each counts the same twins."""
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
