#!/usr/bin/python3
"""Copy a results store without its per-sphere crossing rows, to keep or to commit.

    /usr/bin/python3 scripts/slim_store.py SRC.sqlite DST.sqlite [--force]

The crossings table (one row per sphere through the gap: job key, id, time, x) is ~95 % of a
1551-sphere run's 120 kB. A screen's race, confirmation and 3D check, and its report's tables and
heat maps, use each run's summary row, its clogs and its avalanches, which are copied whole; the
report's snapshots re-run their run and then say that the store has no crossing times to compare
the re-run with. Not for studies whose analyses read crossings: calibrations (front arrival, exit
offset and spread refuse a slim store) and re-injected runs (the steady-state J): this script
refuses a store with re-injected runs. `gapflow compare` and `merge` see a slim copy's runs as
different from the originals (they are: no crossings).

The copy is taken with SQLite's online backup, so a study may still be writing SRC; DST is
written to DST.partial first and renamed when complete. DST is replaced only if it is itself a
slim store (a results store without crossing rows), never SRC itself, never a full store unless
--force, never a file that is not a results store.
"""
import os
import sqlite3
import sys


def open_ro(path):
    return sqlite3.connect(f"file:{path}?mode=ro", uri=True)


def is_store(path):
    try:
        with open_ro(path) as db:
            return db.execute("SELECT 1 FROM sqlite_master WHERE name = 'runs'").fetchone() is not None
    except sqlite3.Error:
        return False


def crossing_rows(path):
    with open_ro(path) as db:
        return db.execute("SELECT count(*) FROM crossings").fetchone()[0]


def refusal(src, dst, force):
    """Why the copy must not be made, or None."""
    if not is_store(src):
        return f"{src}: not a gapflow results store (no runs table)"
    with open_ro(src) as db:
        reinjected = db.execute("SELECT count(*) FROM runs WHERE reinjected > 0").fetchone()[0]
    if reinjected:
        return f"{src}: {reinjected} runs re-injected their spheres; their steady-state J is read from crossings"
    if os.path.exists(dst):
        if os.path.samefile(src, dst):
            return f"{dst} is the source store itself"
        if not is_store(dst):
            return f"{dst} exists and is not a results store; not overwriting it"
        if crossing_rows(dst) > 0 and not force:
            return f"{dst} is a full store (it has crossing rows); not overwriting it without --force"
    return None


def main(argv):
    args = [a for a in argv[1:] if a != "--force"]
    force = len(args) != len(argv) - 1
    if len(args) != 2:
        print("usage: " + __doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    src, dst = args
    why = refusal(src, dst, force)
    if why:
        print(f"error: {why}", file=sys.stderr)
        return 2
    partial = dst + ".partial"
    if os.path.exists(partial):
        os.remove(partial)
    with open_ro(src) as source, sqlite3.connect(partial) as copy:
        source.backup(copy)
    copy = sqlite3.connect(partial)
    runs = copy.execute("SELECT count(*) FROM runs").fetchone()[0]
    rows = copy.execute("DELETE FROM crossings").rowcount
    copy.commit()
    copy.execute("PRAGMA journal_mode = DELETE")  # one self-contained file, no -wal beside it
    copy.execute("VACUUM")
    copy.close()
    os.replace(partial, dst)
    print(f"{dst}: {runs} runs, {rows} crossing rows left out, {os.path.getsize(dst) / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
