#!/usr/bin/env bash
# A blind pass's calibrations run again, by another binary or with other calibrate options, on a copy
# of the pass's store: the same twins, the same seeds. Runs the pass made are reused; new parameter
# values are simulated into the copy, DIR/runs.sqlite (the pass's own store is not written). Writes PASS/DIR/<case>/
# (each calibration's report and summary.json, its log and /usr/bin/time record) and PASS/DIR/report.md, cases.csv by
# calibrate/blind_summary.py, with a copy of the pass's truth.
#
#   GAPFLOW=<binary> studies/calibration_replay.sh PASS DIR [JOBS] [CALIBRATE OPTIONS...]
#
# e.g. studies/calibration_replay.sh results/calibration-blind-pass11 replay-one-contender 2 --contenders 1
# Resumable: run again with the same binary and options, and the calibrations finished are kept and the
# others continue on DIR/runs.sqlite (a copy of the pass's store, not committed). DIR made with another
# binary or other options is refused (exit 2). Calibrations run one after another, each with JOBS
# workers; a calibration's result does not depend on JOBS.
#
# A pass still running, or cut off, is replayed as far as it has got: a twin whose calibration in the
# pass has not finished (no summary.json, or its .time still empty) is left for a later run. The store
# is copied anew at every start, with SQLite's backup (consistent while the pass writes to it), so a
# DIR carried to another machine without its store (studies/blind_pass_carry.sh) is continued there on
# the store of the pass's part run on that machine: with a model seed per twin no run is shared
# between calibrations, so that store holds every run its calibrations made.
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 2 ]] || { echo "usage: studies/calibration_replay.sh PASS DIR [JOBS] [CALIBRATE OPTIONS...]" >&2; exit 2; }
pass=${1%/}
dir=$pass/$2
jobs=${3:-$(nproc)}
shift $(( $# < 3 ? $# : 3 ))
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
[[ -f $pass/runs.sqlite && -d $pass/twins && -d $pass/truth ]] ||
  { echo "error: $pass is not a blind pass with a store (runs.sqlite, twins/, truth/ expected)" >&2; exit 2; }
made_by="$(sha256sum "$gapflow" | cut -c1-16) $*"
copy_store() {  # SQLite's online backup: a consistent copy even while the pass writes to its store
  /usr/bin/python3 -c 'import sqlite3, sys
source, copy = sqlite3.connect(sys.argv[1]), sqlite3.connect(sys.argv[2])
source.backup(copy)
copy.close()' "$pass/runs.sqlite" "$dir/runs.sqlite.partial"
  mv "$dir/runs.sqlite.partial" "$dir/runs.sqlite"
}
if [[ -d $dir ]]; then
  [[ -f $dir/replay.made_by && $(cat "$dir/replay.made_by") == "$made_by" ]] ||
    { echo "error: $dir was made by another binary or other options; use another DIR or delete it" >&2; exit 2; }
else
  mkdir -p "$dir"
  cp -r "$pass/truth" "$pass/design" "$pass/seed_offset" "$dir/"   # what the summary reads
  for f in model_seeds twin_replicates; do
    if [[ -f $pass/$f ]]; then cp "$pass/$f" "$dir/"; fi
  done
  echo "$made_by" > "$dir/replay.made_by"
fi
# A new copy at every start: it holds every run the pass has made so far, also those of calibrations
# that finished since the last start (the replay's own runs of a calibration it had not finished are
# simulated again, to the same values).
copy_store
for truth in "$pass"/truth/*.json; do   # twins made since DIR was (a pass replayed as far as it has got)
  [[ -e $dir/truth/$(basename "$truth") ]] || cp "$truth" "$dir/truth/"
done
unfinished=0
for twin in "$pass"/twins/*.toml; do
  id=$(basename "$twin" .toml)
  [[ -f $dir/$id/summary.json ]] && continue   # finished (as studies/calibration_blind.sh judges it)
  # Not finished in the pass yet: /usr/bin/time creates the .time at the start and writes it at the end.
  if [[ ! -f $pass/$id/summary.json || ( -f $pass/$id.time && ! -s $pass/$id.time ) ]]; then
    unfinished=$((unfinished + 1)); continue
  fi
  /usr/bin/time -v -o "$dir/$id.time" "$gapflow" calibrate "$twin" --model 2d --out "$dir/$id" \
    --db "$dir/runs.sqlite" --jobs "$jobs" --no-plots "$@" > "$dir/$id.log" 2>&1 ||
    { echo "error: the calibration of $id failed; see $dir/$id.log" >&2; exit 1; }
done
if ((unfinished > 0)); then
  echo "replayed what $pass has finished; $unfinished twin(s) left for a later run (no summary yet)" >&2
fi
/usr/bin/python3 calibrate/blind_summary.py "$dir" > /dev/null
