#!/usr/bin/env bash
# Pass 10's 27 calibrations run again by the current binary on a copy of the pass's store: the same
# twins, the same seeds; runs the pass made are reused, new parameter values are simulated into the
# copy. Writes DIR/<case>/ (each calibration's report) and DIR/report.md, cases.csv by
# blind_summary.py (with a copy of the pass's truth). Made for 067155a (the surface fit's second
# start), to see what the change does to the pass's verdicts.
#
#   GAPFLOW=<binary> results/calibration-blind-pass10/replay.sh [JOBS] [DIR]
#
# DIR (default replay) names the output folder under the pass: replay/ is 067155a's replay,
# replay-contenders/ the one made for 2e95302 (contenders fitted in full, responses measured
# again near the fit).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=results/calibration-blind-pass10
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
jobs=${1:-$(nproc)}
dir=$out/${2:-replay}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$out/runs.sqlite" "$work/runs.sqlite"
rm -rf "$dir" && mkdir -p "$dir"
cp -r "$out/truth" "$out/design" "$out/seed_offset" "$dir/"   # what the summary reads
for twin in "$out"/twins/*.toml; do
  id=$(basename "$twin" .toml)
  "$gapflow" calibrate "$twin" --model 2d --out "$dir/$id" --db "$work/runs.sqlite" \
    --jobs "$jobs" --no-plots > /dev/null 2>&1
done
/usr/bin/python3 calibrate/blind_summary.py "$dir" > /dev/null
