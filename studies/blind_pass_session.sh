#!/usr/bin/env bash
# One machine's share of a blind pass that outlives its machine (studies/blind_pass_carry.sh says
# why): puts the carry back into PASS, records the launch in CARRY/launches.txt, runs the pass's own
# command, and saves what it has finished into CARRY every SAVE_EVERY seconds and when it ends.
# Stop it before the machine ends with SIGTERM (kill -TERM "$(cat PASS.session-pid)"): it stops the
# pass's whole command, waits for it, saves, records the stop, and removes PASS.session-pid. Then
# replay what the pass finished (studies/calibration_replay.sh), save again and commit CARRY.
# Nothing of the pass is read or printed here.
#
#   [SAVE_EVERY=300] [ALLOW_OTHER_BINARY=1] studies/blind_pass_session.sh CARRY PASS COMMAND...
#
# e.g. (pass 22; run in the background, from the repository's root)
#   studies/blind_pass_session.sh results/calibration-blind-pass22/carry /work/pass22 \
#     env MODEL_SEEDS=per-twin TWIN_REPLICATES=20 GAPFLOW=/work/bin-p21/gapflow \
#     /usr/bin/time -v -o '/work/pass22.timev{launch}' studies/calibration_blind.sh /work/pass22 2 18000 data/blind/design_v2.toml
# {launch} in COMMAND's words becomes the launch's number. The launch's line names the commit and
# the sha256 of the binary the command names (its first GAPFLOW=... word); a binary whose sha256
# differs from the last launch's is refused (exit 2) unless ALLOW_OTHER_BINARY=1, so that one pass
# is not made by two binaries unnoticed. A save that fails is logged in CARRY/saves.txt, which is
# committed, since the pass's own log cannot be read while it runs.
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 3 ]] || { echo "usage: [SAVE_EVERY=300] studies/blind_pass_session.sh CARRY PASS COMMAND..." >&2; exit 2; }
carry=${1%/}; pass=${2%/}; shift 2
# A stop before the command runs ends the session at the next step; once it runs, it stops the
# command's whole process group.
stopped=0 pass_pid=""
trap 'stopped=1; if [[ -n $pass_pid ]]; then kill -TERM -- "-$pass_pid" 2> /dev/null || true; fi' TERM INT
save_every=${SAVE_EVERY:-300}
[[ $save_every =~ ^[0-9]+$ ]] && ((save_every >= 10)) ||
  { echo "error: SAVE_EVERY is '$save_every'; allowed: a whole number of seconds, at least 10" >&2; exit 2; }

sha=""
binary="(no GAPFLOW= in the command)"
for word in "$@"; do
  if [[ $word == GAPFLOW=* ]]; then
    gapflow=${word#GAPFLOW=}
    [[ -x $gapflow ]] || { echo "error: GAPFLOW=$gapflow is not an executable" >&2; exit 2; }
    sha=$(sha256sum "$gapflow" | cut -c1-16)
    binary="$gapflow, sha256 $sha"
    break
  fi
done
last_sha=$( (grep ' launch [0-9]* at ' "$carry/launches.txt" 2> /dev/null || true) | tail -1 |
  sed -n 's/.*sha256 \([0-9a-f]\{16\}\).*/\1/p')
if [[ -n $last_sha && $sha != "$last_sha" && ${ALLOW_OTHER_BINARY:-0} != 1 ]]; then
  echo "error: the last launch in $carry/launches.txt ran a binary of sha256 $last_sha, this one ${sha:-unknown};" \
    "set ALLOW_OTHER_BINARY=1 to run it anyway (the launch's line records it)" >&2
  exit 2
fi

if [[ -d $carry ]]; then studies/blind_pass_carry.sh restore "$carry" "$pass"; fi
mkdir -p "$carry"
launches=$(grep -c ' launch [0-9]* at ' "$carry/launches.txt" 2> /dev/null || true)
launch=$(( ${launches:-0} + 1 ))
echo "$(date -u +%FT%TZ) launch $launch at $(git rev-parse --short HEAD), binary $binary" >> "$carry/launches.txt"
command=("${@//\{launch\}/$launch}")

save() {
  [[ -d $pass/twins ]] || return 0
  local status=0
  studies/blind_pass_carry.sh save "$pass" "$carry" || status=$?
  if ((status != 0)); then echo "$(date -u +%FT%TZ) save failed (exit $status)" >> "$carry/saves.txt"; fi
}
# The saver sleeps in a child it kills when stopped, so that no sleep outlives it.
(trap 'kill "$nap" 2> /dev/null; exit 0' TERM
 while sleep "$save_every" & nap=$!; wait "$nap"; do save; done) &
saver=$!
trap 'kill "$saver" 2> /dev/null || true; rm -f "$pass.session-pid"' EXIT
echo "$$" > "$pass.session-pid"   # beside PASS, not in it: `kill -TERM $(cat PASS.session-pid)` stops this
record_end() {  # HOW: the launch's end line
  echo "$(date -u +%FT%TZ) launch $launch: $1" >> "$carry/launches.txt"
}
if ((stopped)); then record_end "stopped by a signal before its command ran"; exit 143; fi
# The command in a process group of its own, so that a stop (SIGTERM or SIGINT to this script)
# reaches all of it (time, the pass's script, gapflow) and this script can still save and record.
setsid "${command[@]}" &
pass_pid=$!
if ((stopped)); then kill -TERM -- "-$pass_pid" 2> /dev/null || true; fi   # a stop in between
# wait returns early when a stop's trap runs: wait until the command has ended, then take its own status
while kill -0 "$pass_pid" 2> /dev/null; do wait "$pass_pid" || true; done
status=0; wait "$pass_pid" || status=$?
# gapflow cancels at the end of a step: wait for the whole group (2 min, then KILL) before saving.
for _ in $(seq 120); do kill -0 -- "-$pass_pid" 2> /dev/null || break; sleep 1; done
kill -KILL -- "-$pass_pid" 2> /dev/null || true
kill "$saver" 2> /dev/null || true
wait "$saver" 2> /dev/null || true
save
if ((stopped)); then
  record_end "stopped by a signal (the pass's command ended with exit $status)"
else
  record_end "the pass's command ended with exit $status"
fi
exit "$status"
