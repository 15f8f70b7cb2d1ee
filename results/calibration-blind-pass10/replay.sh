#!/usr/bin/env bash
# Pass 10's 27 calibrations run again by the current binary on a copy of the pass's store
# (studies/calibration_replay.sh: the same twins and seeds, the pass's runs reused). Made for
# 067155a (the surface fit's second start), to see what the change does to the pass's verdicts.
#
#   GAPFLOW=<binary> results/calibration-blind-pass10/replay.sh [JOBS] [DIR]
#
# DIR (default replay) names the output folder under the pass: replay/ is 067155a's replay,
# replay-contenders/ the one made for 2e95302 (contenders fitted in full, responses measured
# again near the fit). A DIR that exists is resumed (same binary and options) or refused: delete it to
# make it again.
set -euo pipefail
cd "$(dirname "$0")/../.."
exec studies/calibration_replay.sh results/calibration-blind-pass10 "${2:-replay}" "${1:-$(nproc)}"
