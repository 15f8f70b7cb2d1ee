#!/usr/bin/env bash
# Cost per answer (issue 15, item 6): CPU-seconds to estimate J_0 to +-2 % (95 %) at the paper's
# medium point, and to decide whether an obstruction point differs from J_0 by 3 %, for the
# protocol the shipped scenarios use today (full discharge, J_paper), 2D.
#   scripts/cost_per_answer.sh [OUT_DIR]      (default results/cost-per-answer; resumable)
# Runs bench/cost_per_answer.toml into OUT_DIR/runs.sqlite (48 runs, ~8 CPU-minutes), measures the
# CPU of one run of each point (getrusage of the child; the store's wall times include waiting on
# a loaded machine), and writes OUT_DIR/README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/cost-per-answer}
mkdir -p "$out"
db="$out/runs.sqlite"
build/app/gapflow study bench/cost_per_answer.toml --db "$db" --jobs 2

cpu_of_run() {  # CPU seconds (user + system) of one `gapflow run` of SCENARIO
  python3 - "$1" <<'PY'
import resource, subprocess, sys
subprocess.run(["build/app/gapflow", "run", sys.argv[1], "--quiet"], check=True, stdout=subprocess.DEVNULL)
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print(f"{r.ru_utime + r.ru_stime:.2f}")
PY
}
cpu0=$(cpu_of_run scenarios/paper/no_obstruction_medium.toml)
cpu1=$(cpu_of_run scenarios/paper/cylinder.toml)
cpu=$(python3 -c "print(f'{($cpu0 + $cpu1) / 2:.2f}')")

{
  echo "# Cost per answer, 2D, the paper's medium point"
  echo
  echo "Produced by \`scripts/cost_per_answer.sh $out\` (study \`bench/cost_per_answer.toml\`: 24 replicates"
  echo "of the paper's medium discharge without an obstruction and with the paper's cylinder, same seeds)."
  echo "CPU per run measured on one run of each point: $cpu0 s (no obstruction), $cpu1 s (cylinder);"
  echo "the table uses their mean. Ranges in brackets: the 95 % interval of the cost from the uncertainty"
  echo "of the run-to-run spread (24 runs)."
  echo
  echo "| protocol | J_0 and run-to-run spread | CPU s per run | J_0 to ±2 % (95 %) | obstruction point | decide a 3 % difference (5 %, power 80 %) |"
  echo "|---|---|---:|---|---|---|"
  /usr/bin/python3 scripts/cost_per_answer.py "$db" --baseline none --point cylinder --cpu-per-run "$cpu" \
    --label "full discharge, J_paper (default step)"
} > "$out/README.md.partial"
mv "$out/README.md.partial" "$out/README.md"
cat "$out/README.md"
