#!/usr/bin/env bash
# Carries an unfinished blind pass from one machine to the next through the repository. A pass of
# 28 calibrations takes 4.5-7 h on 2 cores; a session's machine lasts less, and nothing outside the
# repository survives it. What studies/calibration_blind.sh needs to resume is small: its records
# (seed_offset, design, calibrate_options, model_seeds, twin_replicates; and settings, made_by for a
# folder of studies/form_check_power.sh, carried the same way), the twins and their
# truths, and each finished calibration (its folder and .time). Replays of the pass run as far as it
# has got (studies/calibration_replay.sh PASS DIR: PASS/DIR/) are carried the same way. The run
# stores (*.sqlite*) are not: with MODEL_SEEDS=per-twin no run is shared between calibrations, and a
# calibration cut off is begun again from scratch on the next machine (the same binary, scenario and
# seed give the same result; across two machines of one kind that is assumed, not checked here).
#
#   studies/blind_pass_carry.sh save PASS CARRY      copy what PASS has finished into CARRY
#   studies/blind_pass_carry.sh restore CARRY PASS   put CARRY back into PASS, then run the pass's command again
#
# save copies only finished calibrations (calibration_ended_well of studies/blind_cases.sh: a
# folder with summary.json and a .time that is not empty and does not say the command failed;
# /usr/bin/time creates it empty at the start and writes it when the calibration has ended;
# anything else is cut off or still running, and would be begun again anyway), and a twin only with its truth. It never removes or changes a file already there: a
# file that differs is left as it was, the rest is copied, and the save ends in an error (exit 2),
# since a pass's files are written once. Each file is copied through a temporary name, and one save
# or restore runs at a time on a pass (flock). restore works the same way in the other direction.
# Both say how many files they copied and print nothing of the files' contents: a running pass is
# not read. Each save appends a line to CARRY/saves.txt (UTC time, twins, finished calibrations, and
# how many files differed), from which the pass's wall time is bounded when its `/usr/bin/time -v`
# record was lost with a machine.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() { echo "usage: studies/blind_pass_carry.sh save PASS CARRY | restore CARRY PASS" >&2; exit 2; }
[[ $# -eq 3 ]] || usage
verb=$1; from=${2%/}; to=${3%/}
[[ -d $from ]] || { echo "error: no folder $from" >&2; exit 2; }

records=(seed_offset design calibrate_options model_seeds twin_replicates settings made_by)
source studies/blind_cases.sh   # calibration_ended_well

# copy_once SRC DST: copies SRC to DST (through a temporary name, so that DST is whole or absent)
# unless DST holds the same bytes. Returns 0 when copied, 1 when already there, 3 when DST differs
# (said on stderr; not overwritten). A copy that fails is an error (exit 2).
copy_once() {
  if [[ -e $2 ]]; then
    cmp -s "$1" "$2" && return 1
    echo "error: $2 exists and differs from $1; not overwritten" >&2
    return 3
  fi
  { mkdir -p "$(dirname "$2")" && cp -p "$1" "$2.carry-partial" && mv "$2.carry-partial" "$2"; } ||
    { echo "error: could not copy $1 to $2" >&2; exit 2; }
}

# twins_with_truth FOLDER: the ids of FOLDER/twins/*.toml whose truth is written (gapflow twin
# writes the twin, then its truth: a twin without one is still being made).
twins_with_truth() {
  for twin in "$1"/twins/*.toml; do
    [[ -f $twin ]] || continue
    id=$(basename "$twin" .toml)
    [[ -f $1/truth/$id.json ]] && echo "$id"
  done
  return 0
}

# The files of FOLDER that make a resumable pass, one path per line relative to FOLDER: its records,
# each twin with its truth (the truth first: a twin carried means its truth was), its finished
# calibrations, and of each replay in it (studies/calibration_replay.sh, a folder with
# replay.made_by) the same but its summary over the cases (remade when it ends).
carried_files() {
  (cd "$1"
   for record in "${records[@]}"; do [[ -f $record ]] && echo "$record"; done
   for id in $(twins_with_truth .); do
     echo "truth/$id.json"
     echo "twins/$id.toml"
   done
   for id in $(twins_with_truth .); do
     calibration_ended_well . "$id" || continue
     find "$id" -type f ! -name '*.sqlite*' ! -name '*.carry-partial' | sort
     echo "$id.time"
   done
   for made_by in */replay.made_by; do
     [[ -f $made_by ]] || continue
     replay=$(dirname "$made_by")
     echo "$made_by"
     for record in "${records[@]}"; do [[ -f $replay/$record ]] && echo "$replay/$record"; done
     for id in $(twins_with_truth .); do
       [[ -f $replay/truth/$id.json ]] && echo "$replay/truth/$id.json"
       calibration_ended_well "$replay" "$id" || continue
       find "$replay/$id" -type f ! -name '*.sqlite*' ! -name '*.carry-partial' | sort
       echo "$replay/$id.time"
       [[ -f $replay/$id.log ]] && echo "$replay/$id.log"
     done
   done
   return 0)
}

# copy_all FROM TO: copies carried_files(FROM) into TO, all that do not conflict; sets copied and
# conflicts.
copy_all() {
  copied=0 conflicts=0
  local file status
  while read -r file; do
    status=0
    copy_once "$1/$file" "$2/$file" || status=$?
    case $status in
      0) copied=$((copied + 1)) ;;
      3) conflicts=$((conflicts + 1)) ;;
    esac
  done < <(carried_files "$1")
}

count() {  # FOLDER: "T twins, C finished calibrations"
  local twins=0 done=0 id
  for id in $(twins_with_truth "$1"); do
    twins=$((twins + 1))
    if calibration_ended_well "$1" "$id"; then done=$((done + 1)); fi
  done
  echo "$twins twins, $done finished calibrations"
}

# One save or restore at a time on a pass (the session's periodic saves and a save by hand).
lock=${TMPDIR:-/tmp}/blind_pass_carry.$(realpath -m "$([[ $verb == save ]] && echo "$from" || echo "$to")" | md5sum | cut -c1-16).lock
exec 9> "$lock"
flock 9

case $verb in
  save)
    [[ -d $from/twins ]] || { echo "error: $from is not a blind pass folder (no twins/)" >&2; exit 2; }
    mkdir -p "$to"
    copy_all "$from" "$to"
    echo "$(date -u +%FT%TZ) $(count "$to")$( ((conflicts == 0)) || echo "; $conflicts file(s) differ, not saved")" >> "$to/saves.txt"
    echo "saved $copied new files of $from into $to: $(count "$to")"
    ;;
  restore)
    mkdir -p "$to"
    copy_all "$from" "$to"
    echo "restored $copied files of $from into $to: $(count "$to")"
    ;;
  *) usage ;;
esac
if ((conflicts > 0)); then
  echo "error: $conflicts file(s) differ between $from and $to and were left as they were" >&2
  exit 2
fi
