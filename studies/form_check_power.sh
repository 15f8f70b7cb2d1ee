#!/usr/bin/env bash
# Can the calibration's form check see a drag of another law than the catalogue's on a design? DRAWS
# null twins and DRAWS twins with the blind study's out-of-catalogue drag (outside-quadratic-16:
# particles.quadratic_drag_per_m=16, a drag force per mass k v^2), each its own draw (its data's noise
# and, 1000 x its seed, its own model seed: studies/blind_cases.sh), calibrated blind with the 2D
# model by GAPFLOW, a binary whose form checks report their detectable spread (9076e4e or later).
# Then, in OUT: report.md and cases.csv (calibrate/blind_summary.py), form_checks.txt (what each
# calibration added, its verdict, its smallest adjusted p and detectable spreads) and, per quadratic
# twin, quadratic_drag_visibility-K.txt: the spread a quadratic drag
# asks for across the inclines (from the null twins' J_mid), the check's detectable spread there and
# its power against it on that draw.
#
#   GAPFLOW=BINARY [DRAWS=2] [TWIN_REPLICATES=10] studies/form_check_power.sh OUT JOBS SEED_OFFSET DESIGN
#
# Seeds: null-K has SEED_OFFSET + 100 + K and quadratic-16-K SEED_OFFSET + 142 + K, so draw 1 is the
# blind study's null-1 and outside-quadratic-16 at that offset. Resumable as calibration_blind.sh: a
# twin or a calibration that has ended (calibration_ended_well) is not made again; the runs are kept
# in OUT/runs.sqlite and OUT/twin_runs.sqlite (not committed). Refused (exit 2) before anything is
# written: an OUT made with other settings (OUT/settings: the design's files' sha256, the seed
# offset, the draws, the data's runs, the drag, the binary's sha256), a folder with files and no such
# record (another study's), a second run on the same OUT (a lock), bad numbers.
set -euo pipefail
cd "$(dirname "$0")/.."
usage="usage: GAPFLOW=BINARY [DRAWS=2] [TWIN_REPLICATES=10] $0 OUT JOBS SEED_OFFSET DESIGN (paths relative to the repository)"
[[ $# -eq 4 ]] || { echo "$usage" >&2; exit 2; }
out=$1 design=$4
# whole NAME VALUE LO HI: VALUE as a decimal number (leading zeros are not octal) within LO..HI, else exit 2.
whole() {
  if [[ ! $2 =~ ^[0-9]{1,7}$ ]] || (( 10#$2 < $3 || 10#$2 > $4 )); then
    echo "error: $1 is '$2'; allowed: a whole number from $3 to $4" >&2
    exit 2
  fi
  echo $((10#$2))
}
jobs=$(whole JOBS "$2" 1 1024)
seed_offset=$(whole SEED_OFFSET "$3" 0 1000000)
draws=$(whole DRAWS "${DRAWS:-2}" 1 40)
twin_replicates=$(whole TWIN_REPLICATES "${TWIN_REPLICATES:-10}" 2 1000)
[[ -n ${GAPFLOW:-} && -x $GAPFLOW && -f $GAPFLOW ]] ||
  { echo "error: GAPFLOW is '${GAPFLOW:-}'; allowed: an executable gapflow whose form checks report detectable_spread (9076e4e or later)" >&2; exit 2; }
gapflow=$(realpath "$GAPFLOW")
[[ -f $design ]] || { echo "error: no design file $design" >&2; exit 2; }
design=$(realpath --relative-to=. "$design")
# The drag and its seed are the blind study's outside-quadratic-16 case's (studies/blind_cases.sh).
source studies/blind_cases.sh
read -r _ _ quadratic_seed quadratic_planted <<< "$(grep '^outside-quadratic-16 ' <<< "$blind_cases")"
drag_per_m=${quadratic_planted##*=}
# What the folder is made of: a change to any of it (the design's files, the binary, the counts, the
# seeds' rule, the drag) makes another experiment, refused in this OUT.
design_csv=$(sed -n 's/^csv *= *"\(.*\)".*/\1/p' "$design")
design_scenario=$(sed -n 's/^scenario *= *"\(.*\)".*/\1/p' "$design")
design_hash=$(cd "$(dirname "$design")" && cat "$(basename "$design")" ${design_csv:+"$design_csv"} \
  ${design_scenario:+"$design_scenario"} | sha256sum | cut -c1-16) ||  # pipefail: a file not read fails it
  { echo "error: could not read $design with its csv '$design_csv' and scenario '$design_scenario'" >&2; exit 2; }
settings="design $design $design_hash
seed_offset $seed_offset (null-K: + 100 + K; quadratic-16-K: + $((quadratic_seed - 1)) + K; model seed 1000 x seed)
draws $draws
twin_replicates $twin_replicates
quadratic_drag_per_m $drag_per_m
binary_sha256 $(sha256sum "$gapflow" | cut -c1-16)"
if [[ -f $out/settings ]]; then
  if [[ $(cat "$out/settings") != "$settings" ]]; then
    echo "error: $out was made with other settings; use another OUT" >&2
    diff <(cat "$out/settings") <(echo "$settings") >&2 || true
    exit 2
  fi
elif [[ -d $out && -n $(ls -A "$out") ]]; then
  echo "error: $out holds files and no record of this script's settings (another study's folder?); use another OUT" >&2
  exit 2
fi
mkdir -p "$out/twins" "$out/truth"
exec 9> "$out/lock"
flock -n 9 || { echo "error: another form_check_power.sh is running on $out" >&2; exit 2; }
echo "$settings" > "$out/settings"
# What calibrate/blind_summary.py reads to describe the folder in report.md.
echo "$design" > "$out/design"
echo per-twin > "$out/model_seeds"
echo "$twin_replicates" > "$out/twin_replicates"
echo "studies/form_check_power.sh" > "$out/made_by"

cases=""
for ((k = 1; k <= draws; ++k)); do
  cases+="null-$k $((seed_offset + 100 + k))"$'\n'
  cases+="quadratic-16-$k $((seed_offset + quadratic_seed - 1 + k)) $quadratic_planted"$'\n'
done

while read -r id seed planted; do
  [[ -n $id ]] || continue
  twin="$out/twins/$id.toml"
  # gapflow twin writes the data file, then the truth (each through a temporary name): a twin cut off
  # between the two is made again whole, and anything calibrated on it again after it.
  if [[ ! -f $twin || ! -f $out/truth/$id.json ]]; then
    # shellcheck disable=SC2086  # the planted list is space-separated words
    planted_options $planted
    model_seed_options per-twin "$seed"
    rm -rf "$twin" "$out/truth/$id.json" "${out:?}/$id" "$out/$id.time"
    echo "== twin $id (2d, seed $seed): ${planted:-nothing planted}" >&2
    "$gapflow" twin "$design" --out "$twin" --truth "$out/truth/$id.json" --model 2d --seed "$seed" \
      --replicates "$twin_replicates" --name "$id" --jobs "$jobs" --db "$out/twin_runs.sqlite" \
      "${twin_options[@]}" "${seed_options[@]}" < /dev/null
  fi
  if ! calibration_ended_well "$out" "$id"; then
    rm -rf "${out:?}/$id"
    echo "== calibrate $id (2d, blind)" >&2
    /usr/bin/time -f "%e s wall" -o "$out/$id.time" \
      "$gapflow" calibrate "$twin" --model 2d --out "$out/$id" --db "$out/runs.sqlite" --jobs "$jobs" --no-plots < /dev/null
  fi
done <<< "$cases"

while read -r id _; do
  [[ -z $id ]] || calibration_ended_well "$out" "$id" ||
    { echo "error: $id has not ended well (see $out/$id.time); nothing summarised" >&2; exit 1; }
done <<< "$cases"
/usr/bin/python3 calibrate/blind_summary.py "$out" > /dev/null
/usr/bin/python3 calibrate/form_check_table.py "$out" > "$out/form_checks.txt"
for ((k = 1; k <= draws; ++k)); do
  # A quadratic twin not read as a linear drag has no power of that check to give: the file says
  # what it was read as instead (the tool's exit 2); any other failure is an error.
  rc=0
  /usr/bin/python3 calibrate/quadratic_drag_visibility.py "$out" "$out" "quadratic-16-$k" \
    > "$out/quadratic_drag_visibility-$k.txt" 2> "$out/quadratic_drag_visibility-$k.err" || rc=$?
  if (( rc == 2 )); then cat "$out/quadratic_drag_visibility-$k.err" >> "$out/quadratic_drag_visibility-$k.txt"; fi
  if (( rc != 0 && rc != 2 )); then
    cat "$out/quadratic_drag_visibility-$k.err" >&2
    echo "error: quadratic_drag_visibility.py failed on quadratic-16-$k (exit $rc)" >&2
    exit 1
  fi
  rm -f "$out/quadratic_drag_visibility-$k.err"
done
echo "done: $out/report.md, $out/form_checks.txt, $out/quadratic_drag_visibility-*.txt" >&2
