#!/usr/bin/env bash
# Carries an unfinished blind pass from one machine to the next through the repository. A pass of
# 28 calibrations takes 4.5-7 h on 2 cores; a session's machine lasts less, and nothing outside the
# repository survives it. What studies/calibration_blind.sh needs to resume is small: its records
# (seed_offset, design, calibrate_options, model_seeds, twin_replicates), the twins and their
# truths, and each finished calibration (its folder and .time). Replays of the pass run as far as it
# has got (studies/calibration_replay.sh PASS DIR: PASS/DIR/) are carried the same way. Its run stores (*.sqlite*) are not
# needed: with MODEL_SEEDS=per-twin no run is shared between calibrations, and a calibration that
# was cut off is begun again from scratch (deterministic, so to the same result).
#
#   studies/blind_pass_carry.sh save PASS CARRY      copy what PASS has finished into CARRY
#   studies/blind_pass_carry.sh restore CARRY PASS   put CARRY back into PASS, then run the pass's command again
#
# save copies only finished calibrations (a folder with summary.json and a .time that is not empty:
# /usr/bin/time creates it empty at the start and writes it when the calibration has ended; anything
# else is cut off or still running, and would be begun again anyway) and never removes or changes a file already there: a file
# that differs is an error (exit 2), since a pass's files are written once. restore works the same
# way in the other direction. Both say how many files they copied and print nothing of the files'
# contents: a running pass is not read.
# Each save appends a line to CARRY/saves.txt (UTC time, twins, finished calibrations), from which
# the pass's wall time is bounded when its `/usr/bin/time -v` record was lost with a machine.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() { echo "usage: studies/blind_pass_carry.sh save PASS CARRY | restore CARRY PASS" >&2; exit 2; }
[[ $# -eq 3 ]] || usage
verb=$1; from=${2%/}; to=${3%/}
[[ -d $from ]] || { echo "error: no folder $from" >&2; exit 2; }

records=(seed_offset design calibrate_options model_seeds twin_replicates)

# copy_once SRC DST: copies SRC to DST unless DST holds the same bytes; a different DST is an error.
copy_once() {
  if [[ -e $2 ]]; then
    cmp -s "$1" "$2" || { echo "error: $2 exists and differs from $1; not overwritten" >&2; exit 2; }
    return 1
  fi
  mkdir -p "$(dirname "$2")"
  cp -p "$1" "$2"
}

# finished_calibrations FOLDER TWINS: the ids of TWINS/*.toml whose calibration in FOLDER has
# finished: its summary.json written and its .time not empty (/usr/bin/time creates it at the start
# and writes it at the end).
finished_calibrations() {
  for twin in "$2"/twins/*.toml; do
    [[ -f $twin ]] || continue
    id=$(basename "$twin" .toml)
    [[ -f $1/$id/summary.json && -s $1/$id.time ]] && echo "$id"
  done
  return 0
}

# The files of FOLDER that make a resumable pass, one path per line relative to FOLDER: its records,
# twins, truths and finished calibrations, and of each replay in it (studies/calibration_replay.sh,
# a folder with replay.made_by) the same but its summary over the cases (remade when it ends).
carried_files() {
  (cd "$1"
   for record in "${records[@]}"; do [[ -f $record ]] && echo "$record"; done
   find twins truth -maxdepth 1 -type f \( -name '*.toml' -o -name '*.json' \) 2>/dev/null | sort
   for id in $(finished_calibrations . .); do
     find "$id" -type f ! -name '*.sqlite*' | sort
     echo "$id.time"
   done
   for made_by in */replay.made_by; do
     [[ -f $made_by ]] || continue
     replay=$(dirname "$made_by")
     echo "$made_by"
     for record in "${records[@]}"; do [[ -f $replay/$record ]] && echo "$replay/$record"; done
     find "$replay/truth" -maxdepth 1 -type f -name '*.json' 2>/dev/null | sort
     for id in $(finished_calibrations "$replay" .); do
       find "$replay/$id" -type f ! -name '*.sqlite*' | sort
       echo "$replay/$id.time"
       [[ -f $replay/$id.log ]] && echo "$replay/$id.log"
     done
   done
   return 0)
}

copy_all() {  # FROM TO: copies carried_files(FROM); prints how many were new
  local copied=0
  while read -r file; do
    if copy_once "$1/$file" "$2/$file"; then copied=$((copied + 1)); fi
  done < <(carried_files "$1")
  echo "$copied"
}

count() {  # FOLDER: "T twins, C finished calibrations"
  local twins=0 done=0
  for twin in "$1"/twins/*.toml; do
    [[ -f $twin ]] || continue
    twins=$((twins + 1))
    [[ -f $1/$(basename "$twin" .toml)/summary.json ]] && done=$((done + 1))
  done
  echo "$twins twins, $done finished calibrations"
}

case $verb in
  save)
    [[ -d $from/twins ]] || { echo "error: $from is not a blind pass folder (no twins/)" >&2; exit 2; }
    mkdir -p "$to"
    copied=$(copy_all "$from" "$to")
    echo "$(date -u +%FT%TZ) $(count "$to")" >> "$to/saves.txt"
    echo "saved $copied new files of $from into $to: $(count "$to")"
    ;;
  restore)
    mkdir -p "$to"
    copied=$(copy_all "$from" "$to")
    echo "restored $copied files of $from into $to: $(count "$to")"
    ;;
  *) usage ;;
esac
