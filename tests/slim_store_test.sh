#!/usr/bin/env bash
# scripts/slim_store.py end to end on the tiny study (~5 s): the copy keeps every run, clog and
# avalanche and no crossing row; a study resumed on it runs nothing again; its report says the
# snapshots cannot be compared with stored crossings (instead of calling the runs
# unreproducible); a file that is not a store is never overwritten.
#   tests/slim_store_test.sh GAPFLOW
set -euo pipefail
gapflow=$1
src=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
count() { /usr/bin/python3 -c "import sqlite3,sys; print(sqlite3.connect(sys.argv[1]).execute(sys.argv[2]).fetchone()[0])" "$@"; }

"$gapflow" study "$src/studies/examples/tiny.toml" --db "$work/full.sqlite" --jobs 2 > /dev/null 2>&1
/usr/bin/python3 "$src/scripts/slim_store.py" "$work/full.sqlite" "$work/slim.sqlite"

for table in runs clogs avalanches; do
  a=$(count "$work/full.sqlite" "SELECT count(*) FROM $table")
  b=$(count "$work/slim.sqlite" "SELECT count(*) FROM $table")
  [[ $a == "$b" && $a -gt 0 ]] || fail "$table: $a rows in the store, $b in the slim copy"
done
[[ $(count "$work/full.sqlite" "SELECT count(*) FROM crossings") -gt 0 ]] || fail "the tiny study stored no crossings"
[[ $(count "$work/slim.sqlite" "SELECT count(*) FROM crossings") == 0 ]] || fail "the slim copy kept crossings"

resumed=$("$gapflow" study "$src/studies/examples/tiny.toml" --db "$work/slim.sqlite" --jobs 2 2>&1)
grep -q " 0 runs done now" <<< "$resumed" || fail "resuming on the slim copy ran jobs again: $resumed"

"$gapflow" report "$work/slim.sqlite" --study "$src/studies/examples/tiny.toml" --out "$work/report" > /dev/null 2>&1
grep -q "keeps no crossing times" "$work/report/report.md" || fail "the report does not say the store has no crossings"
if grep -q "no longer reproduces" "$work/report/report.md"; then fail "the report calls the slimmed runs unreproducible"; fi

echo "not a store" > "$work/notes.txt"
if /usr/bin/python3 "$src/scripts/slim_store.py" "$work/full.sqlite" "$work/notes.txt" 2> "$work/err"; then
  fail "overwrote a file that is not a store"
fi
[[ $(cat "$work/notes.txt") == "not a store" ]] || fail "the user's file changed"
grep -q "not a results store" "$work/err" || fail "no clear error: $(cat "$work/err")"
# Never the source itself, never a full store without --force.
if /usr/bin/python3 "$src/scripts/slim_store.py" "$work/full.sqlite" "$work/full.sqlite" 2> "$work/err"; then
  fail "slimmed the source store in place"
fi
cp "$work/full.sqlite" "$work/other_full.sqlite"
if /usr/bin/python3 "$src/scripts/slim_store.py" "$work/slim.sqlite" "$work/other_full.sqlite" 2> "$work/err"; then
  fail "overwrote a full store without --force"
fi
grep -q "full store" "$work/err" || fail "no clear error for a full destination: $(cat "$work/err")"
[[ $(count "$work/other_full.sqlite" "SELECT count(*) FROM crossings") -gt 0 ]] || fail "the full store lost its crossings"
echo "slim store: ok"
