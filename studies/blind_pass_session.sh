#!/usr/bin/env bash
# One machine's share of a blind pass that outlives its machine (studies/blind_pass_carry.sh says
# why): puts the carry back into PASS, records the launch in CARRY/launches.txt, runs the pass's own
# command, and saves what it has finished into CARRY every SAVE_EVERY seconds and when it ends.
# Stop it before the machine ends with SIGTERM (pkill -f blind_pass_session.sh): it stops the pass,
# saves, and records the stop; then replay what the pass finished (studies/calibration_replay.sh),
# save again and commit CARRY. Nothing of the pass is read or printed here.
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
(while sleep "$save_every"; do save; done) &
saver=$!
trap 'kill "$saver" 2> /dev/null || true' EXIT
# The command in a process group of its own, so that a stop (SIGTERM or SIGINT to this script)
# reaches all of it (time, the pass's script, gapflow) and this script can still save and record.
setsid "${command[@]}" &
pass_pid=$!
stopped=0
trap 'stopped=1; kill -TERM -- "-$pass_pid" 2> /dev/null || true' TERM INT
status=0
wait "$pass_pid" || status=$?
while kill -0 "$pass_pid" 2> /dev/null; do status=0; wait "$pass_pid" || status=$?; done
kill "$saver" 2> /dev/null || true
wait "$saver" 2> /dev/null || true
save
if ((stopped)); then
  echo "$(date -u +%FT%TZ) launch $launch: stopped by a signal (the pass's command ended with exit $status)" >> "$carry/launches.txt"
else
  echo "$(date -u +%FT%TZ) launch $launch: the pass's command ended with exit $status" >> "$carry/launches.txt"
fi
exit "$status"
