#!/usr/bin/env bash
# Where across the gap the spheres leave, with and without the waiting-room map's obstructions at
# D 7 d (results/waiting-room-map/README.md, "Why J rises"): scripts/gap_profile.py on the map's
# working store, the 2D confirmation runs (replicates 12-21) and the 3D check runs (22-31).
#
#   scripts/waiting_room_gap_profile.sh [STORE] > results/waiting-room-map/gap_profile.md
#
# STORE (default results/waiting-room-map-quick/runs.sqlite) must still hold its crossing rows:
# the committed slim store (results/waiting-room-map/runs.sqlite) has none, and a fresh checkout
# gets them back only by running the map from an empty working store (studies/waiting_room_map.sh
# after moving the slim copy away: the whole map again).
set -euo pipefail
cd "$(dirname "$0")/.."
store=${1:-results/waiting-room-map-quick/runs.sqlite}
none="none=none:"
a4="A 4 d, D 7 d=A:side_mm=31.0, obstruction.distance_mm=54.25"
c4="cylinder 4 d, D 7 d=cylinder:diameter_mm=31.0, obstruction.distance_mm=54.25"
echo "# Steady outflow across the gap (made by scripts/waiting_room_gap_profile.sh)"
for args in "2d 6 12 21" "3d 6 22 31" "2d 4.26 12 21" "2d 3 12 21"; do
  read -r model w first last <<< "$args"
  echo
  /usr/bin/python3 scripts/gap_profile.py "$store" --model "$model" --w-over-d "$w" --replicates "$first" "$last" \
    --point "$none" --point "$a4" --point "$c4"
done
