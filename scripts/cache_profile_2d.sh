#!/usr/bin/env bash
# Cache behaviour of the 2D step against the particle count (issue 15, item 3), by simulation:
# valgrind's cachegrind over the step benchmark (bench/bench_step.cpp: 0.3 s warm-up + 250 timed
# steps of the flowing hopper, both counted) at each N given. Prints instructions, data references
# and D1 / last-level misses per particle-step. Cachegrind simulates L1 and the last-level cache of
# this machine only (no L2, no other tenants), so it tells work and locality apart from capacity.
#   scripts/cache_profile_2d.sh 1000 5000      (~1 min and ~4 min of one core)
set -euo pipefail
cd "$(dirname "$0")/.."
steps=550  # 300 warm-up + 250 timed steps of 1 ms
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf "| particles | instructions / particle-step | data refs / particle-step | D1 miss rate | LL data misses / particle-step |\n"
printf "|---:|---:|---:|---:|---:|\n"
for n in "$@"; do
  valgrind --tool=cachegrind --cache-sim=yes --cachegrind-out-file="$tmp/cg.$n" \
    build/bench/gapflow_bench --benchmark_filter="Step2D/particles:$n/" > /dev/null 2> "$tmp/log.$n"
  python3 - "$tmp/log.$n" "$n" "$steps" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
n, steps = int(sys.argv[2]), int(sys.argv[3])
def count(label):
    return int(re.search(label + r":\s+([\d,]+)", text).group(1).replace(",", ""))
ps = n * steps
ir, dr, d1, lld = count(r"I\s+refs"), count(r"D\s+refs"), count(r"D1\s+misses"), count(r"LLd misses")
print(f"| {n} | {ir / ps:.0f} | {dr / ps:.0f} | {100 * d1 / dr:.2f} % | {lld / ps:.3f} |")
PY
done
