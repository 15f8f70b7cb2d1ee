#!/usr/bin/env bash
# A blind pass's calibrations run again, by another binary or with other calibrate options, on a copy
# of the pass's store: the same twins, the same seeds. Runs the pass made are reused; new parameter
# values are simulated into the copy, DIR/runs.sqlite (the pass's own store is not written). Writes PASS/DIR/<case>/
# (each calibration's report and summary.json, its log and /usr/bin/time record) and PASS/DIR/report.md, cases.csv by
# calibrate/blind_summary.py, with a copy of the pass's truth.
#
#   [ONLY="ID ..."] GAPFLOW=<binary> studies/calibration_replay.sh PASS DIR [JOBS] [CALIBRATE OPTIONS...]
#
# ONLY names the twins to replay (the others are left alone, neither replayed nor counted as left):
# on a machine whose store holds only some calibrations' runs (a pass carried between machines, see
# below), the ones it ran. A name with no twin in PASS is an error (exit 2).
# e.g. studies/calibration_replay.sh results/calibration-blind-pass11 replay-one-contender 2 --contenders 1
# The binary's defaults apply, not the pass's: builds from 21de738 on ask rule 5's alternatives (2) by
# default, so a pass before 24 is its own loop again only with --alternatives 0 (its summaries'
# "alternatives": 0 or absent), which is then part of the replay's record like any option.
# Resumable: run again with the same binary and options, and the calibrations finished are kept and the
# others continue on DIR/runs.sqlite (a copy of the pass's store, not committed). DIR made with another
# binary or other options is refused (exit 2). Calibrations run one after another, each with JOBS
# workers; a calibration's result does not depend on JOBS.
#
# A pass still running, or cut off, is replayed as far as it has got: a twin whose calibration in the
# pass has not finished (no summary.json, or its .time still empty) is left for a later run. The store
# is copied anew at every start, with SQLite's backup (consistent while the pass writes to it), so a
# DIR carried to another machine without its store (studies/blind_pass_carry.sh) is continued there on
# the store of the pass's part run on that machine. With a model seed per twin no run is shared
# between calibrations, so that store holds every run of the calibrations that machine ran; replay
# only those (stop the pass, then replay, then save): a calibration carried from another machine and
# replayed here would have its runs simulated again.
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
# ONLY, checked before anything is written: its names split on any whitespace, no globbing.
only=()
if [[ -v ONLY ]]; then
  read -r -d '' -a only <<< "$ONLY" || true
  ((${#only[@]} > 0)) || { echo "error: ONLY is set but names no twin" >&2; exit 2; }
  for id in "${only[@]}"; do
    [[ $id != */* ]] || { echo "error: ONLY names '$id'; allowed: twin names (no '/')" >&2; exit 2; }
    [[ -f $pass/twins/$id.toml ]] || { echo "error: ONLY names '$id'; $pass/twins has no $id.toml" >&2; exit 2; }
  done
fi
named() {  # ID: whether the replay takes this twin
  ((${#only[@]} == 0)) && return 0
  local id
  for id in "${only[@]}"; do [[ $id == "$1" ]] && return 0; done
  return 1
}
source studies/blind_cases.sh   # calibration_ended_well
copy_store() {  # SQLite's online backup: a consistent copy even while the pass writes to its store
  rm -f "$dir"/runs.sqlite.partial "$dir"/runs.sqlite.partial-wal "$dir"/runs.sqlite.partial-shm
  /usr/bin/python3 -c 'import sqlite3, sys
source = sqlite3.connect("file:" + sys.argv[1] + "?mode=ro", uri=True)
copy = sqlite3.connect(sys.argv[2])
source.backup(copy)
copy.close()
source.close()' "$pass/runs.sqlite" "$dir/runs.sqlite.partial"
  # A replay killed earlier may have left its store's log behind; SQLite would apply it to the copy.
  rm -f "$dir"/runs.sqlite-wal "$dir"/runs.sqlite-shm
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
exec 9> "$dir/runs.sqlite.replay-lock"   # *.sqlite*: neither copied nor carried
flock -n 9 || { echo "error: another replay is running in $dir" >&2; exit 2; }
# Which calibrations the pass has finished is decided before the store is copied: a calibration's
# runs are all in the store before its .time is written, so the copy holds them. The copy is made
# anew at every start, so that it holds every run the pass has made so far (the replay's own runs of
# a calibration it had not finished are simulated again, to the same values).
to_replay=() unfinished=0
for twin in "$pass"/twins/*.toml; do
  [[ -f $twin ]] || continue
  id=$(basename "$twin" .toml)
  named "$id" || continue
  calibration_ended_well "$dir" "$id" && continue
  if calibration_ended_well "$pass" "$id"; then to_replay+=("$id"); else unfinished=$((unfinished + 1)); fi
done
copy_store
for truth in "$pass"/truth/*.json; do   # twins made since DIR was (a pass replayed as far as it has got)
  [[ -f $truth && ! -e $dir/truth/$(basename "$truth") ]] || continue
  cp "$truth" "$dir/truth/.partial" && mv "$dir/truth/.partial" "$dir/truth/$(basename "$truth")"
done
for id in "${to_replay[@]}"; do
  /usr/bin/time -v -o "$dir/$id.time" "$gapflow" calibrate "$pass/twins/$id.toml" --model 2d --out "$dir/$id" \
    --db "$dir/runs.sqlite" --jobs "$jobs" --no-plots "$@" > "$dir/$id.log" 2>&1 ||
    { echo "error: the calibration of $id failed; see $dir/$id.log" >&2; exit 1; }
done
if ((unfinished > 0)); then
  echo "replayed what $pass has finished; $unfinished twin(s) left for a later run (not finished there yet)" >&2
fi
/usr/bin/python3 calibrate/blind_summary.py "$dir" > /dev/null
