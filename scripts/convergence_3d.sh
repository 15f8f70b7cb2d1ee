#!/usr/bin/env bash
# The 3D convergence study (issue 15, item 1): J against Bullet's step and solver iterations,
# against a reference at a quarter of the default step with twice the iterations. Resumable.
#   scripts/convergence_3d.sh [OUT_DIR]      (default results/convergence-3d; ~35 CPU-minutes)
# Writes OUT_DIR/README.md; the store OUT_DIR/step_3d.sqlite stays out of git.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/convergence-3d}
mkdir -p "$out"
build/app/gapflow study studies/convergence/step_3d.toml --db "$out/step_3d.sqlite" --jobs 2
{
  echo "# 3D convergence: time step and solver iterations"
  echo
  echo "Produced by \`scripts/convergence_3d.sh $out\` (study \`studies/convergence/step_3d.toml\`, table by"
  echo "\`studies/convergence_table.py\`): 400 medium spheres, W = 40 mm = 5.2 d, the paper's shaking,"
  echo "20 replicates per setting."
  echo
  /usr/bin/python3 studies/convergence_table.py "$out/step_3d.sqlite" --model 3d --reference reference --fit "iterations 10"
} > "$out/README.md.partial"
mv "$out/README.md.partial" "$out/README.md"
cat "$out/README.md"
