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

# CPU seconds per simulated second of one run at each setting (getrusage of the child: the stores'
# wall times include waiting on a loaded machine). The flow scenario of step_2d.toml, replicate 0.
cpu_per_sim_s() {
  python3 - "$g" "$@" <<'PY'
import re, resource, subprocess, sys
g, sets = sys.argv[1], sys.argv[2:]
cmd = [g, "run", "scenarios/paper/no_obstruction_medium.toml", "--set", "particles.count=400",
       "--set", "bottleneck.gap_mm=40"]
for s in sets:
    cmd += ["--set", s]
text = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
sim = float(re.search(r"time\s+([\d.]+) s simulated", text).group(1))
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print(f"{(r.ru_utime + r.ru_stime) / sim:.3f}")
PY
}
cost_row() {  # label, then overrides
  local label=$1; shift
  echo "| $label | $(cpu_per_sim_s "$@") |"
}

{
  echo "# 2D convergence: time step and solver iterations"
  echo
  echo "Produced by \`scripts/convergence_2d.sh $out\` (studies \`studies/convergence/step_2d.toml\` and"
  echo "\`studies/convergence/clogging_2d.toml\`, tables by \`studies/convergence_table.py\`)."
  echo
  echo "## Flow rate (400 spheres, W = 40 mm = 5.2 d, 48 replicates per setting)"
  echo
  python3 studies/convergence_table.py "$out/step_2d.sqlite" --reference reference --fit "iterations 8/3" \
    | sed 's/| CPU s per sim s | speed-up vs ref |/| wall s per sim s (loaded machine) | |/'
  echo
  echo "## Clogging (600 spheres re-injected, W = 19.375 mm = 2.5 d, unshaken, local perturbation, 8 x 40 s)"
  echo
  python3 studies/convergence_table.py "$out/clogging_2d.sqlite" --avalanches --reference reference
  echo
  echo "## CPU cost per simulated second (one run of the flow scenario, replicate 0, CPU time)"
  echo
  echo "| setting | CPU s per simulated s |"
  echo "|---|---:|"
  cost_row "reference: 0.25 ms, 16/6" model.box2d.time_step_s=0.00025 model.box2d.velocity_iterations=16 model.box2d.position_iterations=6
  cost_row "0.5 ms, 8/3" model.box2d.time_step_s=0.0005 model.box2d.velocity_iterations=8 model.box2d.position_iterations=3
  cost_row "1 ms, 8/3" model.box2d.time_step_s=0.001 model.box2d.velocity_iterations=8 model.box2d.position_iterations=3
  cost_row "1 ms, 4/3" model.box2d.time_step_s=0.001 model.box2d.velocity_iterations=4 model.box2d.position_iterations=3
  cost_row "1 ms, 8/1" model.box2d.time_step_s=0.001 model.box2d.velocity_iterations=8 model.box2d.position_iterations=1
  cost_row "1 ms, 4/1" model.box2d.time_step_s=0.001 model.box2d.velocity_iterations=4 model.box2d.position_iterations=1
  cost_row "1.5 ms, 4/1" model.box2d.time_step_s=0.0015 model.box2d.velocity_iterations=4 model.box2d.position_iterations=1
  cost_row "2 ms, 8/3" model.box2d.time_step_s=0.002 model.box2d.velocity_iterations=8 model.box2d.position_iterations=3
  cost_row "2 ms, 4/1" model.box2d.time_step_s=0.002 model.box2d.velocity_iterations=4 model.box2d.position_iterations=1
  cost_row "4 ms, 8/3" model.box2d.time_step_s=0.004 model.box2d.velocity_iterations=8 model.box2d.position_iterations=3
} > "$out/README.md.partial"
mv "$out/README.md.partial" "$out/README.md"
cat "$out/README.md"
