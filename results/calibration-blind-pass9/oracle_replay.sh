#!/usr/bin/env bash
# Pass 9's twins re-drawn by the current `gapflow twin` (af30c2b on: the oracle refits the friction
# with the measurement's penalty about its true value), reusing every run of the pass's twin store:
# nothing is simulated, the twin files must come out identical (checked), only the oracle changes.
# Writes oracle/<case>.json (the truth files as that binary writes them) and oracle/visible.txt, only
# once every twin has been checked. The cases, their seed offset and design are pass 9's: the case list
# as the blind script had it then (f7193ee), the offset from OUT/seed_offset.
#
#   results/calibration-blind-pass9/oracle_replay.sh     (after studies/calibration_blind.sh made the stores)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=results/calibration-blind-pass9
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp "$out/twin_runs.sqlite" "$work/twin_runs.sqlite"   # the pass's store stays as the pass left it
runs_before=$(sqlite3 "$work/twin_runs.sqlite" "select count(*) from runs")
offset=$(cat "$out/seed_offset")
mkdir -p "$work/oracle"
git show f7193ee:studies/calibration_blind.sh | sed -n '/^cases="/,/^"/p' | sed '1d;$d' | while read -r id model seed planted; do
  [ -n "$id" ] || continue
  args=()
  for p in $planted; do
    case "$p" in effect:*) args+=(--effect "${p#effect:}") ;; set:*) args+=(--set "${p#set:}") ;; esac
  done
  "$gapflow" twin data/blind/design.toml --out "$work/$id.toml" --truth "$work/oracle/$id.json" --model "$model" \
    --seed $((seed + offset)) --replicates 10 --name "$id" --jobs 1 --db "$work/twin_runs.sqlite" "${args[@]}" > /dev/null
  # The scenario line is relative to the file's folder; everything else must match.
  if ! cmp -s <(grep -v '^scenario' "$work/$id.toml") <(grep -v '^scenario' "$out/twins/$id.toml"); then
    echo "error: $id's twin differs from the pass's: the replay is not of the same data" >&2
    exit 1
  fi
done
if [[ $(sqlite3 "$work/twin_runs.sqlite" "select count(*) from runs") != "$runs_before" ]]; then
  echo "error: the replay simulated runs: it is not a replay of the pass's data" >&2
  exit 1
fi
mkdir -p "$out/oracle"
cp "$work"/oracle/*.json "$out/oracle/"
/usr/bin/python3 - "$out" <<'PY' | tee "$out/oracle/visible.txt"
import csv, json, sys
out = sys.argv[1]
rows = {r["case"]: r for r in csv.DictReader(open(f"{out}/cases.csv"))}
single = sorted(c for c, r in rows.items() if r["truth"] not in ("none", "two effects", "outside the catalogue", "3D model"))
print("case, oracle power in the pass (lambda), with the measurement's penalty (lambda), identified")
visible = []
for c in single:
    s = json.load(open(f"{out}/oracle/{c}.json"))["signal"]
    r = rows[c]
    print(f"{c}, {float(r['oracle_power']):.2f} ({float(r['signal_chi2']):.1f}), {s['oracle_power']:.2f} ({s['chi2']:.1f}), {r['identified']}")
    if s["oracle_power"] >= 0.8:
        visible.append(c)
found = [c for c in visible if rows[c]["identified"] == "True"]
print(f"visible with the penalty (power >= 0.8): {len(visible)} of {len(single)}; identified among them: {len(found)}")
print("found although not visible:", ", ".join(c for c in single if c not in visible and rows[c]["identified"] == "True"))
PY
