#!/usr/bin/env bash
# The paper's three sphere sizes without obstruction at W = 33 mm (section III), with replicates.
# Usage: studies/paper_sizes.sh OUT_DIR MODEL(2d|3d) REPLICATES [--set key=value ...]
# Writes OUT_DIR/<size>.txt (replicate table, mean J with 95 % intervals) and OUT_DIR/command.txt.
set -euo pipefail
cd "$(dirname "$0")/.."
out=$1; model=$2; reps=$3; shift 3
mkdir -p "$out"
echo "studies/paper_sizes.sh $out $model $reps $*" > "$out/command.txt"
for size in small medium large; do
  f="$out/$size.txt"
  build/app/gapflow run "scenarios/paper/no_obstruction_$size.toml" --model "$model" --quiet \
    --replicates "$reps" "$@" > "$f.partial"
  mv "$f.partial" "$f"
  echo "$size:"; grep -E "^J_" "$f"
done
