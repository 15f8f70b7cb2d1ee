#!/usr/bin/env bash
# Can the calibration's form check see a drag of another law than the catalogue's on a design? DRAWS
# null twins and DRAWS twins with the blind study's out-of-catalogue drag (outside-quadratic-16:
# particles.quadratic_drag_per_m=16, a drag force per mass k v^2), each its own draw (its data's noise
# and, 1000 x its seed, its own model seed: studies/blind_cases.sh), calibrated blind with the 2D
# model by GAPFLOW, a binary whose form checks report their detectable spread (9076e4e or later).
# Then, in OUT: report.md and cases.csv (calibrate/blind_summary.py), form_checks.txt (what each
# calibration added, its verdict, its smallest adjusted p and detectable spreads) and, per quadratic
# twin read as a drag along the incline, quadratic_drag_visibility-K.txt: the spread a quadratic drag
# asks for across the inclines (from the null twins' J_mid), the check's detectable spread there and
# its power against it on that draw.
#
#   GAPFLOW=BINARY [DRAWS=2] [TWIN_REPLICATES=10] studies/form_check_power.sh OUT JOBS SEED_OFFSET DESIGN
#
# Seeds: null-K has SEED_OFFSET + 100 + K and quadratic-16-K SEED_OFFSET + 142 + K, so draw 1 is the
# blind study's null-1 and outside-quadratic-16 at that offset. Resumable as calibration_blind.sh: a
# twin or a calibration that has ended (calibration_ended_well) is not made again; the runs are kept
# in OUT/runs.sqlite and OUT/twin_runs.sqlite (not committed). An OUT made with another design, seed
# offset, draw count, data runs or binary is refused (exit 2) before anything is written.
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: GAPFLOW=BINARY [DRAWS=2] [TWIN_REPLICATES=10] $0 OUT JOBS SEED_OFFSET DESIGN"
[[ $# -eq 4 ]] || { echo "$usage" >&2; exit 2; }
out=$1 jobs=$2 seed_offset=$3 design=$4
draws=${DRAWS:-2}
twin_replicates=${TWIN_REPLICATES:-10}
gapflow=$(realpath "${GAPFLOW:?GAPFLOW must name the binary (one whose form checks report detectable_spread)}")
[[ -x $gapflow ]] || { echo "error: GAPFLOW $gapflow is not an executable" >&2; exit 2; }
[[ -f $design ]] || { echo "error: no design file $design" >&2; exit 2; }
for name in JOBS:$jobs SEED_OFFSET:$seed_offset DRAWS:$draws TWIN_REPLICATES:$twin_replicates; do
  if [[ ! ${name#*:} =~ ^[0-9]{1,6}$ ]]; then
    echo "error: ${name%%:*} is '${name#*:}'; allowed: a whole number" >&2
    exit 2
  fi
done
(( draws >= 1 && draws <= 40 )) || { echo "error: DRAWS is '$draws'; allowed: 1 to 40" >&2; exit 2; }
design=$(realpath --relative-to=. "$design")
binary_sha=$(sha256sum "$gapflow" | cut -c1-16)
settings="design $design
seed_offset $seed_offset
draws $draws
twin_replicates $twin_replicates
binary_sha256 $binary_sha"
# One OUT, one setting: the twins and calibrations of one are never mixed with another's.
if [[ -f $out/settings && $(cat "$out/settings") != "$settings" ]]; then
  echo "error: $out was made with other settings; use another OUT" >&2
  diff <(cat "$out/settings") <(echo "$settings") >&2 || true
  exit 2
fi
mkdir -p "$out/twins" "$out/truth"
echo "$settings" > "$out/settings"

source studies/blind_cases.sh
cases=""
for ((k = 1; k <= draws; ++k)); do
  cases+="null-$k $((seed_offset + 100 + k))"$'\n'
  cases+="quadratic-16-$k $((seed_offset + 142 + k)) set:particles.quadratic_drag_per_m=16"$'\n'
done

while read -r id seed planted; do
  [[ -n $id ]] || continue
  twin="$out/twins/$id.toml"
  if [[ ! -f $twin ]]; then
    # shellcheck disable=SC2086  # the planted list is space-separated words
    planted_options $planted
    model_seed_options per-twin "$seed"
    rm -f "$out/truth/$id.json"  # a twin cut off before its data file was written left at most this
    echo "== twin $id (2d, seed $seed): ${planted:-nothing planted}" >&2
    "$gapflow" twin "$design" --out "$twin" --truth "$out/truth/$id.json" --model 2d --seed "$seed" \
      --replicates "$twin_replicates" --name "$id" --jobs "$jobs" --db "$out/twin_runs.sqlite" \
      "${twin_options[@]}" "${seed_options[@]}"
  fi
  if ! calibration_ended_well "$out" "$id"; then
    rm -rf "${out:?}/$id"
    echo "== calibrate $id (2d, blind)" >&2
    /usr/bin/time -f "%e s wall" -o "$out/$id.time" \
      "$gapflow" calibrate "$twin" --model 2d --out "$out/$id" --db "$out/runs.sqlite" --jobs "$jobs" --no-plots
  fi
done <<< "$cases"

/usr/bin/python3 calibrate/blind_summary.py "$out" > /dev/null
/usr/bin/python3 calibrate/form_check_table.py "$out" > "$out/form_checks.txt"
for ((k = 1; k <= draws; ++k)); do
  # A quadratic twin read as anything but an effect checked along the incline has no power to give:
  # the script says so in the file instead of failing.
  if ! /usr/bin/python3 calibrate/quadratic_drag_visibility.py "$out" "$out" "quadratic-16-$k" \
      > "$out/quadratic_drag_visibility-$k.txt" 2> "$out/quadratic_drag_visibility-$k.err"; then
    cat "$out/quadratic_drag_visibility-$k.err" >> "$out/quadratic_drag_visibility-$k.txt"
  fi
  rm -f "$out/quadratic_drag_visibility-$k.err"
done
echo "done: $out/report.md, $out/form_checks.txt, $out/quadratic_drag_visibility-*.txt" >&2
