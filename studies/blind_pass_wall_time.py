#!/usr/bin/env python3
"""The wall time of a blind pass carried from machine to machine (studies/blind_pass_carry.sh).

A pass's `/usr/bin/time -v` record is lost with a machine that ends while the pass runs, so its
wall time is read from the carry's logs instead: launches.txt (each launch's start, and its end
where studies/blind_pass_session.sh recorded one: "ended" or "stopped by a signal") and saves.txt
(when each save was made). A launch without a recorded end ran until about its last save before the
next launch (at least until then, if no save was made by hand after the pass had stopped); one with
neither was lost with its machine (its time unknown, nothing of it kept). Minutes are rounded down.

    /usr/bin/python3 studies/blind_pass_wall_time.py CARRY

Prints a line per launch and the total: the time known, a lower bound where an end was not recorded.
Exit 2 on a folder without launches.txt.
"""
import re
import sys
from datetime import datetime
from pathlib import Path

STAMP = r"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)"
LAUNCH = re.compile(STAMP + r" launch (\d+) at ")
END = re.compile(STAMP + r" launch (\d+): (stopped by a signal|the pass's command ended)")
SAVE = re.compile(STAMP + r" ")


def when(stamp):
    return datetime.strptime(stamp, "%Y-%m-%dT%H:%M:%SZ")


def hours_minutes(seconds):
    minutes = int(seconds // 60)
    return f"{minutes // 60} h {minutes % 60:02d} min"


def launches(carry):
    """[(number, start, end or None, how the end is known)] in the order launched."""
    starts, ends = {}, {}
    for line in (carry / "launches.txt").read_text().splitlines():
        if m := LAUNCH.match(line):
            starts[int(m.group(2))] = when(m.group(1))
        elif m := END.match(line):
            ends[int(m.group(2))] = (when(m.group(1)), m.group(3))
    saves_file = carry / "saves.txt"
    saves = [when(m.group(1)) for line in (saves_file.read_text().splitlines() if saves_file.exists() else [])
             if (m := SAVE.match(line))]
    numbers = sorted(starts)
    out = []
    for i, n in enumerate(numbers):
        start = starts[n]
        if n in ends:
            out.append((n, start, ends[n][0], "stopped" if ends[n][1].startswith("stopped") else "ended"))
            continue
        until = starts[numbers[i + 1]] if i + 1 < len(numbers) else datetime.max
        last = [s for s in saves if start <= s < until]
        out.append((n, start, max(last), "last save") if last else (n, start, None, "lost"))
    return out


def main(argv):
    if len(argv) != 2:
        print("usage: studies/blind_pass_wall_time.py CARRY", file=sys.stderr)
        return 2
    carry = Path(argv[1])
    if not (carry / "launches.txt").is_file():
        print(f"error: {carry} has no launches.txt (not a carried pass)", file=sys.stderr)
        return 2
    known = 0.0
    bound = False
    lost = 0
    for n, start, end, how in launches(carry):
        if end is None:
            lost += 1
            print(f"launch {n}: from {start:%Y-%m-%d %H:%M:%S} UTC, lost with its machine (no end, no save)")
            continue
        seconds = (end - start).total_seconds()
        known += seconds
        bound |= how == "last save"
        what = {"stopped": "stopped", "ended": "ended",
                "last save": "until its last save (its end not recorded)"}[how]
        print(f"launch {n}: from {start:%Y-%m-%d %H:%M:%S} to {end:%H:%M:%S} UTC, {hours_minutes(seconds)}, {what}")
    print(f"wall time over the launches: {hours_minutes(known)}"
          + (" (a launch's end read from its last save)" if bound else "")
          + (f"; {lost} launch(es) lost with their machines, their time unknown and nothing of them kept" if lost else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
