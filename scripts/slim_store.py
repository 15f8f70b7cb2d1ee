#!/usr/bin/python3
"""Copy a results store without its per-sphere crossing rows, to keep or to commit.

    /usr/bin/python3 scripts/slim_store.py SRC.sqlite DST.sqlite

The crossings table (one row per sphere through the gap: job key, id, time, x) is ~95 % of a
1551-sphere run's 120 kB. Screens (the race, the confirmation, the 3D check and their report)
never read it: they use each run's summary row, its clogs and its avalanches, which are copied
whole. Studies whose reports do read crossings (snapshots, calibration observables such as the
exit offset and spread) must not be slimmed. The copy is taken with SQLite's online backup, so a
study may still be writing SRC; DST is written to DST.partial first and renamed when complete,
and an existing DST is replaced only if it is itself a store (it has a runs table).
"""
import os
import sqlite3
import sys


def is_store(path):
    try:
        with sqlite3.connect(f"file:{path}?mode=ro", uri=True) as db:
            return db.execute("SELECT 1 FROM sqlite_master WHERE name = 'runs'").fetchone() is not None
    except sqlite3.Error:
        return False


def main(argv):
    if len(argv) != 3:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    src, dst = argv[1], argv[2]
    if not is_store(src):
        print(f"error: {src}: not a gapflow results store (no runs table)", file=sys.stderr)
        return 2
    if os.path.exists(dst) and not is_store(dst):
        print(f"error: {dst} exists and is not a results store; not overwriting it", file=sys.stderr)
        return 2
    partial = dst + ".partial"
    if os.path.exists(partial):
        os.remove(partial)
    with sqlite3.connect(f"file:{src}?mode=ro", uri=True) as source, sqlite3.connect(partial) as copy:
        source.backup(copy)
    copy = sqlite3.connect(partial)
    runs = copy.execute("SELECT count(*) FROM runs").fetchone()[0]
    rows = copy.execute("DELETE FROM crossings").rowcount
    copy.commit()
    copy.execute("VACUUM")
    copy.close()
    os.replace(partial, dst)
    print(f"{dst}: {runs} runs, {rows} crossing rows left out, {os.path.getsize(dst) / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
