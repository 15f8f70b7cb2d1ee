#!/usr/bin/env bash
# A finished blind pass, made outside the repository (studies/calibration_blind.sh /work/passNN ...),
# copied into the repository: everything but its run stores (*.sqlite*: hundreds of MB, which the
# script remakes), its `/usr/bin/time -v` record if given, the twins' scenario lines made to name the
# same scenario file from their new place, and the analyses a pass's README cites:
#   report.md, cases.csv, confusion.png   calibrate/blind_summary.py DEST
#   lean.txt                              calibrate/score_lean.py --cases "<the nulls>" DEST
#   oracle_scale.txt                      calibrate/oracle_scale.py DEST
#   interval_sides.txt                    calibrate/interval_sides.py DEST
#
#   studies/blind_pass_copy.sh PASS DEST [TIMEV]     e.g. /work/pass20 results/calibration-blind-pass20 /work/pass20.timev
#
# Refused (exit 2, nothing written): a PASS with a twin not yet calibrated (not finished), or a DEST
# that already holds a pass (its cases.csv). DEST may hold other files (a PREREGISTRATION.md).
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 2 ]] || { echo "usage: studies/blind_pass_copy.sh PASS DEST [TIMEV]" >&2; exit 2; }
pass=${1%/}; dest=${2%/}; timev=${3:-}
[[ -d $pass/twins ]] || { echo "error: $pass is not a blind pass folder (no twins/)" >&2; exit 2; }
[[ -z $timev || -f $timev ]] || { echo "error: no time record $timev" >&2; exit 2; }
for twin in "$pass"/twins/*.toml; do
  id=$(basename "$twin" .toml)
  [[ -f $pass/$id/summary.json ]] || { echo "error: $pass is not finished: $id has no summary.json" >&2; exit 2; }
done
[[ ! -f $dest/cases.csv ]] || { echo "error: $dest holds a pass already ($dest/cases.csv)" >&2; exit 2; }
mkdir -p "$dest"
(cd "$pass" && tar cf - --exclude='*.sqlite*' .) | (cd "$dest" && tar xf -)
if [[ -n $timev ]]; then cp "$timev" "$dest/$(basename "$pass").timev"; fi
# A twin names its scenario relative to its own folder: the same file, named from the new one.
for twin in "$dest"/twins/*.toml; do
  line=$(grep -m1 '^scenario = "' "$twin") || continue
  old=${line#scenario = \"}; old=${old%\"}
  target=$(realpath -m "$pass/twins/$old")
  new=$(realpath -m --relative-to="$dest/twins" "$target")
  sed -i "s#^scenario = \"$old\"#scenario = \"$new\"#" "$twin"
done
/usr/bin/python3 calibrate/blind_summary.py "$dest" > /dev/null
nulls=()
for twin in "$dest"/twins/null-*.toml; do nulls+=("$(basename "$twin" .toml)"); done
/usr/bin/python3 calibrate/score_lean.py --cases "${nulls[*]}" "$dest" > "$dest/lean.txt"
/usr/bin/python3 calibrate/oracle_scale.py "$dest" > "$dest/oracle_scale.txt"
/usr/bin/python3 calibrate/interval_sides.py "$dest" > "$dest/interval_sides.txt"
echo "copied $pass to $dest (without its stores); summary in $dest/report.md"
