#!/usr/bin/env bash
# Issue 18's waiting-room map: the racing screen of studies/paper/waiting_room_map.toml on its
# --quick grid (every third value of each axis, first and last kept: 3 sizes per shape, D/d 0, 2,
# 7, 20, W/d 3, 4.26 (the paper's 33 mm), 6), 2D with the rolling contact, then its 3D check; the report goes to OUT.
#
#   studies/waiting_room_map.sh [OUT] [JOBS]     (default results/waiting-room-map, all cores)
#
# Resumable: every run is kept in results/waiting-room-map-quick/runs.sqlite (not committed:
# ~120 kB per run, nearly all of it per-sphere crossings the screen never reads); re-running the
# script continues the race where it stopped and remakes the report from the store. OUT/runs.sqlite
# is the same store without its crossing rows (scripts/slim_store.py, a few kB per run): it is
# written when the screen ends and is the one committed; when the working store is missing (a new
# checkout) the script starts from it, so a map that spans machines or sessions loses no finished
# run. The *.time file gets one line per invocation. GAPFLOW=path runs another binary (a copy, so
# that rebuilding the tree does not change the program under a running map).
set -euo pipefail
gapflow_env=${GAPFLOW:+$(realpath "$GAPFLOW")}  # before the cd: a relative path is the caller's
cd "$(dirname "$0")/.."
out=${1:-results/waiting-room-map}
jobs=${2:-$(nproc)}
gapflow=${gapflow_env:-build/app/gapflow}
study=studies/paper/waiting_room_map.toml
store=results/waiting-room-map-quick/runs.sqlite
slim=$out/runs.sqlite
mkdir -p "$out" "$(dirname "$store")"
if [[ ! -e $store && -e $slim ]]; then
  echo "starting from $slim (the committed store without crossings)"
  cp "$slim" "$store"
fi
status=0
trap 'echo "interrupted: writing the checkpoint $slim" >&2' INT  # a handler, not '': gapflow keeps its Ctrl-C
/usr/bin/time -a -f "%e s wall, %U s user CPU: screen and check" -o "$out/map.time" \
  "$gapflow" study "$study" --quick --jobs "$jobs" || status=$?
if [[ -e $store ]]; then  # also after an interruption: the checkpoint
  /usr/bin/python3 scripts/slim_store.py "$store" "$slim"
fi
[[ $status == 0 ]] || exit "$status"
"$gapflow" report "$store" --study "$study" --quick --out "$out"
