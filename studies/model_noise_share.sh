#!/usr/bin/env bash
# The model's share of the residual's variance at the baseline fit (summary.json model_noise_share,
# calibrate/fit.hpp) and the surface noise check (surface_noise_ratio, calibrate/surface_noise.hpp)
# for each twin of a blind pass, at each model replicate count given: a calibration
# with --max-effects 0 (the baseline and its fresh-seed checks only) per twin and count, into
# OUT/<replicates>/<case>/. With STORE holding the pass's runs at those counts (e.g. a copy of the
# store of the pass's replay at 12), nothing is simulated and it takes seconds per twin; else runs.
# Prints the median and range over the 2D-made twins per count. Resumable (finished twins kept).
#
#   studies/model_noise_share.sh PASS STORE OUT REPLICATES...
#   e.g. studies/model_noise_share.sh results/calibration-blind-pass15 /work/share-check.sqlite /work/share-scan 6 12
set -euo pipefail
cd "$(dirname "$0")/.."
[[ $# -ge 4 ]] || { echo "usage: studies/model_noise_share.sh PASS STORE OUT REPLICATES..." >&2; exit 2; }
pass=${1%/}; store=$2; out=$3; shift 3
gapflow=$(realpath "${GAPFLOW:-build/app/gapflow}")
[[ -d $pass/twins && -f $store ]] || { echo "error: $pass/twins or $store missing" >&2; exit 2; }
for n in "$@"; do
  for twin in "$pass"/twins/*.toml; do
    id=$(basename "$twin" .toml)
    [[ -f $out/$n/$id/summary.json ]] && continue
    mkdir -p "$out/$n"
    "$gapflow" calibrate "$twin" --model 2d --db "$store" --out "$out/$n/$id" --jobs 1 --no-plots --max-effects 0 \
      --model-replicates "$n" > "$out/$n/$id.log" 2>&1 || { echo "error: $id at $n replicates failed; see $out/$n/$id.log" >&2; exit 1; }
  done
done
/usr/bin/python3 - "$pass" "$out" "$@" <<'PY'
import json, statistics, sys
from pathlib import Path
pass_dir, out, counts = Path(sys.argv[1]), Path(sys.argv[2]), sys.argv[3:]
made_by_3d = {p.stem for p in (pass_dir / "truth").glob("*.json") if json.load(open(p)).get("model") == "3d"}
for n in counts:
    share = {s.parent.name: json.load(open(s))["model_noise_share"] for s in (out / n).glob("*/summary.json")}
    v = [x for case, x in share.items() if case not in made_by_3d and x is not None]  # null: no valid point
    if not v:
        print(f"{n} model replicates: no 2D-made twin with a share")
        continue
    print(f"{n} model replicates: the model's share of the variance at the baseline, median {statistics.median(v):.2f} "
          f"over {len(v)} 2D-made twins (range {min(v):.2f}-{max(v):.2f})")
    for field, what in (("node_correlation", "the model replicates' correlation between grid nodes (independent: ~0)"),
                        ("surface_noise_ratio", "how much the surface understates the model's variance at the baseline")):
        got = {s.parent.name: json.load(open(s)).get(field) for s in (out / n).glob("*/summary.json")}
        r = [x for case, x in got.items() if case not in made_by_3d and x is not None]
        if r:
            print(f"{n} model replicates: surface noise check, {what} ({field}), median {statistics.median(r):.2f} "
                  f"over {len(r)} 2D-made twins (range {min(r):.2f}-{max(r):.2f})")
    by = {}  # per observable, from each calibration's log line: name rho (factor x)
    for log in (out / n).glob("*.log"):
        if log.stem in made_by_3d:
            continue
        for line in log.read_text().splitlines():
            if "surface noise check" in line and "by observable: " in line:
                for part in line.split("by observable: ")[1].split(". Above")[0].split(", "):
                    name, rho, factor = part.replace("(", "").replace(" x)", "").split(" ")
                    by.setdefault(name, []).append((float(rho), float(factor)))
    for name, v in sorted(by.items()):
        rho, factor = zip(*v)
        flagged = sum(f > 1.5 for f in factor)
        print(f"  {name}: correlation median {statistics.median(rho):+.2f} (range {min(rho):+.2f} to {max(rho):+.2f}); "
              f"understated median {statistics.median(factor):.2f} x (range {min(factor):.2f}-{max(factor):.2f}), "
              f"above 1.5 in {flagged} of {len(v)} twins")
PY
