#!/usr/bin/env bash
# Pass 23's scoring, once all 28 calibrations have ended (results/calibration-blind-pass23/PREREGISTRATION.md
# and ALTERNATIVES_PREREGISTRATION.md): the rule-5 replay first (on the pass's store), then the copy, the
# pass's counts, the pooled counts with passes 10 and 12-21, and the replays' comparisons and summaries (a
# control with the rule off on the same binary, then the rule: A1a and A1b of the pre-registration's addendum).
#
#   studies/score_pass23.sh LAUNCH_TIMEV [ONLY]
#
# LAUNCH_TIMEV: the /usr/bin/time record of the launch that finished the pass (/work/pass23.timevN).
# ONLY: the twins this machine's store holds runs of, when the pass was carried between machines (the
# replay takes only those; ALTERNATIVES_PREREGISTRATION.md). Needs /work/bin-alt/gapflow, built at the
# commit the pre-registration's addendum names, in /work/wt-alt.
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 1 && -f $1 ]] || { echo "usage: studies/score_pass23.sh LAUNCH_TIMEV [ONLY]" >&2; exit 2; }
timev=$1
P=results/calibration-blind-pass23
[[ -x /work/bin-alt/gapflow ]] || { echo "error: /work/bin-alt/gapflow missing (see $P/carry/README.md)" >&2; exit 2; }
(( $(ls /work/pass23/*/summary.json | wc -l) == 28 )) || { echo "error: pass 23 has not ended" >&2; exit 2; }
if [[ $# -ge 2 ]]; then export ONLY=$2; fi
GAPFLOW=/work/bin-alt/gapflow studies/calibration_replay.sh /work/pass23 replay-alternatives-off 2 --alternatives 0
GAPFLOW=/work/bin-alt/gapflow studies/calibration_replay.sh /work/pass23 replay-alternatives 2 --alternatives 2
unset ONLY
studies/blind_pass_copy.sh /work/pass23 $P "$timev"
/usr/bin/python3 calibrate/visibility_ceiling.py --gates --by-case $P > $P/gates.txt
/usr/bin/python3 calibrate/replay_compare.py $P $P > $P/size_errors.txt
passes=$(printf 'results/calibration-blind-pass%s ' 10 12 13 14 15 16 17 18 19 20 21 23)
/usr/bin/python3 calibrate/visibility_ceiling.py --by-case $passes > $P/pooled_passes_10_12-21_23.txt
/usr/bin/python3 calibrate/visibility_ceiling.py --gates --by-case $passes > $P/pooled_gates_10_12-21_23.txt
for r in replay-alternatives-off replay-alternatives; do /usr/bin/python3 calibrate/blind_summary.py $P/$r > /dev/null; done
# A1a: the control (rule off, same binary) against the pass; A1b: the rule against the control.
/usr/bin/python3 calibrate/alternatives_replay_compare.py $P $P/replay-alternatives-off > $P/replay-alternatives-off/compare.txt ||
  echo "A1a: the control differs from the pass: see $P/replay-alternatives-off/compare.txt"
/usr/bin/python3 calibrate/alternatives_replay_compare.py --pass23-wording $P/replay-alternatives-off $P/replay-alternatives \
  > $P/replay-alternatives/compare.txt ||
  echo "A1b: differences beyond rule 5: see $P/replay-alternatives/compare.txt"
echo scored
