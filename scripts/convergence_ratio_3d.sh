#!/usr/bin/env bash
# Does the 3D step error cancel in J/J_0? (issue 15, item 1) J/J_0 of the paper's cylinder against
# Bullet's step, 60 replicates per step and arm (studies/convergence/ratio_3d.toml). Resumable.
#   scripts/convergence_ratio_3d.sh [OUT_DIR] [JOBS]   (default results/convergence-ratio-3d, 2; ~40 CPU-minutes)
# Writes OUT_DIR/README.md; the store OUT_DIR/ratio_3d.sqlite stays out of git.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/convergence-ratio-3d}
jobs=${2:-2}
mkdir -p "$out"
build/app/gapflow study studies/convergence/ratio_3d.toml --db "$out/ratio_3d.sqlite" --jobs "$jobs"
{
  echo "# 3D convergence of a ratio: J/J_0 of the paper's cylinder against the time step"
  echo
  echo "Produced by \`scripts/convergence_ratio_3d.sh $out\` (study \`studies/convergence/ratio_3d.toml\`, table by"
  echo "\`studies/convergence_ratio.py\`): 400 medium spheres, W = 40 mm = 5.2 d, the paper's shaking, the"
  echo "paper's cylinder (80 mm, centre 100 mm above the gap line) against the same board without it,"
  echo "60 replicates per step and arm, 10 solver iterations."
  echo
  /usr/bin/python3 studies/convergence_ratio.py "$out/ratio_3d.sqlite" --model 3d --reference 0.0005
} > "$out/README.md.partial"
mv "$out/README.md.partial" "$out/README.md"
cat "$out/README.md"
