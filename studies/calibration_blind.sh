#!/usr/bin/env bash
# The calibration loop's blind study: twins of a design (data/blind/design.toml unless DESIGN) with hidden
# effects of hidden sizes (drawn from each case's seed), each calibrated blind with
# the 2D model; then the summary (confusion matrix, interval coverage, null
# false-positive rate, held-out error before/after) in OUT/report.md.
#
#   [MODEL_SEEDS=per-twin|design] studies/calibration_blind.sh [OUT] [JOBS] [SEED_OFFSET] [DESIGN] [CALIBRATE OPTIONS...]
#       (default results/calibration-blind, all cores, offset 0, data/blind/design.toml; options
#       after DESIGN go to every `gapflow calibrate`, e.g. --decisive-score 1e-4)
#
# SEED_OFFSET is added to every case's seed: another offset draws another set of twins (other
# sizes, other data noise) for the same cases, to test rules chosen after seeing one set on
# twins they have not seen. Pass 5 (results/calibration-blind) used offset 1000.
#
# MODEL_SEEDS says which draw of the model's noise each calibration fits. `per-twin` (the default
# from pass 20 on): each twin carries its own seed as its [model] seed (its data are made on other
# seeds, design seed + 1000003 + seed), so the twins are independent draws of the model's noise as
# well as the data's; nothing is shared between calibrations, which costs about 4.5 times the runs.
# `design` (every pass up to 19): the design's [model] seed in every twin, so every calibration of
# every pass fits the same model runs at a grid node (shared, which is cheap), and a pass samples
# the data's noise only: its count is one draw of the model's noise, not the loop's rate.
#
# Resumable: a twin file or a calibration summary that exists is not made again,
# and every run is kept in OUT/runs.sqlite (calibrations: identical runs are shared
# between twins) and OUT/twin_runs.sqlite (the twins' data). Those two stores are
# not committed (hundreds of MB); this script remakes them.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:-results/calibration-blind}
jobs=${2:-$(nproc)}
seed_offset=${3:-0}
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
design=${4:-data/blind/design.toml}
calibrate_options=("${@:5}")
mkdir -p "$out/twins" "$out/truth"
# Twins and summaries of one seed offset must not be mixed with another's (an OUT with twins and
# no record was made before the offset existed: offset 0).
recorded=""
if [[ -f $out/seed_offset ]]; then recorded=$(cat "$out/seed_offset")
elif compgen -G "$out/twins/*.toml" > /dev/null; then recorded=0; fi
if [[ -n $recorded && $recorded != "$seed_offset" ]]; then
  echo "error: $out was made with seed offset $recorded, not $seed_offset; use another OUT" >&2
  exit 2
fi
echo "$seed_offset" > "$out/seed_offset"
# Likewise the design: twins of one design are never calibrated beside another's (an OUT with twins
# and no record was made before the design could be chosen: data/blind/design.toml).
[[ -f $design ]] || { echo "error: no design file $design" >&2; exit 2; }
design=$(realpath --relative-to=. "$design")
recorded_design=""
if [[ -f $out/design ]]; then recorded_design=$(cat "$out/design")
elif compgen -G "$out/twins/*.toml" > /dev/null; then recorded_design=data/blind/design.toml; fi
if [[ -n $recorded_design && $recorded_design != "$design" ]]; then
  echo "error: $out was made from $recorded_design, not $design; use another OUT" >&2
  exit 2
fi
echo "$design" > "$out/design"
# And the calibrations' options (an OUT without a record ran with none).
options_text="${calibrate_options[*]}"
recorded_options=""
if [[ -f $out/calibrate_options ]]; then recorded_options=$(cat "$out/calibrate_options"); fi
if [[ $recorded_options != "$options_text" ]] && compgen -G "$out/*/summary.json" > /dev/null; then
  echo "error: $out was calibrated with options '$recorded_options', not '$options_text'; use another OUT" >&2
  exit 2
fi
echo "$options_text" > "$out/calibrate_options"
# And the model seeds (an OUT without a record used the design's).
model_seeds=${MODEL_SEEDS:-per-twin}
if [[ $model_seeds != design && $model_seeds != per-twin ]]; then
  echo "error: MODEL_SEEDS is '$model_seeds'; allowed: design, per-twin" >&2
  exit 2
fi
recorded_seeds=""
if [[ -f $out/model_seeds ]]; then recorded_seeds=$(cat "$out/model_seeds")
elif compgen -G "$out/twins/*.toml" > /dev/null; then recorded_seeds=design; fi
if [[ -n $recorded_seeds && $recorded_seeds != "$model_seeds" ]]; then
  echo "error: $out was made with MODEL_SEEDS=$recorded_seeds, not $model_seeds; use another OUT" >&2
  exit 2
fi
echo "$model_seeds" > "$out/model_seeds"

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
      --replicates 10 --name "$id" --jobs "$jobs" --db "$out/twin_runs.sqlite" "${twin_options[@]}" \
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
