#!/usr/bin/env bash
# Pass 24's scoring, once all 28 calibrations have ended (results/calibration-blind-pass24/PREREGISTRATION.md):
# a control replay with rule 5 off on the pass's store and binary (every run reused: the loop as it would
# have decided without the rule), then the copy, the pass's counts, the pooled counts with passes 10, 12-21
# and 23, and the comparison of the control with the pass (expectation 10).
#
#   studies/score_pass24.sh LAUNCH_TIMEV [ONLY]
#
# LAUNCH_TIMEV: the /usr/bin/time record of the launch that finished the pass (/work/pass24.timevN).
# ONLY: the twins this machine's store holds runs of, when the pass was carried between machines (the
# control replays only those; a calibration replayed without its runs would simulate them again).
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 1 && -f $1 ]] || { echo "usage: studies/score_pass24.sh LAUNCH_TIMEV [ONLY]" >&2; exit 2; }
timev=$1
P=results/calibration-blind-pass24
[[ -x /work/bin-p24/gapflow ]] || { echo "error: /work/bin-p24/gapflow missing (see $P/carry/README.md)" >&2; exit 2; }
(( $(ls /work/pass24/*/summary.json | wc -l) == 28 )) || { echo "error: pass 24 has not ended" >&2; exit 2; }
if [[ $# -ge 2 ]]; then export ONLY=$2; fi
GAPFLOW=/work/bin-p24/gapflow studies/calibration_replay.sh /work/pass24 replay-alternatives-off 2 --alternatives 0
unset ONLY
studies/blind_pass_copy.sh /work/pass24 $P "$timev"
/usr/bin/python3 calibrate/visibility_ceiling.py --gates --by-case $P > $P/gates.txt
/usr/bin/python3 calibrate/replay_compare.py $P $P > $P/size_errors.txt
passes=$(printf 'results/calibration-blind-pass%s ' 10 12 13 14 15 16 17 18 19 20 21 23 24)
/usr/bin/python3 calibrate/visibility_ceiling.py --by-case $passes > $P/pooled_passes_10_12-21_23-24.txt
/usr/bin/python3 calibrate/visibility_ceiling.py --gates --by-case $passes > $P/pooled_gates_10_12-21_23-24.txt
/usr/bin/python3 calibrate/blind_summary.py $P/replay-alternatives-off > /dev/null
/usr/bin/python3 calibrate/pass_counts.py $P $P/replay-alternatives-off > $P/pass_counts.txt   # expectations 8, 9
# Expectation 10: the control (rule off) as BEFORE, the pass (rule on) as AFTER.
/usr/bin/python3 calibrate/alternatives_replay_compare.py $P/replay-alternatives-off $P > $P/replay-alternatives-off/compare.txt ||
  echo "expectation 10: differences beyond rule 5: see $P/replay-alternatives-off/compare.txt"
# Expectation 11: where an alternative is named and the drag's law is not established, and no failed test
# is said first, the verdict ends with the law's reservation.
/usr/bin/python3 calibrate/reservations_check.py $P/cases.csv > $P/reservations.txt
echo scored
