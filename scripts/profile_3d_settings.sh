#!/usr/bin/env bash
# Before/after numbers of the 3D solver settings (README "3D solver settings: before/after").
#
#   scripts/profile_3d_settings.sh [--reps N] [--j-reps N] [--no-j] [--no-callgrind] COMMIT|BINARY ...
#
# Each argument is a git commit (exported and built, target gapflow only, into
# $PROFILE3D_DIR/<commit>, default /tmp/gapflow-profile3d; ccache is shared with
# CCACHE_BASEDIR so only the files that differ are compiled) or the path of a
# gapflow binary. For each it measures, on the paper's medium discharge cut to
# 300 spheres (scenarios/paper/no_obstruction_medium.toml, 3D):
#   1. callgrind over 0.5 s settling + 2 s flow: instructions per particle-step
#      (total instructions / calls of btRigidBody::applyDamping, which Bullet makes
#      once per dynamic body per step) and the solver's share (inclusive
#      btSequentialImpulseConstraintSolver::solveGroup);
#   2. the same 2.5 s natively, --reps times (default 3): simulated s per wall s
#      and per CPU s (user + sys), median;
#   3. J (paper) of --j-reps replicates (default 6, --jobs 2) of the whole 300-sphere
#      discharge, mean with its 95 % interval as `gapflow run --replicates` prints it.
# Prints one Markdown table row per argument. Needs valgrind (Debian package).
set -euo pipefail

reps=3
j_reps=6
with_j=1
with_callgrind=1
targets=()
while (($#)); do
  case "$1" in
    --reps) reps="$2"; shift 2 ;;
    --j-reps) j_reps="$2"; shift 2 ;;
    --no-j) with_j=0; shift ;;
    --no-callgrind) with_callgrind=0; shift ;;
    -h|--help) sed -n '2,20p' "$0"; exit 0 ;;
    -*) echo "profile_3d_settings.sh: unknown option '$1'" >&2; exit 2 ;;
    *) targets+=("$1"); shift ;;
  esac
done
if ((${#targets[@]} == 0)); then
  echo "usage: scripts/profile_3d_settings.sh [--reps N] [--j-reps N] [--no-j] [--no-callgrind] COMMIT|BINARY ..." >&2
  exit 2
fi
((with_callgrind == 0)) || command -v valgrind >/dev/null || { echo "profile_3d_settings.sh: valgrind missing (apt-get install valgrind)" >&2; exit 2; }

repo="$(cd "$(dirname "$0")/.." && pwd)"
work="${PROFILE3D_DIR:-/tmp/gapflow-profile3d}"
mkdir -p "$work"
scenario="$repo/scenarios/paper/no_obstruction_medium.toml"
common_args=(--model 3d --set particles.count=300)
window_args=(--set run.time_limit_s=2.5)

# A gapflow binary for a commit: exported tree, Release build, target gapflow only.
binary_for() {
  local target="$1"
  if [[ -x "$target" && ! -d "$target" ]]; then echo "$target"; return; fi
  local commit
  commit="$(git -C "$repo" rev-parse --short=10 "$target^{commit}")" || {
    echo "profile_3d_settings.sh: '$target' is neither a binary nor a commit" >&2; exit 2; }
  local src="$work/$commit"
  if [[ ! -x "$src/build/app/gapflow" ]]; then
    rm -rf "$src" && mkdir -p "$src"
    git -C "$repo" archive "$commit" | tar -x -C "$src"
    export CCACHE_BASEDIR="$src"
    cmake -S "$src" -B "$src/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache \
      -DGAPFLOW_BUILD_BENCH=OFF >"$src/build.log" 2>&1
    cmake --build "$src/build" --target gapflow -j2 >>"$src/build.log" 2>&1 ||
      { echo "profile_3d_settings.sh: build of $commit failed, see $src/build.log" >&2; exit 1; }
  fi
  echo "$src/build/app/gapflow"
}

# Instructions per particle-step and solver share, from one callgrind run.
callgrind_numbers() {
  local bin="$1" out="$2"
  valgrind --tool=callgrind --callgrind-out-file="$out" "$bin" run "$scenario" "${common_args[@]}" \
    "${window_args[@]}" --quiet >/dev/null 2>"$out.log"
  callgrind_annotate --inclusive=yes --threshold=100 "$out" >"$out.txt"
  python3 - "$out" "$out.txt" <<'EOF'
import re, sys
raw, annotated = sys.argv[1], sys.argv[2]
total = None
fn_names, calls, current_cfn = {}, 0, None
with open(raw) as f:
    for line in f:
        if line.startswith("summary:") or line.startswith("totals:"):
            total = int(line.split()[1])
        m = re.match(r"cfn=\((\d+)\)(?: (.*))?", line)
        if m:
            if m.group(2): fn_names[m.group(1)] = m.group(2).strip()
            current_cfn = fn_names.get(m.group(1), "")
            continue
        if line.startswith("calls=") and current_cfn and current_cfn.startswith("btRigidBody::applyDamping"):
            calls += int(line.split("=")[1].split()[0])
solver = 0
with open(annotated) as f:
    for line in f:
        if "btSequentialImpulseConstraintSolver::solveGroup(" in line:
            solver = max(solver, int(line.split()[0].replace(",", "")))
print(f"{total / calls:.0f} {100.0 * solver / total:.1f}% {calls}")
EOF
}

# Median simulated s per wall s and per CPU s over `reps` native runs of the window.
speed_numbers() {
  local bin="$1" tmp="$2"
  for ((i = 0; i < reps; ++i)); do
    /usr/bin/time -f "%e %U %S" -o "$tmp.time" "$bin" run "$scenario" "${common_args[@]}" \
      "${window_args[@]}" >"$tmp.out" 2>&1
    local sim
    sim="$(sed -n 's/^time *\([0-9.]*\) s simulated.*/\1/p' "$tmp.out")"
    read -r wall user sys <"$tmp.time"
    python3 -c "print($sim / $wall, $sim / ($user + $sys))"
  done | sort -n | python3 -c "
import sys, statistics
rows = [tuple(map(float, l.split())) for l in sys.stdin]
print(f'{statistics.median(r[0] for r in rows):.2f} {statistics.median(r[1] for r in rows):.2f}')"
}

# Mean J (paper) of the replicated 300-sphere discharge, as printed by --replicates.
j_numbers() {
  local bin="$1" tmp="$2"
  "$bin" run "$scenario" "${common_args[@]}" --replicates "$j_reps" --jobs 2 >"$tmp.j" 2>&1
  grep -i "J (paper)" "$tmp.j" | tail -1 | sed 's/^ *//'
}

echo "| build | instructions / particle-step | solver share | particle-steps | sim s / wall s | sim s / CPU s | J (paper), $j_reps replicates |"
echo "|---|---:|---:|---:|---:|---:|---|"
for target in "${targets[@]}"; do
  bin="$(binary_for "$target")"
  tag="$(echo "$target" | tr '/' '_')"
  ipps="-" share="-" psteps="-"
  if ((with_callgrind)); then read -r ipps share psteps < <(callgrind_numbers "$bin" "$work/callgrind.$tag"); fi
  read -r per_wall per_cpu < <(speed_numbers "$bin" "$work/speed.$tag")
  j="-"
  if ((with_j)); then j="$(j_numbers "$bin" "$work/j.$tag")"; fi
  echo "| $target | $ipps | $share | $psteps | $per_wall | $per_cpu | $j |"
done
