#!/usr/bin/env bash
# The scale numbers of README "Running a study on a cluster", into results/cluster_scale/:
#   merge_10k.txt   gapflow merge of synthetic stores: 10^4 runs in 64 shards, crossings per run as in the
#                   committed paper stores (bench/merge_scale.cpp), timed on this machine
#   plan_time.txt   how long a share takes to expand the job list (`gapflow study --plan`), per job
#   scale.md        cost per run of each committed study (results/*/runs.sqlite, wall_time_s) and the
#                   projected wall time of three workloads on 2, 64 and 1000 cores (scripts/cluster_scale.py)
#   scripts/cluster_scale.sh [build dir]     (~2 min on 2 cores; writes ~1.7 GB in a temp folder, then removes it)
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
out=results/cluster_scale
mkdir -p "$out"
crossings=$(python3 - <<'PY'
import glob, sqlite3
runs = crossings = 0
for f in glob.glob('results/*/runs.sqlite'):
    c = sqlite3.connect(f'file:{f}?mode=ro', uri=True)
    runs += c.execute('select count(*) from runs').fetchone()[0]
    crossings += c.execute('select count(*) from crossings').fetchone()[0]
print(round(crossings / runs))
PY
)
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
{
  echo "# $build/bench/gapflow_merge_scale --runs 10000 --shards 64 --crossings $crossings (mean of results/*/runs.sqlite)"
  echo "# $(date -u +%FT%TZ), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg), gapflow $(git describe --always --dirty)"
  "$build/bench/gapflow_merge_scale" --runs 10000 --shards 64 --crossings "$crossings" --dir "$tmp/merge"
} | tee "$out/merge_10k.txt"
{
  echo "# $build/app/gapflow study studies/paper/flow_vs_distance.toml --plan, 5 times"
  jobs=$("$build/app/gapflow" study studies/paper/flow_vs_distance.toml --plan | wc -l)
  start=$(date +%s.%N)
  for _ in 1 2 3 4 5; do "$build/app/gapflow" study studies/paper/flow_vs_distance.toml --plan >/dev/null; done
  end=$(date +%s.%N)
  echo "jobs=$jobs"
  python3 -c "print(f'plan_ms_per_job={($end - $start) / 5 / $jobs * 1000:.3f}')"
} | tee "$out/plan_time.txt"
python3 scripts/cluster_scale.py results "$out" > "$out/scale.md"
cat "$out/scale.md"
