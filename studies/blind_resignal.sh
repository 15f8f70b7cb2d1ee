#!/usr/bin/env bash
# Recompute the oracle's signal (truth/<id>.json "signal": lambda and oracle power) of a finished
# blind pass's twins with the current gapflow, without touching the pass.
#
#   studies/blind_resignal.sh PASS OUT [STORE] [JOBS] [CASE...]
#
# PASS is a pass folder made by studies/calibration_blind.sh (its seed_offset, design, twins/ and
# truth/). Each twin with planted effects is made again, as the pass made it, into OUT/twins and
# OUT/truth; STORE (default PASS/twin_runs.sqlite, which is not committed) holds the pass's twin
# runs, so a twin whose runs are all there costs no simulation (without it everything is run
# again: minutes per twin). The remade data file must equal the pass's (the scenario line aside,
# which a committed pass rewrites; with DESIGN, also the lines naming the design and the model's
# replicates): else the twins differ and the script stops with exit 1.
# Then `calibrate/oracle_scale.py PASS --new OUT` compares the old and the new lambda with the loop's
# own view of each twin. The cases and their seeds are studies/blind_cases.sh's (calibration_blind.sh's);
# CASE... limits the remaking to those twins (the comparison then covers the ones remade).
# DESIGN=<design file> remakes them from another design that holds the same points, e.g.
# data/blind/design_v3.toml (v2 with 12 model replicates): lambda is then that design's loop's view.
# The data must still be the pass's; the twin's description and its [model] replicates may differ.
set -euo pipefail
cd "$(dirname "$0")/.."
if [[ $# -lt 2 ]]; then
  echo "usage: studies/blind_resignal.sh PASS OUT [STORE] [JOBS] [CASE...]" >&2
  exit 2
fi
pass=$1
out=$2
store=${3:-$pass/twin_runs.sqlite}
jobs=${4:-$(nproc)}
only=" ${*:5} "
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
for f in seed_offset design; do
  [[ -f $pass/$f ]] || { echo "error: $pass/$f missing: not a blind pass folder" >&2; exit 2; }
done
[[ -f $store ]] || echo "note: no store $store: every twin is simulated again" >&2
seed_offset=$(cat "$pass/seed_offset")
design=${DESIGN:-$(cat "$pass/design")}
model_seeds=design   # a pass without the record used the design's model seed
[[ -f $pass/model_seeds ]] && model_seeds=$(cat "$pass/model_seeds")
twin_replicates=10   # the runs per data point of every pass without the record (up to 21)
[[ -f $pass/twin_replicates ]] && twin_replicates=$(cat "$pass/twin_replicates")
# What may differ between the pass's twin and the remade one: the scenario line (a committed pass
# rewrites it), and with another design its name (first line, description) and the model's replicates
# (the first `replicates =` line; the points' own come after it).
comparable() {
  if [[ -z ${DESIGN:-} ]]; then grep -v '^scenario = ' "$1"; return; fi
  grep -v -e '^scenario = ' -e '^description = ' -e '^# Made by' "$1" | awk '!(/^replicates = / && !seen++)'
}
mkdir -p "$out/twins" "$out/truth"
source studies/blind_cases.sh
echo "$blind_cases" | while read -r id model seed planted; do
  [[ -n $id && -n $planted && -f $pass/twins/$id.toml ]] || continue
  [[ $only == "  " || $only == *" $id "* ]] || continue
  # shellcheck disable=SC2086  # the planted list is space-separated words
  planted_options $planted
  model_seed_options "$model_seeds" $((seed + seed_offset))
  if [[ ! -f $out/truth/$id.json ]]; then
    echo "== twin $id" >&2
    "$gapflow" twin "$design" --out "$out/twins/$id.toml" --truth "$out/truth/$id.json.part" --model "$model" \
      --seed $((seed + seed_offset)) --replicates "$twin_replicates" --name "$id" --jobs "$jobs" --db "$store" "${twin_options[@]}" \
      "${seed_options[@]}" >&2
    if ! diff <(comparable "$pass/twins/$id.toml") <(comparable "$out/twins/$id.toml") > /dev/null; then
      echo "error: the remade $id differs from $pass/twins/$id.toml: not the pass's twin" >&2
      exit 1
    fi
    mv "$out/truth/$id.json.part" "$out/truth/$id.json"
  fi
done
/usr/bin/python3 calibrate/oracle_scale.py "$pass" --new "$out"
