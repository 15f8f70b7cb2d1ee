#!/usr/bin/env bash
# A calibration as an MPI job (3 ranks on this machine: rank 0 runs the loop and writes the
# store, ranks 1-2 simulate) against the same calibration run locally, on a twin of the tiny
# design with a planted drag: the stores must be identical run by run (`gapflow compare`) and
# the summaries equal apart from wall times. ctest `mpi_calibrate` (slow).
#   scripts/mpi_calibrate_local.sh [path/to/gapflow]
# Exit 0 identical, 1 different or failed, 77 skipped (no mpirun, or gapflow built without MPI).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
gapflow="${1:-$here/build/app/gapflow}"
design="$here/data/examples/tiny_design.toml"
command -v mpirun >/dev/null || { echo "skipped: no mpirun (apt-get install openmpi-bin libopenmpi-dev)"; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

"$gapflow" twin "$design" --out "$tmp/twin.toml" --truth "$tmp/truth.json" --effect linear_drag=5 --seed 21 \
  --replicates 6 --jobs 2 --db "$tmp/twin.sqlite" 2>/dev/null
"$gapflow" calibrate "$tmp/twin.toml" --out "$tmp/local" --db "$tmp/local.sqlite" --jobs 2 --no-plots 2>/dev/null
set +e
# --allow-run-as-root: CI and this machine build as root; --oversubscribe: 3 ranks on 2 cores.
mpirun --allow-run-as-root --oversubscribe -np 3 "$gapflow" calibrate "$tmp/twin.toml" --mpi --out "$tmp/mpi" \
  --db "$tmp/mpi.sqlite" --no-plots >"$tmp/mpi.log" 2>&1
rc=$?
set -e
if [ $rc -eq 2 ] && grep -q "built without MPI" "$tmp/mpi.log"; then
  echo "skipped: $(grep -m1 'built without MPI' "$tmp/mpi.log")"
  exit 77
fi
grep -v "runs/min" "$tmp/mpi.log" || true
[ $rc -eq 0 ] || { echo "FAIL: mpirun exited $rc"; exit 1; }
shards=$("$gapflow" export "$tmp/mpi.sqlite" --table provenance | tail -n +2 | cut -d, -f2)
echo "runs per rank:"; echo "$shards" | sort | uniq -c
if grep -qv "^mpi rank" <<< "$shards"; then echo "FAIL: a run not made by an MPI rank"; exit 1; fi
"$gapflow" compare "$tmp/local.sqlite" "$tmp/mpi.sqlite"
/usr/bin/python3 - "$tmp/local/summary.json" "$tmp/mpi/summary.json" <<'PY'
import json, sys
a, b = (json.load(open(f)) for f in sys.argv[1:3])
for k in ("wall_seconds", "cpu_seconds", "runs_simulated", "runs_reused", "run_seconds"):  # cost, not result
    a.pop(k, None); b.pop(k, None)
def differences(x, y, where="summary"):
    """The paths at which two JSON values differ, for a failure that says where."""
    if isinstance(x, dict) and isinstance(y, dict):
        return [d for k in sorted(set(x) | set(y)) for d in differences(x.get(k), y.get(k), f"{where}.{k}")]
    if isinstance(x, list) and isinstance(y, list) and len(x) == len(y):
        return [d for i, (u, v) in enumerate(zip(x, y)) for d in differences(u, v, f"{where}[{i}]")]
    return [] if x == y else [f"{where}: local {json.dumps(x)[:80]}, MPI {json.dumps(y)[:80]}"]
if a != b:
    print("FAIL: the MPI calibration's summary differs from the local one:")
    print("\n".join(differences(a, b)[:20])); sys.exit(1)
print(f"summaries equal: verdict '{a['verdict']}', effects {[e['effect'] for e in a['effects']]}")
PY
