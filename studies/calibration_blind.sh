#!/usr/bin/env bash
# The calibration loop's blind study: twins of a design (data/blind/design.toml unless DESIGN) with hidden
# effects of hidden sizes (drawn from each case's seed), each calibrated blind with
# the 2D model; then the summary (confusion matrix, interval coverage, null
# false-positive rate, held-out error before/after) in OUT/report.md.
#
#   [MODEL_SEEDS=per-twin|design] [TWIN_REPLICATES=N] studies/calibration_blind.sh [OUT] [JOBS] [SEED_OFFSET] [DESIGN] [CALIBRATE OPTIONS...]
#       (default results/calibration-blind, all cores, offset 0, data/blind/design.toml; options
#       after DESIGN go to every `gapflow calibrate`, e.g. --decisive-score 1e-4)
#
# TWIN_REPLICATES (default 10, every pass up to 21): the runs averaged into each twin's data point,
# its "measured" replicate count. It sets the data's noise only; the calibration's model replicates
# are the design's [model] replicates. Less noise makes every planted effect easier to see, so a
# pass's counts hold for its data count only. (Murray et al. 2016 ran each of their simulations 20
# times; they give no repeat count for their experiments.)
#
# SEED_OFFSET is added to every case's seed: another offset draws another set of twins (other
# sizes, other data noise) for the same cases, to test rules chosen after seeing one set on
# twins they have not seen. Pass 5 (results/calibration-blind) used offset 1000.
#
# MODEL_SEEDS says which draw of the model's noise each calibration fits. `per-twin` (the default
# from pass 20 on): each twin carries 1000 x its seed as its [model] seed (studies/blind_cases.sh
# says why 1000; its data are made on other seeds, design seed + 1000003 + seed), so the twins are
# independent draws of the model's noise as well as the data's; nothing is shared between
# calibrations, which costs about 4.5 times the runs.
# `design` (every pass up to 19): the design's [model] seed in every twin, so every calibration of
# every pass fits the same model runs at a grid node (shared, which is cheap), and a pass samples
# the data's noise only: its count is one draw of the model's noise, not the loop's rate.
#
# Resumable: a twin file or a calibration summary that exists is not made again,
# and every run is kept in OUT/runs.sqlite (calibrations; with MODEL_SEEDS=design identical
# runs are shared between twins) and OUT/twin_runs.sqlite (the twins' data). Those two stores are
# not committed (hundreds of MB); this script remakes them.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/calibration-blind}
jobs=${2:-$(nproc)}
seed_offset=${3:-0}
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
design=${4:-data/blind/design.toml}
calibrate_options=("${@:5}")
model_seeds=${MODEL_SEEDS:-per-twin}
twin_replicates=${TWIN_REPLICATES:-10}
# What an OUT was made with is recorded in it, and a run with other settings is refused (exit 2)
# before anything is written: twins and summaries of one setting are never mixed with another's.
# recorded FILE BEFORE: FILE's content; for an OUT with twins and no record (made before the
# setting existed), BEFORE; else empty.
recorded() {
  if [[ -f $out/$1 ]]; then cat "$out/$1"
  elif compgen -G "$out/twins/*.toml" > /dev/null; then echo "$2"; fi
}
refuse_other() {  # NAME RECORDED WANTED
  if [[ -n $2 && $2 != "$3" ]]; then
    echo "error: $out was made with $1 $2, not $3; use another OUT" >&2
    exit 2
  fi
}
if [[ $model_seeds != design && $model_seeds != per-twin ]]; then
  echo "error: MODEL_SEEDS is '$model_seeds'; allowed: per-twin, design" >&2
  exit 2
fi
if [[ ! $twin_replicates =~ ^0*[0-9]{1,4}$ ]] || (( 10#$twin_replicates < 2 || 10#$twin_replicates > 1000 )); then
  echo "error: TWIN_REPLICATES is '$twin_replicates'; allowed: a whole number of runs from 2 to 1000" >&2
  exit 2
fi
twin_replicates=$((10#$twin_replicates))
[[ -f $design ]] || { echo "error: no design file $design" >&2; exit 2; }
design=$(realpath --relative-to=. "$design")
refuse_other "seed offset" "$(recorded seed_offset 0)" "$seed_offset"
refuse_other design "$(recorded design data/blind/design.toml)" "$design"
refuse_other MODEL_SEEDS "$(recorded model_seeds design)" "$model_seeds"
refuse_other TWIN_REPLICATES "$(recorded twin_replicates 10)" "$twin_replicates"
# The calibrations' options matter once one has run (an OUT without a record ran with none).
options_text="${calibrate_options[*]}"
if compgen -G "$out/*/summary.json" > /dev/null; then
  recorded_options=""
  if [[ -f $out/calibrate_options ]]; then recorded_options=$(cat "$out/calibrate_options"); fi
  if [[ $recorded_options != "$options_text" ]]; then
    echo "error: $out was calibrated with options '$recorded_options', not '$options_text'; use another OUT" >&2
    exit 2
  fi
fi
mkdir -p "$out/twins" "$out/truth"
echo "$seed_offset" > "$out/seed_offset"
echo "$design" > "$out/design"
echo "$options_text" > "$out/calibrate_options"
echo "$model_seeds" > "$out/model_seeds"
echo "$twin_replicates" > "$out/twin_replicates"

# The cases (id, model, seed, planted): studies/blind_cases.sh.
source studies/blind_cases.sh

echo "$blind_cases" | while read -r id model seed planted; do
  [ -n "$id" ] || continue
  seed=$((seed + seed_offset))
  twin="$out/twins/$id.toml"
  if [ ! -f "$twin" ]; then
    # shellcheck disable=SC2086  # the planted list is space-separated words
    planted_options $planted
    model_seed_options "$model_seeds" "$seed"
    echo "== twin $id ($model, seed $seed): ${planted:-nothing planted}" >&2
    "$gapflow" twin "$design" --out "$twin" --truth "$out/truth/$id.json" --model "$model" --seed "$seed" \
      --replicates "$twin_replicates" --name "$id" --jobs "$jobs" --db "$out/twin_runs.sqlite" "${twin_options[@]}" \
      "${seed_options[@]}"
  fi
  if [ ! -f "$out/$id/summary.json" ]; then
    echo "== calibrate $id (2d, blind)" >&2
    /usr/bin/time -f "%e s wall" -o "$out/$id.time" \
      "$gapflow" calibrate "$twin" --model 2d --out "$out/$id" --db "$out/runs.sqlite" --jobs "$jobs" --no-plots \
      "${calibrate_options[@]}"
  fi
done
/usr/bin/python3 calibrate/blind_summary.py "$out"
