#!/usr/bin/env bash
# One machine's share of a blind pass that outlives its machine (studies/blind_pass_carry.sh says
# why): puts the carry back into PASS, records the launch in CARRY/launches.txt, runs the pass's own
# command, and saves what it has finished into CARRY every SAVE_EVERY seconds and when it ends.
# Commit CARRY before the machine ends; nothing of the pass is read or printed here.
#
#   [SAVE_EVERY=300] studies/blind_pass_session.sh CARRY PASS COMMAND...
#
# e.g. (pass 22; run in the background, from the repository's root)
#   studies/blind_pass_session.sh results/calibration-blind-pass22/carry /work/pass22 \
#     env MODEL_SEEDS=per-twin TWIN_REPLICATES=20 GAPFLOW=/work/bin-p21/gapflow \
#     /usr/bin/time -v -o /work/pass22.timevN studies/calibration_blind.sh /work/pass22 2 18000 data/blind/design_v2.toml
# The launch's line names the commit and the sha256 of $GAPFLOW as the command sets it (the first
# GAPFLOW=... word of COMMAND), so a launch on another binary shows.
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 3 ]] || { echo "usage: [SAVE_EVERY=300] studies/blind_pass_session.sh CARRY PASS COMMAND..." >&2; exit 2; }
carry=${1%/}; pass=${2%/}; shift 2
save_every=${SAVE_EVERY:-300}
[[ $save_every =~ ^[0-9]+$ ]] && ((save_every >= 10)) ||
  { echo "error: SAVE_EVERY is '$save_every'; allowed: a whole number of seconds, at least 10" >&2; exit 2; }

binary="(no GAPFLOW= in the command)"
for word in "$@"; do
  if [[ $word == GAPFLOW=* ]]; then
    gapflow=${word#GAPFLOW=}
    [[ -x $gapflow ]] || { echo "error: GAPFLOW=$gapflow is not an executable" >&2; exit 2; }
    binary="$gapflow, sha256 $(sha256sum "$gapflow" | cut -c1-16)"
    break
  fi
done

if [[ -d $carry ]]; then studies/blind_pass_carry.sh restore "$carry" "$pass"; fi
mkdir -p "$carry"
launches=$(grep -c ' launch [0-9]* at ' "$carry/launches.txt" 2> /dev/null || true)
launch=$(( ${launches:-0} + 1 ))
echo "$(date -u +%FT%TZ) launch $launch at $(git rev-parse --short HEAD), binary $binary" >> "$carry/launches.txt"

save() { if [[ -d $pass/twins ]]; then studies/blind_pass_carry.sh save "$pass" "$carry" || true; fi; }
(while sleep "$save_every"; do save; done) &
saver=$!
trap 'kill "$saver" 2> /dev/null || true' EXIT
status=0
"$@" || status=$?
save
echo "$(date -u +%FT%TZ) launch $launch: the pass's command ended with exit $status" >> "$carry/launches.txt"
exit "$status"
