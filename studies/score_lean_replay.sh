#!/usr/bin/env bash
# Twins of a finished blind pass (default its nulls) calibrated again with the other setting of the
# signatures' seeds than the pass's (own seeds or shared with the baseline; the pass's other calibrate
# options kept), on a copy of the
# pass's store: the same twins and seeds, so the baseline and its runs are the pass's, and only the
# signatures' runs differ. Not blind: a check on the simulator of whether the first round's scores
# lean toward the effects' steps because the signatures shared the baseline nodes' runs
# (calibrate/README.md, step 3); on a pass with a model seed per twin (MODEL_SEEDS=per-twin) each null is its
# own draw of the model's noise, and the two settings are compared on the same draws. Writes
# OUT/<case>/ (report, summary.json, log) and prints calibrate/score_lean.py for the pass's own
# calibrations of those cases and for OUT's. Resumable (finished cases kept; OUT/runs.sqlite, the
# copy, is not committed).
#
#   GAPFLOW=<binary> studies/score_lean_replay.sh PASS STORE OUT [JOBS] [CASE...]
#   e.g. studies/score_lean_replay.sh results/calibration-blind-pass16 /work/pass16-stores/runs.sqlite /work/lean16 2
# (Until pass 20 it always added --independent-signatures and dropped the pass's options: pass 16's
# replay ran without its --decisive-score 1e-4, which the first round's scores do not depend on.)
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 3 ]] || { echo "usage: studies/score_lean_replay.sh PASS STORE OUT [JOBS] [CASE...]" >&2; exit 2; }
pass=${1%/}; store=$2; out=${3%/}; jobs=${4:-$(nproc)}
shift $(( $# < 4 ? $# : 4 ))
cases=("$@")
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
[[ -d $pass/twins && -f $store ]] || { echo "error: $pass/twins or $store missing" >&2; exit 2; }
if [[ ${#cases[@]} -eq 0 ]]; then
  for twin in "$pass"/twins/null-*.toml; do cases+=("$(basename "$twin" .toml)"); done
fi
# The pass's options (a pass without the record ran with none), its signatures' setting toggled. The
# setting is what the first case's calibration records (summary.json "independent_signatures";
# absent before the option existed: shared), since a pass without either flag ran its binary's
# default (shared up to pass 20's binary, a build of 13aa5bd; on seeds of their own from bf54828).
# Shared again: --shared-signatures where GAPFLOW knows it, else no flag (a binary from before it,
# whose default is shared).
options=()
if [[ -f $pass/calibrate_options ]]; then read -r -a options < "$pass/calibrate_options" || true; fi
replay_options=()
for o in "${options[@]}"; do
  [[ $o == --independent-signatures || $o == --shared-signatures ]] || replay_options+=("$o")
done
[[ ${#cases[@]} -gt 0 ]] || { echo "error: no null twin in $pass, and no CASE given" >&2; exit 2; }
first_summary=$pass/${cases[0]}/summary.json
# The binary's options, read whole before they are searched: `gapflow --help | grep -q` under pipefail
# fails at random when grep exits at its first match and the writer dies of SIGPIPE.
calibrate_help=$("$gapflow" calibrate --help 2>/dev/null || true)
[[ -f $first_summary ]] || { echo "error: $pass has no calibration of ${cases[0]}" >&2; exit 2; }
if grep -q '"independent_signatures": true' "$first_summary"; then
  label="with the signatures sharing the baseline's runs"
  if grep -q -- '--shared-signatures' <<< "$calibrate_help"; then replay_options+=(--shared-signatures); fi
else
  label="with --independent-signatures"
  replay_options+=(--independent-signatures)
fi
# Rule 5 as the pass ran it (summary.json "alternatives"; absent before the option: none asked), where
# GAPFLOW knows the option: binaries from 21de738 on ask 2 by default, which a pass before 24 did not.
if grep -q -- '--alternatives' <<< "$calibrate_help"; then
  asked=$(/usr/bin/python3 -c 'import json, sys; print(json.load(open(sys.argv[1])).get("alternatives", 0))' "$first_summary")
  replay_options+=(--alternatives "$asked")
fi
# An OUT is calibrated with one set of options only (recorded in it; an OUT without the record was
# made by the script before pass 20, with --independent-signatures alone).
if [[ -d $out ]]; then
  recorded_options=--independent-signatures
  if [[ -f $out/replay_options ]]; then recorded_options=$(cat "$out/replay_options"); fi
  if [[ $recorded_options != "${replay_options[*]}" ]]; then
    echo "error: $out was calibrated with '$recorded_options', not '${replay_options[*]}'; use another OUT" >&2
    exit 2
  fi
fi
mkdir -p "$out"
echo "${replay_options[*]}" > "$out/replay_options"
[[ -f $out/runs.sqlite ]] || { cp "$store" "$out/runs.sqlite.partial" && mv "$out/runs.sqlite.partial" "$out/runs.sqlite"; }
for id in "${cases[@]}"; do
  [[ -f $pass/twins/$id.toml ]] || { echo "error: no twin $id in $pass" >&2; exit 2; }
  [[ -f $out/$id/summary.json ]] && continue
  "$gapflow" calibrate "$pass/twins/$id.toml" --model 2d --db "$out/runs.sqlite" --out "$out/$id" --jobs "$jobs" \
    --no-plots "${replay_options[@]}" > "$out/$id.log" 2>&1 || { echo "error: $id failed; see $out/$id.log" >&2; exit 1; }
done
echo "== the pass ($pass)"
/usr/bin/python3 calibrate/score_lean.py --cases "${cases[*]}" "$pass"
echo "== $label ($out): options '${replay_options[*]}'"
/usr/bin/python3 calibrate/score_lean.py --cases "${cases[*]}" "$out"
