#!/usr/bin/env bash
# Run the paper's studies (studies/paper/*.toml) one after the other on all cores and
# write each report. Resumable: run it again after an interruption and finished runs
# are kept. The wall time of each study (elapsed, this machine) goes to
# results/<study>/wall_time.txt.
# Usage: studies/run_paper_studies.sh [STUDY_NAME ...]   (default: all of them, in this order)
#   names: flow_vs_distance flow_vs_gap screen_confirm clogging clogging_long cylinder_peak_3d clog_location
# The body is one function, read whole before it runs: editing this file while it runs
# cannot derail the running copy (bash otherwise reads a script as it goes).
set -euo pipefail
main() {
  cd "$(dirname "$0")/.."
  studies=("$@")
  [ ${#studies[@]} -eq 0 ] && studies=(flow_vs_distance flow_vs_gap screen_confirm clogging clogging_long cylinder_peak_3d clog_location)
  for s in "${studies[@]}"; do
    file="studies/paper/$s.toml"
    out="results/$(echo "$s" | tr _ -)"
    start=$(date +%s)
    build/app/gapflow study "$file"
    elapsed=$(( $(date +%s) - start ))
    mkdir -p "$out"
    echo "gapflow study $file: ${elapsed} s elapsed on $(nproc) cores, $(date -u +%FT%TZ) (this invocation only; a resumed study sums its invocations)" \
      >> "$out/wall_time.txt"
    build/app/gapflow report "$out" --study "$file" > /dev/null
  done
}
main "$@"; exit $?  # one line: bash never reads past it
