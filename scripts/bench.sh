#!/usr/bin/env bash
# Build the benchmark suite, run it and compare with the committed baseline.
#
#   scripts/bench.sh                    full suite, 5 repetitions (~10 min on 2 cores, measured at load 5-7)
#   scripts/bench.sh --quick            a few benchmarks, 4 repetitions (~3 min)
#   scripts/bench.sh --large            also the opt-in 3D runs at 10000 and 20000 particles
#   scripts/bench.sh --filter REGEX     only benchmarks matching REGEX (Google Benchmark filter)
#   scripts/bench.sh --strict           exit 1 when a slowdown or a physics change is flagged
#   scripts/bench.sh --update-baseline  after the run, make it the baseline (bench/baselines/)
#   scripts/bench.sh --no-build         use the existing build-bench/
#
# Writes bench/results/latest.json (every repetition plus mean/median/stddev/cv),
# latest.load.txt (uptime before and after: other jobs slow the numbers down),
# compare.txt (compare.py's table with its Mann-Whitney U test) and compare.json.
# Without --strict the exit status is 0 even when something is flagged: timings
# on a shared machine are advisory.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
build="$root/build-bench"
results="$root/bench/results"
baselines="$root/bench/baselines"
# Debian's compare.py needs Debian's scipy/numpy: call the system interpreter,
# not whatever python3 comes first on PATH (e.g. a pyenv without scipy).
py=/usr/bin/python3
compare=/usr/share/benchmark/compare.py

command_line="scripts/bench.sh $*"
quick=0 large=0 strict=0 update=0 build_it=1 filter=""
while [[ $# -gt 0 ]]; do
  case "$1" in
    --quick) quick=1 ;;
    --large) large=1 ;;
    --strict) strict=1 ;;
    --update-baseline) update=1 ;;
    --no-build) build_it=0 ;;
    --filter) filter="$2"; shift ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "bench.sh: unknown option '$1' (see --help)" >&2; exit 2 ;;
  esac
  shift
done

if [[ $build_it -eq 1 ]]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build" --target gapflow_bench -j "$(nproc)"
fi

reps=5
# Names carry "/iterations:N" (fixed step counts), hence the "/" after each size.
if [[ $quick -eq 1 ]]; then
  # 4 repetitions, not 3: with 3 against the baseline's runs the U test's
  # smallest p-value is too large to ever flag anything at alpha = 0.05.
  reps=4
  [[ -z "$filter" ]] && filter='Step2D/particles:(500|2000)/|Step3D/particles:(500|2000)/|Measurement2D|Study|Discharge2D'
fi
if [[ $large -eq 1 ]]; then
  # An explicit filter replaces the default one that leaves "Large" out.
  if [[ -n "$filter" ]]; then filter="$filter|Step3DLarge"; else filter='.'; fi
fi

mkdir -p "$results"
args=(--benchmark_repetitions=$reps
      # Not --benchmark_report_aggregates_only: the file must keep every
      # repetition, which compare.py's U test needs; the console shows aggregates.
      --benchmark_display_aggregates_only=true
      --benchmark_out="$results/latest.json" --benchmark_out_format=json)
# Without a filter the suite's main leaves out the opt-in benchmarks ("Large").
[[ -n "$filter" ]] && args+=(--benchmark_filter="$filter")

# Pin to the machine's cores (all of them: Study/workers:2 needs two).
cores="0-$(( $(nproc) - 1 ))"
{
  echo "command: $command_line"
  echo "cores: $cores ($(nproc)), $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
  echo "before: $(date -Is) $(uptime)"
} > "$results/latest.load.txt"
taskset -c "$cores" "$build/bench/gapflow_bench" "${args[@]}"
echo "after:  $(date -Is) $(uptime)" >> "$results/latest.load.txt"
cat "$results/latest.load.txt"

status=0
if [[ -f "$baselines/baseline.json" ]]; then
  echo
  echo "=== compare.py benchmarks bench/baselines/baseline.json bench/results/latest.json ==="
  "$py" "$compare" -a --no-color -d "$results/compare.json" benchmarks \
    "$baselines/baseline.json" "$results/latest.json" | tee "$results/compare.txt"
  echo
  "$py" "$root/bench/compare_gate.py" "$results/compare.json" \
    "$baselines/baseline.json" "$results/latest.json" || status=$?
else
  echo "no baseline yet (bench/baselines/baseline.json): run with --update-baseline"
fi

if [[ $update -eq 1 ]]; then
  mkdir -p "$baselines"
  cp "$results/latest.json" "$baselines/baseline.json"
  cp "$results/latest.load.txt" "$baselines/baseline.load.txt"
  echo "baseline updated: bench/baselines/baseline.json (load: bench/baselines/baseline.load.txt)"
fi

if [[ $status -ne 0 && $strict -eq 1 ]]; then
  echo "bench.sh --strict: flagged (see above)" >&2
  exit 1
fi
exit 0
