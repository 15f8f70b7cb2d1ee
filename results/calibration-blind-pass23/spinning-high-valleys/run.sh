#!/bin/bash
# Pass 23's spinning-high, two regions on direct simulation (the method of
# results/calibration-blind-pass15/spinning-high-valleys/): each calibration stopped once its baseline line is logged.
#   results/calibration-blind-pass23/spinning-high-valleys/run.sh [OUT]    (default /tmp/spinning-high-valleys)
# GAPFLOW: the binary (default build/app/gapflow); the store, outputs and logs go to OUT.
set -u
here=$(cd "$(dirname "$0")" && pwd)
gapflow=$(realpath "${GAPFLOW:-$here/../../../build/app/gapflow}")
out=${1:-/tmp/spinning-high-valleys}
mkdir -p "$out"
for R in A B; do
  [[ -f $out/log$R.done ]] && continue
  "$gapflow" calibrate "$here/$R.toml" --model 2d --out "$out/out$R" --db "$out/sh.sqlite" --jobs 1 --no-plots \
    --max-effects 0 > "$out/log$R.txt" 2>&1 &
  pid=$!
  while kill -0 $pid 2> /dev/null; do
    if grep -q "^calibrate: baseline particles.friction_particle=" "$out/log$R.txt"; then kill $pid; break; fi
    sleep 5
  done
  wait $pid 2> /dev/null
  touch "$out/log$R.done"
done
echo "logs in $out (log*.txt)"
