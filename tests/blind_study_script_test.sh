#!/usr/bin/env bash
# studies/calibration_blind.sh, blind_resignal.sh and score_lean_replay.sh with a stand-in gapflow
# (~15 s): which model seed each twin is given (MODEL_SEEDS=per-twin, the default: 1000 x its seed;
# design: none, so the design's), how many runs each twin's data point averages (TWIN_REPLICATES), that an OUT made with one setting (or before the record, as
# pass 19's) refuses the other before writing anything (exit 2), that a
# resume makes and calibrates nothing again, that the summary says which draw the pass fits, and
# that studies/score_lean_replay.sh replays with the other setting of --independent-signatures, and
# that studies/blind_pass_copy.sh copies a finished pass (and only a finished one) without its stores,
# and that studies/blind_pass_carry.sh carries a cut-off pass to another machine to be resumed there.
#   tests/blind_study_script_test.sh
set -euo pipefail
src=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

# The stand-in: logs its arguments; `twin` writes the twin (its [model] seed: --model-seed, else 1)
# and a truth with nothing planted; `calibrate` writes a summary that found nothing.
cat > "$work/gapflow" <<'STUB'
#!/usr/bin/env bash
# STUB_BINARY: new (knows --shared-signatures; default own seeds), old (neither; default shared) or
# rule5 (as new, and asks rule 5's alternatives, 2 by default, recorded in its summaries).
if [[ $* == *--help* ]]; then
  [[ ${STUB_BINARY:-new} != old ]] && echo "  --independent-signatures,--shared-signatures{false}"
  [[ ${STUB_BINARY:-new} == rule5 ]] && echo "  --alternatives INT:INT in [0 - 9]"
  # More help after the options, longer than a pipe holds: a script that reads it as
  # `gapflow --help | grep -q` under pipefail then fails every time (grep exits at the match, this
  # writer dies of SIGPIPE), not only when the scheduler happens to interleave them so (CI, 2026-11-29).
  printf '%*s\n' 200000 ''
  exit 0
fi
echo "$*" >> "$STUB_LOG"
command=$1; shift
own_seeds=false
[[ ${STUB_BINARY:-new} != old ]] && own_seeds=true
alternatives_field=""
[[ ${STUB_BINARY:-new} == rule5 ]] && alternatives_field='"alternatives": 2, '
[[ $* == *--independent-signatures* ]] && own_seeds=true
[[ $* == *--shared-signatures* ]] && own_seeds=false
out="" truth="" model_seed=1 replicates=10
while [[ $# -gt 0 ]]; do
  case $1 in
    --out) out=$2; shift ;;
    --truth) truth=$2; shift ;;
    --model-seed) model_seed=$2; shift ;;
    --replicates) replicates=$2; shift ;;
    --alternatives) alternatives_field="\"alternatives\": $2, "; shift ;;
  esac
  shift
done
if [[ $command == twin ]]; then
  printf '[model]\nscenario = "x.toml"\nseed = %s\n' "$model_seed" > "$out"
  # STUB_POINTS: J_mid at three inclines (as sqrt(sin theta): spread 0.900 over 3-20 deg), for the null
  # twins that quadratic_drag_visibility.py reads.
  [[ -n ${STUB_POINTS:-} ]] && printf '[observable]\nkind = "j_mid"\n%s' \
    "$(for t in 3 8 20; do printf '[[point]]\nW_over_d = 4.5\nincline_deg = %s\nshape = "none"\nvalue = %s\n' \
       $t "$(awk -v t=$t 'BEGIN { print 100 * sqrt(sin(t * 3.14159265358979 / 180)) }')"; done)" >> "$out"
  # The new stand-in's truth records the data's runs per point, as gapflow twin's does; the old one's not.
  runs_field=""
  [[ ${STUB_BINARY:-new} == new ]] && runs_field=", \"replicates\": $replicates"
  printf '{"twin": "t", "model": "2d", "seed": 1%s, "planted": [{"name": "free", "key": "k", "value": 0.3, "neutral": null}], "measured": {}}\n' "$runs_field" > "$truth"
else
  mkdir -p "$out"
  : > "$out/report.md"
  checks=""  # STUB_POINTS: a linear drag's check along the incline that sees a spread of 0.9
  [[ -n ${STUB_POINTS:-} ]] && checks='"form_checks": [{"effect": "linear_drag", "column": "incline_deg", "statistic": 2.0, "dof": 2, "rest_dof": 41, "p_adjusted": 0.5, "scale": 1.0, "spread_level": 0.01, "detectable_spread": 0.9}], '
  errors='{"n": 12, "rmse": 0.1, "rms_whitened": 1.0, "chi2": 12.0, "dof": 12, "p": 0.5, "invalid": 0}'
  printf '{"effects": [], "verdict": "consistent with noise", "poor_fit": false, "held_out_beyond_noise": false, "before": {"fitted": %s, "held_out_fresh": %s}, "after": {"params": {"k": 0.3}, "fitted": %s, "held_out_fresh": %s}, "measured_free": [], "rounds": [], %s%s"independent_signatures": %s, "runs_simulated": 10, "runs_reused": 0, "run_seconds": 1.0, "wall_seconds": 1.0}\n' \
    "$errors" "$errors" "$errors" "$errors" "$checks" "$alternatives_field" "$own_seeds" > "$out/summary.json"
fi
STUB
chmod +x "$work/gapflow"
export GAPFLOW=$work/gapflow STUB_LOG=$work/log
blind() { "$src/studies/calibration_blind.sh" "$@" > "$work/stdout" 2> "$work/stderr"; }
design=data/blind/design_v2.toml
source "$src/studies/blind_cases.sh"
cases=$(grep -c . <<< "$blind_cases")

blind "$work/own" 1 16000 $design || fail "per-twin pass (the default): $(cat "$work/stderr")"
while read -r id model seed planted; do
  [[ -n $id ]] || continue
  grep -qx "seed = $(((seed + 16000) * 1000))" "$work/own/twins/$id.toml" || fail "$id: not its own model seed"
done <<< "$blind_cases"
[[ $(grep -c '^calibrate ' "$work/log") == "$cases" ]] || fail "not $cases calibrations"
grep -q "every twin its own model seed" "$work/own/report.md" || fail "the summary does not say the seeds are per twin"
grep -q "the signatures on seeds of their own" "$work/own/report.md" || fail "the summary does not say the signatures' seeds"
[[ $(grep -c -- '^twin .* --replicates 10 ' "$work/log") == "$cases" ]] || fail "the twins' data are not of 10 runs by default"
grep -q "data of 10 runs per point" "$work/own/report.md" || fail "the summary does not say the data's runs per point"

# TWIN_REPLICATES sets the runs in each twin's data point, and says so in the summary.
: > "$work/log"
TWIN_REPLICATES=020 blind "$work/twenty" 1 16000 $design || fail "TWIN_REPLICATES=020: $(cat "$work/stderr")"
[[ $(cat "$work/twenty/twin_replicates") == 20 ]] || fail "020 not recorded as 20"
[[ $(grep -c -- '^twin .* --replicates 20 ' "$work/log") == "$cases" ]] || fail "TWIN_REPLICATES=20 did not reach every twin"
grep -q "data of 20 runs per point" "$work/twenty/report.md" || fail "the summary does not say 20 runs per point"

MODEL_SEEDS=design blind "$work/shared" 1 16000 $design || fail "design-seed pass: $(cat "$work/stderr")"
if grep -q -- "--model-seed" <(grep "shared/twins" "$work/log"); then fail "MODEL_SEEDS=design gave a model seed"; fi
grep -q "one draw of the model's noise" "$work/shared/report.md" || fail "the summary does not say one draw"
grep -qx "seed = 1" "$work/shared/twins/null-1.toml" || fail "MODEL_SEEDS=design: not the design's seed"

# A resume makes nothing again; the other setting, or a bad one, is refused before anything is made.
: > "$work/log"
blind "$work/own" 1 16000 $design || fail "resume: $(cat "$work/stderr")"
[[ ! -s $work/log ]] || fail "a resume ran gapflow: $(head -1 "$work/log")"
rm "$work/own/null-1/summary.json" "$work/own/twins/null-1.toml"
set +e
MODEL_SEEDS=design blind "$work/own" 1 16000 $design; rc_default=$?
MODEL_SEEDS=perTwin blind "$work/new" 1 16000 $design; rc_bad=$?
set -e
[[ $rc_default == 2 ]] || fail "a per-twin OUT resumed with the design's seeds: exit $rc_default"
[[ $rc_bad == 2 ]] || fail "MODEL_SEEDS=perTwin: exit $rc_bad"
grep -q "allowed: per-twin, design" "$work/stderr" || fail "no clear error: $(cat "$work/stderr")"
[[ ! -e $work/new ]] || fail "a refused run left $work/new behind"
[[ ! -s $work/log ]] || fail "a refused run ran gapflow: $(head -1 "$work/log")"
[[ $(cat "$work/own/model_seeds") == per-twin ]] || fail "a refused run changed the record"
set +e
TWIN_REPLICATES=20 blind "$work/own" 1 16000 $design; rc_replicates=$?
grep -q "made with TWIN_REPLICATES 10, not 20" "$work/stderr" || fail "no clear error for other replicates: $(cat "$work/stderr")"
TWIN_REPLICATES=1 blind "$work/new" 1 16000 $design; rc_one=$?
grep -q "TWIN_REPLICATES is '1'; allowed: a whole number of runs from 2 to 1000" "$work/stderr" || fail "no clear error for 1 run: $(cat "$work/stderr")"
TWIN_REPLICATES=ten blind "$work/new" 1 16000 $design; rc_word=$?
set -e
[[ $rc_replicates == 2 && $rc_one == 2 && $rc_word == 2 ]] || fail "bad or other replicates: exits $rc_replicates $rc_one $rc_word"
[[ ! -e $work/new && ! -s $work/log ]] || fail "a refused TWIN_REPLICATES ran or wrote"
[[ $(cat "$work/own/twin_replicates") == 10 ]] || fail "a refused run changed the replicates' record"

# A pass folder from before the record (twins, no model_seeds) used the design's seed: the default
# (per-twin) is refused there, and nothing of it changes.
mkdir -p "$work/old/twins" && cp "$work/shared/twins/null-1.toml" "$work/old/twins/"
echo 16000 > "$work/old/seed_offset" && echo $design > "$work/old/design"   # as pass 19's folder
set +e
blind "$work/old" 1 16000 $design; rc_old=$?
set -e
[[ $rc_old == 2 ]] || fail "a pass folder without the record resumed with a seed per twin: exit $rc_old"
grep -q "made with MODEL_SEEDS design, not per-twin" "$work/stderr" || fail "no clear error: $(cat "$work/stderr")"
set +e
MODEL_SEEDS=design TWIN_REPLICATES=20 blind "$work/old" 1 16000 $design; rc_old_runs=$?
set -e
[[ $rc_old_runs == 2 ]] || fail "a pass folder without the record resumed with 20 runs per point: exit $rc_old_runs"
grep -q "made with TWIN_REPLICATES 10, not 20" "$work/stderr" || fail "no clear error: $(cat "$work/stderr")"
[[ $(ls "$work/old" | tr '\n' ' ') == "design seed_offset twins " ]] || fail "a refused run wrote into the old pass folder: $(ls "$work/old")"

# The oracle's remaking gives each twin the model seed the pass gave it (else its twin differs).
"$src/studies/blind_resignal.sh" "$work/own" "$work/resignal" "$work/none.sqlite" 1 rolling-low \
  > /dev/null 2> "$work/stderr" || true
grep -q -- "--model-seed 16111000" "$work/log" || fail "blind_resignal.sh did not remake rolling-low with its model seed"
if grep -q "differs from" "$work/stderr"; then fail "the remade twin differs: $(cat "$work/stderr")"; fi
: > "$work/log"
"$src/studies/blind_resignal.sh" "$work/twenty" "$work/resignal-twenty" "$work/none.sqlite" 1 rolling-low \
  > /dev/null 2> "$work/stderr" || true
grep -q -- "--replicates 20 " "$work/log" || fail "blind_resignal.sh did not remake a TWIN_REPLICATES=20 twin of 20 runs"
# A replay of the nulls toggles the signatures' setting, read from the pass's calibrations (a pass
# without either flag ran its binary's default), and keeps the pass's other options. The passes above
# ran on the new stand-in (own seeds by default): replayed shared.
touch "$work/store.sqlite"
: > "$work/log"
"$src/studies/score_lean_replay.sh" "$work/own" "$work/store.sqlite" "$work/lean-own" 1 null-2 > /dev/null 2>&1 || true
grep -q -- "--no-plots --shared-signatures$" "$work/log" || fail "the replay of a pass on own seeds by default: $(cat "$work/log")"
# A pass by an old binary (shared by default, no flag) is replayed with --independent-signatures.
STUB_BINARY=old MODEL_SEEDS=design blind "$work/old-binary" 1 16000 $design || fail "old-binary pass: $(cat "$work/stderr")"
: > "$work/log"
STUB_BINARY=old "$src/studies/score_lean_replay.sh" "$work/old-binary" "$work/store.sqlite" "$work/lean-old" 1 null-2 \
  > /dev/null 2>&1 || true
grep -q -- "--no-plots --independent-signatures$" "$work/log" || fail "the replay of an old binary's pass: $(cat "$work/log")"
MODEL_SEEDS=design blind "$work/both" 1 16000 $design --held-out-route --independent-signatures || fail "pass with options: $(cat "$work/stderr")"
: > "$work/log"
"$src/studies/score_lean_replay.sh" "$work/both" "$work/store.sqlite" "$work/lean-both" 1 null-2 > /dev/null 2>&1 || true
grep -q -- "--no-plots --held-out-route --shared-signatures$" "$work/log" || fail "the replay of a pass with the option: $(cat "$work/log")"
# A pass on own seeds replayed by an old binary (as pass 20's replay by its own binary): no flag,
# its default being shared.
: > "$work/log"
STUB_BINARY=old "$src/studies/score_lean_replay.sh" "$work/both" "$work/store.sqlite" "$work/lean-both-old" 1 null-2 \
  > /dev/null 2>&1 || true
grep -q -- "--no-plots --held-out-route$" "$work/log" || fail "an old binary's replay of an own-seeds pass: $(cat "$work/log")"
# Rule 5 as the pass ran it, where the replay's binary knows the option (and asks 2 by default): a
# pass from before it (no record) is replayed with --alternatives 0, one that asked 2 with 2.
: > "$work/log"
STUB_BINARY=rule5 "$src/studies/score_lean_replay.sh" "$work/own" "$work/store.sqlite" "$work/lean-own-rule5" 1 null-2 \
  > /dev/null 2>&1 || true
grep -q -- "--no-plots --shared-signatures --alternatives 0$" "$work/log" || fail "a pass before rule 5 replayed by a binary with it: $(cat "$work/log")"
STUB_BINARY=rule5 MODEL_SEEDS=design blind "$work/rule5" 1 16000 $design || fail "rule-5 pass: $(cat "$work/stderr")"
: > "$work/log"
STUB_BINARY=rule5 "$src/studies/score_lean_replay.sh" "$work/rule5" "$work/store.sqlite" "$work/lean-rule5" 1 null-2 \
  > /dev/null 2>&1 || true
grep -q -- "--no-plots --shared-signatures --alternatives 2$" "$work/log" || fail "a pass with rule 5 replayed: $(cat "$work/log")"
# A replay's OUT is not resumed with other options (here: another pass's).
set +e
"$src/studies/score_lean_replay.sh" "$work/own" "$work/store.sqlite" "$work/lean-both" 1 null-2 > /dev/null 2> "$work/stderr"
rc_replay=$?
set -e
[[ $rc_replay == 2 ]] && grep -q "was calibrated with '--held-out-route --shared-signatures'" "$work/stderr" ||
  fail "a replay OUT resumed with other options: exit $rc_replay, $(cat "$work/stderr")"
# A finished pass copied into the repository's results: no stores, the twins naming the same
# scenario file from their new place; an unfinished pass, or a destination holding one, refused.
touch "$work/own/runs.sqlite"
"$src/studies/blind_pass_copy.sh" "$work/own" "$work/results/pass" > /dev/null 2> "$work/stderr" ||
  fail "copying a finished pass: $(cat "$work/stderr")"
[[ -z $(find "$work/results/pass" -name '*.sqlite*') ]] || fail "a store was copied"
[[ -f $work/results/pass/report.md && -f $work/results/pass/lean.txt ]] || fail "no summary or lean in the copy"
copied=$(sed -n 's/^scenario = "\(.*\)"$/\1/p' "$work/results/pass/twins/null-2.toml")
[[ $(realpath -m "$work/results/pass/twins/$copied") == $(realpath -m "$work/own/twins/x.toml") ]] ||
  fail "the copied twin names another scenario: $copied"
set +e
"$src/studies/blind_pass_copy.sh" "$work/own" "$work/results/pass" > /dev/null 2>&1; rc_again=$?
rm "$work/shared/null-3/summary.json"
"$src/studies/blind_pass_copy.sh" "$work/shared" "$work/results/unfinished" > /dev/null 2> "$work/stderr"; rc_unfinished=$?
set -e
[[ $rc_again == 2 ]] || fail "copied over a pass: exit $rc_again"
[[ $rc_unfinished == 2 && ! -e $work/results/unfinished ]] || fail "an unfinished pass was copied: exit $rc_unfinished"
grep -q "null-3 has no summary.json" "$work/stderr" || fail "no clear error: $(cat "$work/stderr")"
# A pass cut off by its machine's end, carried through the repository by studies/blind_pass_carry.sh
# and resumed on another: only what had finished is carried (no store, no calibration still running),
# the resumed pass makes only what was missing, and a carried file is never overwritten.
blind "$work/whole" 1 16000 $design || fail "a whole pass: $(cat "$work/stderr")"
touch "$work/whole/runs.sqlite"
cp -r "$work/whole" "$work/cut"
# null-1: cut off before its summary; null-3: its summary written, its calibration not yet ended
# (/usr/bin/time creates the .time empty at the start and writes it at the end); null-4: no twin yet.
rm "$work/cut/null-1/summary.json"
: > "$work/cut/null-1.time"
: > "$work/cut/null-3.time"
rm -r "$work/cut/null-4" "$work/cut/null-4.time" "$work/cut/twins/null-4.toml" "$work/cut/truth/null-4.json"
# studies/calibration_replay.sh replays what the cut-off pass has finished, and only that.
replay() { "$src/studies/calibration_replay.sh" "$@" > "$work/stdout" 2> "$work/stderr"; }
: > "$work/log"
/usr/bin/python3 -c 'import sqlite3, sys; s = sqlite3.connect(sys.argv[1]); s.execute("pragma journal_mode=wal")
s.execute("create table runs (key text)"); s.execute("insert into runs values (?)", ("kept",)); s.commit()' "$work/cut/runs.sqlite"
replay "$work/cut" replay-x 1 || fail "replaying a cut-off pass: $(cat "$work/stderr")"
[[ $(/usr/bin/python3 -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute("select key from runs").fetchone()[0])' \
     "$work/cut/replay-x/runs.sqlite") == kept ]] || fail "the replay's copy of the store lacks the pass's runs"
[[ $(grep -c '^calibrate ' "$work/log") == $((cases - 3)) ]] && ! grep -q "null-[134]" "$work/log" ||
  fail "the replay of a cut-off pass calibrated other twins than the finished ones: $(cat "$work/log")"
grep -q "2 twin(s) left for a later run" "$work/stderr" || fail "the replay does not say what it left: $(cat "$work/stderr")"
# ONLY: the twins named, and no other; a name without a twin is refused.
: > "$work/log"
ONLY="null-2" replay "$work/cut" replay-only 1 || fail "a replay of one named twin: $(cat "$work/stderr")"
[[ $(grep -c '^calibrate ' "$work/log") == 1 ]] && grep -q "^calibrate .*null-2.toml" "$work/log" && [[ ! -s $work/stderr ]] ||
  fail "ONLY=null-2 did not replay exactly null-2: $(cat "$work/log") $(cat "$work/stderr")"
rm -r "$work/cut/replay-only"
: > "$work/log"
ONLY=$'null-2\tnull-3\n' replay "$work/cut" replay-only 1 || fail "ONLY with a tab and a newline: $(cat "$work/stderr")"
grep -q "^calibrate .*null-2.toml" "$work/log" || fail "ONLY split on a tab lost null-2: $(cat "$work/log")"
grep -q "1 twin(s) left for a later run" "$work/stderr" || fail "ONLY's unfinished null-3 not said: $(cat "$work/stderr")"
rm -r "$work/cut/replay-only"
set +e
ONLY="null-2 nothing-9" replay "$work/cut" replay-only 1; rc_only=$?
grep -q "ONLY names 'nothing-9'" "$work/stderr"; said_only=$?
ONLY=" " replay "$work/cut" replay-blank 1; rc_blank=$?
ONLY="../twins/null-2" replay "$work/cut" replay-path 1; rc_path=$?
set -e
[[ $rc_only == 2 && $said_only == 0 ]] || fail "an unknown ONLY name: exit $rc_only"
[[ $rc_blank == 2 && $rc_path == 2 && ! -e $work/cut/replay-only && ! -e $work/cut/replay-blank && ! -e $work/cut/replay-path ]] ||
  fail "a refused ONLY wrote its folder, or a blank ONLY or a path was not refused (exit $rc_blank, $rc_path)"
carry() { "$src/studies/blind_pass_carry.sh" "$@" > "$work/stdout" 2> "$work/stderr"; }
carry save "$work/cut" "$work/carry" || fail "saving a cut-off pass: $(cat "$work/stderr")"
[[ -z $(find "$work/carry" -name '*.sqlite*') ]] || fail "a store was carried"
[[ -f $work/carry/replay-x/replay.made_by && -f $work/carry/replay-x/null-2/summary.json && -s $work/carry/replay-x/null-2.time &&
   ! -e $work/carry/replay-x/report.md ]] || fail "the replay was not carried, or its partial summary was"
[[ -f $work/carry/twins/null-1.toml && -f $work/carry/twins/null-3.toml && ! -e $work/carry/null-1 && ! -e $work/carry/null-3 &&
   ! -e $work/carry/null-3.time && ! -e $work/carry/twins/null-4.toml ]] ||
  fail "the carry holds a calibration that had not finished, or lacks a twin that had"
carry save "$work/cut" "$work/carry" && grep -q "^saved 0 new files" "$work/stdout" || fail "a second save copied again"
[[ $(wc -l < "$work/carry/saves.txt") == 2 ]] || fail "saves.txt does not log each save"
carry restore "$work/carry" "$work/resumed" || fail "restoring: $(cat "$work/stderr")"
: > "$work/log"
blind "$work/resumed" 1 16000 $design || fail "resuming a carried pass: $(cat "$work/stderr")"
[[ $(grep -c '^twin ' "$work/log") == 1 && $(grep -c '^calibrate ' "$work/log") == 3 ]] ||
  fail "the resumed pass did not make exactly the missing twin and calibrations: $(cat "$work/log")"
cmp -s "$work/resumed/null-2/summary.json" "$work/whole/null-2/summary.json" || fail "a carried calibration changed"
# The carried replay goes on where it stopped, on the new machine's store.
touch "$work/resumed/runs.sqlite"
: > "$work/log"
replay "$work/resumed" replay-x 1 || fail "continuing a carried replay: $(cat "$work/stderr")"
[[ $(grep -c '^calibrate ' "$work/log") == 3 && -f $work/resumed/replay-x/truth/null-4.json ]] ||
  fail "the carried replay did not calibrate exactly the three twins it had left: $(cat "$work/log")"
echo "changed" > "$work/cut/twins/null-2.toml"
set +e
carry save "$work/cut" "$work/carry"; rc_differs=$?
grep -q "null-2.toml exists and differs" "$work/stderr"; said_differs=$?
carry save "$work/nothing" "$work/carry"; rc_missing=$?
set -e
[[ $rc_differs == 2 && $said_differs == 0 ]] || fail "a differing file: exit $rc_differs, $(cat "$work/stderr")"
cmp -s "$work/carry/twins/null-2.toml" "$work/whole/twins/null-2.toml" || fail "a carried file was overwritten"
[[ $rc_missing == 2 ]] || fail "saving from a missing folder: exit $rc_missing"
# studies/blind_pass_session.sh: one machine's share, the carry put back, the launch recorded, all
# that finished saved; a second machine's share then has nothing to make.
session() { "$src/studies/blind_pass_session.sh" "$@" > "$work/stdout" 2> "$work/stderr"; }
: > "$work/log"
session "$work/carry2" "$work/sess" env GAPFLOW="$work/gapflow" "$src/studies/calibration_blind.sh" "$work/sess" 1 16000 $design ||
  fail "a session: $(cat "$work/stderr")"
[[ $(find "$work/carry2" -name summary.json | wc -l) == "$cases" ]] || fail "the session did not save every calibration"
grep -q "launch 1 at .*, binary $work/gapflow, sha256 [0-9a-f]\{16\}$" "$work/carry2/launches.txt" &&
  grep -q "launch 1: the pass's command ended with exit 0" "$work/carry2/launches.txt" || fail "launch not recorded: $(cat "$work/carry2/launches.txt")"
: > "$work/log"
session "$work/carry2" "$work/sess2" env GAPFLOW="$work/gapflow" "$src/studies/calibration_blind.sh" "$work/sess2" 1 16000 $design ||
  fail "a second session: $(cat "$work/stderr")"
[[ ! -s $work/log ]] || fail "the second session made again what the first had carried: $(head -1 "$work/log")"
grep -q "launch 2 at " "$work/carry2/launches.txt" || fail "the second launch is not numbered 2"
# {launch} in the command is the launch's number; another binary than the last launch's is refused.
session "$work/carry2" "$work/sess2" env GAPFLOW="$work/gapflow" touch "$work/timev{launch}" &&
  [[ -f $work/timev3 ]] || fail "{launch} not replaced by 3: $(ls "$work")"
cp "$work/gapflow" "$work/gapflow-other" && echo "# other" >> "$work/gapflow-other"
set +e
session "$work/carry2" "$work/sess2" env GAPFLOW="$work/gapflow-other" true; rc_other=$?
set -e
[[ $rc_other == 2 ]] && grep -q "ALLOW_OTHER_BINARY=1" "$work/stderr" && ! grep -q "launch 4 at " "$work/carry2/launches.txt" ||
  fail "another binary was not refused: exit $rc_other, $(cat "$work/stderr")"
ALLOW_OTHER_BINARY=1 session "$work/carry2" "$work/sess2" env GAPFLOW="$work/gapflow-other" true &&
  grep -q "launch 4 at .*gapflow-other" "$work/carry2/launches.txt" || fail "ALLOW_OTHER_BINARY=1 refused"

# A stop (SIGTERM to the pid the session writes beside PASS) reaches the whole command, the
# command's own children too, and is saved and recorded.
"$src/studies/blind_pass_session.sh" "$work/carry2" "$work/sess2" env GAPFLOW="$work/gapflow-other" \
  bash -c "touch '$work/started'; (sleep 3; touch '$work/not-stopped') & wait" > /dev/null 2>&1 &
session_pid=$!
for _ in $(seq 100); do [[ -e $work/started && -s $work/sess2.session-pid ]] && break; sleep 0.2; done
[[ $(cat "$work/sess2.session-pid") == "$session_pid" ]] || fail "the session's pid file does not name it"
kill -TERM "$(cat "$work/sess2.session-pid")"
set +e; wait "$session_pid"; rc_stop=$?; set -e
sleep 3.5
[[ ! -e $work/not-stopped ]] || fail "the stop did not reach the command's children"
grep -q "launch 5: stopped by a signal" "$work/carry2/launches.txt" || fail "the stop not recorded: $(tail -2 "$work/carry2/launches.txt")"
[[ $rc_stop != 0 && ! -e $work/sess2.session-pid ]] || fail "a stopped session exited 0 or left its pid file"

# What must not be carried: a twin whose truth is not written yet, a calibration whose .time says
# it failed. A copy that fails is an error, not a file counted as there.
mkdir -p "$work/odd/twins" "$work/odd/truth" "$work/odd/null-2"
cp "$work/whole/twins/null-1.toml" "$work/odd/twins/"
cp "$work/whole/twins/null-2.toml" "$work/odd/twins/" && cp "$work/whole/truth/null-2.json" "$work/odd/truth/"
cp "$work/whole/null-2/summary.json" "$work/odd/null-2/"
printf 'Command exited with non-zero status 1\n3.00 s wall\n' > "$work/odd/null-2.time"
carry save "$work/odd" "$work/carry-odd" || fail "saving the odd pass: $(cat "$work/stderr")"
[[ ! -e $work/carry-odd/twins/null-1.toml && -f $work/carry-odd/twins/null-2.toml && ! -e $work/carry-odd/null-2 ]] ||
  fail "a twin without its truth, or a failed calibration, was carried"
mkdir -p "$work/blocked" && : > "$work/blocked/twins"   # a file where the twins' folder goes: even root cannot copy
set +e
carry save "$work/whole" "$work/blocked"; rc_copy=$?
set -e
[[ $rc_copy == 2 ]] && grep -q "could not copy" "$work/stderr" || fail "a failed copy was not an error: exit $rc_copy, $(cat "$work/stderr")"

# A replay killed earlier left its store's log behind: the new copy of the pass's store is what the
# replay reads, not the old copy with the old log applied.
/usr/bin/python3 -c 'import os, sqlite3, sys
s = sqlite3.connect(sys.argv[1]); s.execute("pragma journal_mode=wal"); s.execute("create table runs (key text)")
s.execute("insert into runs values (?)", ("stale",)); s.commit(); os._exit(0)' "$work/stale.sqlite"
[[ -s $work/stale.sqlite-wal ]] || fail "the test could not leave a log behind"
cp "$work/stale.sqlite" "$work/cut/replay-x/runs.sqlite" && cp "$work/stale.sqlite-wal" "$work/cut/replay-x/runs.sqlite-wal"
rm -r "$work/cut/replay-x/null-2"
replay "$work/cut" replay-x 1 || fail "replaying again: $(cat "$work/stderr")"
[[ $(/usr/bin/python3 -c 'import sqlite3, sys; print(sqlite3.connect(sys.argv[1]).execute("select key from runs").fetchone()[0])' \
     "$work/cut/replay-x/runs.sqlite") == kept ]] || fail "the replay's store copy read the stale log"
# studies/form_check_power.sh: DRAWS null and quadratic-drag twins on their seeds (draw 1 on the blind
# study's null-1 and outside-quadratic-16 seeds at the offset), each its own model seed, summarised
# with the folder's own design and seeds; the check's power against the drag from the null twins'
# J_mid; a resume makes nothing again, a cut-off calibration or a twin without its truth is made
# again; other settings, a foreign folder, bad numbers are refused before anything is written.
power() { STUB_POINTS=1 "$src/studies/form_check_power.sh" "$@" > "$work/stdout" 2> "$work/stderr"; }
wide=data/blind/design_v4_wide.toml
: > "$work/log"
DRAWS=2 power "$work/power" 1 19000 $wide || fail "form_check_power.sh: $(cat "$work/stderr")"
[[ $(grep -c '^twin ' "$work/log") == 4 && $(grep -c '^calibrate ' "$work/log") == 4 ]] || fail "not 4 twins and 4 calibrations"
grep -q -- "--seed 19101 .*--name null-1 .*--model-seed 19101000$" "$work/log" || fail "null-1 not on its seeds"
grep -q -- "--seed 19143 .*--name quadratic-16-1 .*--set particles.quadratic_drag_per_m=16 --model-seed 19143000$" "$work/log" ||
  fail "quadratic-16-1 not on the blind study's outside-quadratic-16 seeds at the offset: $(grep quadratic-16-1 "$work/log")"
grep -q -- "--seed 19144 .*--name quadratic-16-2 .*--model-seed 19144000$" "$work/log" || fail "quadratic-16-2 not on its seeds"
if grep -q -- "--name null-.*--set" "$work/log"; then fail "a null twin was planted with something"; fi
grep -q "Made by \`studies/form_check_power.sh\` (twins of \`$wide\`" "$work/power/report.md" ||
  fail "report.md does not say what made it of which design: $(grep 'Made by' "$work/power/report.md")"
grep -q "data of 10 runs per point; every twin its own model seed" "$work/power/report.md" || fail "report.md misstates the seeds"
[[ -s $work/power/form_checks.txt ]] || fail "no form-check table"
grep -q "^median 0.900 " "$work/power/quadratic_drag_visibility-2.txt" &&
  grep -q "^quadratic-16-2: .*power at the spread a quadratic drag asks for (0.900): 0.80 at the stated noise" \
  "$work/power/quadratic_drag_visibility-2.txt" || fail "no power: $(cat "$work/power/quadratic_drag_visibility-2.txt")"
: > "$work/log"
DRAWS=2 power "$work/power" 1 019000 $wide || fail "form_check_power.sh resumed: $(cat "$work/stderr")"
[[ ! -s $work/log ]] || fail "a resume (offset 019000, read as 19000) ran gapflow: $(head -1 "$work/log")"
: > "$work/power/null-2.time"               # cut off: time made its record and the command never ended
rm "$work/power/truth/quadratic-16-1.json"  # cut off between the twin's data file and its truth
DRAWS=2 power "$work/power" 1 19000 $wide || fail "form_check_power.sh after a cut: $(cat "$work/stderr")"
[[ $(cut -d' ' -f1 "$work/log" | sort | uniq -c | tr -s ' ' | tr '\n' ';') == " 2 calibrate; 1 twin;" ]] &&
  grep -q "^calibrate .*null-2.toml" "$work/log" && grep -q "^twin .*--name quadratic-16-1 " "$work/log" ||
  fail "not exactly the cut-off calibration and twin made again: $(cat "$work/log")"
: > "$work/log"
set +e
DRAWS=3 power "$work/power" 1 19000 $wide; rc_draws=$?
TWIN_REPLICATES=20 DRAWS=2 power "$work/power" 1 19000 $wide; rc_runs=$?
DRAWS=2 power "$work/power" 1 19001 $wide; rc_offset=$?
grep -q "made with other settings" "$work/stderr" || fail "no clear error: $(cat "$work/stderr")"
DRAWS=2 power "$work/own" 1 19000 $wide; rc_foreign=$?
grep -q "no record of this script's settings" "$work/stderr" || fail "a foreign folder: $(cat "$work/stderr")"
DRAWS=08x power "$work/new" 1 19000 $wide; rc_bad=$?
grep -q "DRAWS is '08x'; allowed: a whole number from 1 to 40" "$work/stderr" || fail "bad DRAWS: $(cat "$work/stderr")"
set -e
[[ "$rc_draws $rc_runs $rc_offset $rc_foreign $rc_bad" == "2 2 2 2 2" ]] ||
  fail "not refused: exits $rc_draws $rc_runs $rc_offset $rc_foreign $rc_bad"
[[ ! -s $work/log && ! -e $work/new && $(grep -c '^draws 2$' "$work/power/settings") == 1 ]] ||
  fail "a refused run ran gapflow, wrote or changed the record"
# Carried to another machine (blind_pass_carry.sh, as a pass) and resumed there: nothing made again.
"$src/studies/blind_pass_carry.sh" save "$work/power" "$work/power-carry" > /dev/null 2>&1 || fail "carrying the power folder"
"$src/studies/blind_pass_carry.sh" restore "$work/power-carry" "$work/power-there" > /dev/null 2>&1 || fail "restoring it"
DRAWS=2 power "$work/power-there" 1 19000 $wide || fail "form_check_power.sh on the carried folder: $(cat "$work/stderr")"
[[ ! -s $work/log ]] || fail "the carried folder's resume ran gapflow: $(head -1 "$work/log")"

echo "ok"
