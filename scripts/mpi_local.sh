#!/usr/bin/env bash
# The tiny study as an MPI job (OpenMPI from Debian, 3 ranks on this machine: rank 0 hands
# out jobs and writes the store, ranks 1-2 simulate) against a local run of the same study:
# the two stores must be identical run by run (`gapflow compare`). ctest `mpi_study` (slow).
#   scripts/mpi_local.sh [path/to/gapflow]
# Exit 0 identical, 1 different or failed, 77 skipped (no mpirun, or gapflow built without MPI).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
gapflow="${1:-$here/build/app/gapflow}"
study="$here/studies/examples/tiny.toml"
command -v mpirun >/dev/null || { echo "skipped: no mpirun (apt-get install openmpi-bin libopenmpi-dev)"; exit 77; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

"$gapflow" study "$study" --db "$tmp/local.sqlite" --jobs 2 2>/dev/null
set +e
# --allow-run-as-root: CI and this machine build as root; --oversubscribe: 3 ranks on 2 cores.
mpirun --allow-run-as-root --oversubscribe -np 3 "$gapflow" study "$study" --mpi --db "$tmp/mpi.sqlite" \
  >"$tmp/mpi.log" 2>&1
rc=$?
set -e
if [ $rc -eq 2 ] && grep -q "built without MPI" "$tmp/mpi.log"; then
  echo "skipped: $(grep -m1 'built without MPI' "$tmp/mpi.log")"
  exit 77
fi
cat "$tmp/mpi.log"
[ $rc -eq 0 ] || { echo "FAIL: mpirun exited $rc"; exit 1; }
# Every run must have been simulated by a rank other than 0.
shards=$("$gapflow" export "$tmp/mpi.sqlite" --table provenance | tail -n +2 | cut -d, -f2)
echo "runs per rank:"; echo "$shards" | sort | uniq -c
if grep -qv "^mpi rank" <<< "$shards"; then echo "FAIL: a run not made by an MPI rank"; exit 1; fi
"$gapflow" compare "$tmp/local.sqlite" "$tmp/mpi.sqlite"
