#!/usr/bin/env bash
# Issue 18's waiting-room map: the racing screen of studies/paper/waiting_room_map.toml on its
# --quick grid (every third value of each axis, first and last kept: 3 sizes per shape, D/d 0, 2,
# 7, 20, W/d 3, 5, 6), 2D with the rolling contact, then its 3D check; the report goes to OUT.
#
#   studies/waiting_room_map.sh [OUT] [JOBS]     (default results/waiting-room-map, all cores)
#
# Resumable: every run is kept in results/waiting-room-map-quick/runs.sqlite (not committed:
# ~120 kB per run); re-running the script continues the race where it stopped and remakes the
# report from the store. The *.time file gets one line per invocation.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/waiting-room-map}
jobs=${2:-$(nproc)}
gapflow=build/app/gapflow
study=studies/paper/waiting_room_map.toml
store=results/waiting-room-map-quick/runs.sqlite
mkdir -p "$out"
/usr/bin/time -a -f "%e s wall, %U s user CPU: screen and check" -o "$out/map.time" \
  "$gapflow" study "$study" --quick --jobs "$jobs"
"$gapflow" report "$store" --study "$study" --quick --out "$out"
