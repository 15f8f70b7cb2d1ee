#!/bin/bash
# Makes every file in results/seeing/ (run from the repository root after building):
#   bash results/seeing/make.sh
# 2D model, scenarios/paper/cylinder.toml (cylinder 80 mm at D = 100 mm), seed 1.
set -euo pipefail
G=build/app/gapflow
OUT=results/seeing
SC=scenarios/paper/cylinder.toml
SHORT=(--set 'run.end="time_limit"' --set run.time_limit_s=4 --quiet)
rm -rf "$OUT/vtk" "$OUT"/*.png "$OUT"/*.mp4

# 1. Snapshot at t = 3 s, coloured by speed.
$G run $SC "${SHORT[@]}" --snapshot-at 3 --snapshot-dir "$OUT" > /dev/null
mv "$OUT/t0003.00s.png" "$OUT/snapshot_cylinder_t3s.png"

# 2. Snapshot of a clog (narrow gap W = 20 mm, no obstruction): the arch the clog locator sees, in red.
$G run scenarios/paper/no_obstruction_medium.toml --set bottleneck.gap_mm=20 --set 'run.end="time_limit"' \
  --set run.time_limit_s=6 --quiet --snapshot-on-clog --snapshot-dir "$OUT/clogs" > /dev/null
mv "$(ls "$OUT"/clogs/clog001_*.png)" "$OUT/snapshot_clog_w20.png"
rm -rf "$OUT/clogs"

# 3. Movie: 4 s at 25 fps, streamed to ffmpeg.
$G run $SC "${SHORT[@]}" --movie "$OUT/movie_cylinder_4s.mp4" --fps 25 --px-per-mm 0.8 > /dev/null

# 4. ParaView series (every 2 s: 3 frames) and a preview of its last frame read back by VTK.
$G run $SC "${SHORT[@]}" --vtk "$OUT/vtk" --vtk-interval 2 > /dev/null
/usr/bin/python3 scripts/vtk_preview.py "$OUT/vtk/run.pvd" 2 "$OUT/paraview_preview_t4s.png"

# 5. Live view: the page in headless Chromium, 2 s of virtual time after load.
port=18123
$G serve $SC --port $port --exit-after 60 & server=$!
trap 'kill $server 2>/dev/null || true' EXIT
for _ in $(seq 50); do curl -sf "http://127.0.0.1:$port/state" > /dev/null && break; sleep 0.2; done
sleep 4  # let the spheres settle and start to flow
profile=$(mktemp -d)
chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking \
  --disable-component-update --disable-sync --user-data-dir="$profile" --window-size=800,1000 \
  --virtual-time-budget=2000 --screenshot="$OUT/live_view.png" "http://127.0.0.1:$port/" > /dev/null 2>&1
rm -rf "$profile"
