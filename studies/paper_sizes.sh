#!/usr/bin/env bash
# The paper's three sphere sizes without obstruction at W = 33 mm (section III), with replicates.
# Usage: studies/paper_sizes.sh MODEL(2d|3d) REPLICATES [--set key=value ...]
# Writes results/paper_sizes_<model>/<size>.txt (replicate table, mean J with 95 % intervals).
set -euo pipefail
cd "$(dirname "$0")/.."
model=$1; reps=$2; shift 2
out=results/paper_sizes_$model
mkdir -p "$out"
for size in small medium large; do
  f="$out/$size.txt"
  build/app/gapflow run "scenarios/paper/no_obstruction_$size.toml" --model "$model" --quiet \
    --replicates "$reps" "$@" > "$f.partial"
  mv "$f.partial" "$f"
  echo "$size:"; grep -E "^J_" "$f"
done
