#!/usr/bin/env bash
# The 2D convergence study (issue 15, item 1): J and clogging statistics against the time step and
# the solver iterations, the table that chooses model.box2d's defaults, and the CPU cost of each
# setting. Resumable (the studies' stores keep finished runs).
#   scripts/convergence_2d.sh [OUT_DIR]      (default results/convergence-2d; ~65 CPU-minutes)
# Writes OUT_DIR/README.md; the stores OUT_DIR/*.sqlite stay out of git.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/convergence-2d}
mkdir -p "$out"
g=build/app/gapflow
$g study studies/convergence/step_2d.toml --db "$out/step_2d.sqlite" --jobs 2
$g study studies/convergence/clogging_2d.toml --db "$out/clogging_2d.sqlite" --jobs 2
$g study studies/convergence/ablation_2d.toml --db "$out/ablation_2d.sqlite" --jobs 2

# Overlap of touching discs in the flowing pile against the step (and Box2D's slop, through the engine
# scale): one run each, walls not shaken, ParaView frames every 0.25 s into a temporary folder.
overlap_rows() {
  local tmp; tmp=$(mktemp -d)
  for s in "0.0005 1" "0.001 1" "0.002 1" "0.004 1" "0.004 4" "0.004 10"; do
    set -- $s
    $g run scenarios/paper/no_obstruction_medium.toml --quiet --set particles.count=400 --set bottleneck.gap_mm=40 \
      --set shaking.walls.enabled=false --set model.box2d.time_step_s=$1 --set model.box2d.engine_diameter=$2 \
      --vtk "$tmp/$1_$2" --vtk-interval 0.25 > /dev/null 2>&1
    /usr/bin/python3 scripts/overlap_2d.py "$tmp/$1_$2" --label "$(python3 -c "print(f'{1000 * $1:g} ms')"), engine scale $2"
  done
  rm -rf "$tmp"
}

# Cost of each setting: instructions per simulated second of one run (cachegrind without cache
# simulation: a count, the same on a loaded or a quiet machine; timed CPU seconds of single runs
# varied by +-15 % on the shared machine). The flow scenario of step_2d.toml, replicate 0; the count
# includes the 0.5 s of settling and set-up. Measured once into OUT_DIR/instructions.txt (~6 min of one core).
instructions="$out/instructions.txt"
if [ ! -s "$instructions" ]; then
  for s in "0.001 8 3" "0.001 4 3" "0.001 8 1" "0.001 4 1" "0.0015 4 1" "0.002 8 3" "0.002 4 1"; do
    set -- $s
    log=$(valgrind --tool=cachegrind --cache-sim=no --cachegrind-out-file=/dev/null "$g" run \
      scenarios/paper/no_obstruction_medium.toml --set particles.count=400 --set bottleneck.gap_mm=40 \
      --set model.box2d.time_step_s=$1 --set model.box2d.velocity_iterations=$2 \
      --set model.box2d.position_iterations=$3 2>&1)
    ir=$(echo "$log" | grep "I *refs" | sed 's/.*refs: *//; s/,//g')
    sim=$(echo "$log" | grep -o "[0-9.]* s simulated" | cut -d' ' -f1)
    echo "$1 $2 $3 $ir $sim"
  done > "$instructions.partial"
  mv "$instructions.partial" "$instructions"
fi
cost_table() {
  python3 - "$instructions" <<'PY'
import sys
rows = [l.split() for l in open(sys.argv[1]) if l.strip()]
per = {(dt, v, p): int(ir) / float(sim) for dt, v, p, ir, sim in rows}
base = per[("0.001", "8", "3")]
print("| step | iterations (velocity/position) | instructions per simulated s | relative to 1 ms, 8/3 |")
print("|---|---|---:|---:|")
for (dt, v, p), x in per.items():
    print(f"| {1000 * float(dt):g} ms | {v}/{p} | {x / 1e9:.3f} e9 | {x / base:.2f} |")
PY
}

{
  echo "# 2D convergence: time step and solver iterations"
  echo
  echo "Produced by \`scripts/convergence_2d.sh $out\` (studies \`studies/convergence/step_2d.toml\` and"
  echo "\`studies/convergence/clogging_2d.toml\`, tables by \`studies/convergence_table.py\`)."
  echo
  echo "## Flow rate (400 spheres, W = 40 mm = 5.2 d, 48 replicates per setting)"
  echo
  /usr/bin/python3 studies/convergence_table.py "$out/step_2d.sqlite" --reference reference --fit "iterations 8/3"

  echo
  echo "## Clogging (600 spheres re-injected, W = 19.375 mm = 2.5 d, unshaken, local perturbation, 8 x 40 s)"
  echo
  /usr/bin/python3 studies/convergence_table.py "$out/clogging_2d.sqlite" --avalanches --reference reference
  echo
  echo "## Why J grows with the step: one ingredient at a time (walls not shaken, 32 replicates)"
  echo
  /usr/bin/python3 studies/convergence_table.py "$out/ablation_2d.sqlite" --reference "noshake@model.box2d.time_step_s=0.0005"
  echo
  echo "Overlap of touching discs, frames 0.5-1.75 s after release (\`scripts/overlap_2d.py\`; pairs closer than"
  echo "1.02 (r_i + r_j), overlap relative to r_i + r_j):"
  echo
  echo "| run | near pairs | overlapping | mean overlap | largest |"
  echo "|---|---:|---:|---:|---:|"
  overlap_rows
  echo
  echo "## Cost per simulated second (instructions of one run, replicate 0)"
  echo
  cost_table
} > "$out/README.md.partial"
mv "$out/README.md.partial" "$out/README.md"
cat "$out/README.md"
