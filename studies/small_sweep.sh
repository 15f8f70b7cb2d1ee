#!/usr/bin/env bash
# One scenario key swept over values, each value run with replicates, on the small
# reference scenario (400 medium spheres, W = 40 mm = 5.2 d: never clogs).
# Usage: studies/small_sweep.sh OUT_DIR MODEL(2d|3d) REPLICATES KEY VALUE...
# Writes OUT_DIR/<key>=<value>.txt: the replicate table and mean J with 95 % intervals.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1; model=$2; reps=$3; key=$4; shift 4
mkdir -p "$out"
for v in "$@"; do
  f="$out/$key=$v.txt"
  build/app/gapflow run scenarios/paper/no_obstruction_medium.toml --model "$model" --quiet \
    --set particles.count=400 --set bottleneck.gap_mm=40 --set "$key=$v" \
    --replicates "$reps" > "$f.partial"
  mv "$f.partial" "$f"
  echo "$key = $v:"; grep -E "^J_" "$f"
done
