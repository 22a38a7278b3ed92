#!/usr/bin/env bash
# scripts/find_float_roundtrips.py on a compile database of two sources: it lists the function
# that widens a float-rounded pair back to double (exit 1) and not the one that keeps floats;
# a missing database is exit 2. Usage: float_roundtrips_test.sh PYTHON CXX
set -uo pipefail
PYTHON=$1
CXX=$2
HERE=$(cd "$(dirname "$0")" && pwd)
SCRIPT="$HERE/../scripts/find_float_roundtrips.py"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

cat > "$work/compile_commands.json" <<JSON
[
  {"directory": "$HERE/float_roundtrips", "file": "$HERE/float_roundtrips/widened_again.cpp",
   "command": "$CXX -O2 -std=c++20 -c widened_again.cpp -o widened_again.o"},
  {"directory": "$HERE/float_roundtrips", "file": "$HERE/float_roundtrips/kept_single.cpp",
   "command": "$CXX -O2 -std=c++20 -c kept_single.cpp -o kept_single.o"}
]
JSON
"$PYTHON" "$SCRIPT" "$work" > "$work/out.txt" 2>&1
status=$?
[ $status -eq 1 ] || fail "exit $status, expected 1: $(cat "$work/out.txt")"
grep -q "widened_again.cpp: widenedAgain" "$work/out.txt" || fail "widenedAgain not listed: $(cat "$work/out.txt")"
grep -q "keptSingle" "$work/out.txt" && fail "keptSingle listed: $(cat "$work/out.txt")"
grep -q "^1 place where" "$work/out.txt" || fail "not one place: $(cat "$work/out.txt")"
ls "$HERE/float_roundtrips"/*.o 2>/dev/null && fail "object files written"

"$PYTHON" "$SCRIPT" "$work/missing" > "$work/out.txt" 2>&1
status=$?
[ $status -eq 2 ] || fail "a missing database: exit $status, expected 2"
grep -q "cannot read $work/missing/compile_commands.json" "$work/out.txt" || fail "no clear error: $(cat "$work/out.txt")"
echo "ok"
