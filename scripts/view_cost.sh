#!/bin/bash
# CPU time (user+sys, s, ffmpeg included) of each run output against the bare run (README, "Seeing a run"):
# 2D, scenarios/paper/cylinder.toml, 6 s simulated (run.end=time_limit), seed 1; 3 repetitions.
# Usage (from the repository root, after building): bash scripts/view_cost.sh
set -u
G=build/app/gapflow
tmp=$(mktemp -d)
t() {
  /usr/bin/time -f "%U %S" -o "$tmp/tm" $G run scenarios/paper/cylinder.toml --set 'run.end="time_limit"' \
    --set run.time_limit_s=6 --quiet "$@" > /dev/null 2>&1
  awk '{print $1+$2}' "$tmp/tm"
}
for rep in 1 2 3; do
  echo "bare $(t)"
  echo "hook_only $(t --snapshot-at 1000 --snapshot-dir "$tmp/s")"
  echo "snapshots_6 $(t --snapshot-at 1,2,3,4,5,6 --snapshot-dir "$tmp/s")"
  echo "vtk_every_0.1s $(t --vtk "$tmp/vtk")"
  echo "movie_25fps $(t --movie "$tmp/m.mp4")"
done
rm -rf "$tmp"
