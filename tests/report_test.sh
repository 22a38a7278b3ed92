#!/usr/bin/env bash
# Pictures as a user opens them (issue 23).
#   report_test.sh export NBV_BINARY       the PLY export read back: counts, colours, faces, frusta
#   report_test.sh report NBV_BINARY OUT   the HTML report of a run opened in headless Chromium:
#       the page says it rendered, no script error, the 3D view not blank; the screenshot is
#       left at OUT. Exits 77 (skipped) after the checks without a browser if chromium is missing.
set -euo pipefail
MODE="$1"
NBV="$2"
HERE="$(cd "$(dirname "$0")" && pwd)"
PY=/usr/bin/python3
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
fail() { echo "FAIL: $*"; exit 1; }
field() { $PY -c "import json,sys; d=json.load(open('$1')); print(eval(sys.argv[1], {}, d))" "$2"; }

if [ "$MODE" = export ]; then
  "$NBV" workload --name bunny-3 --map m.vdb >/dev/null || fail "nbv workload"
  occupied=$("$NBV" info m.vdb | sed -n 's/^  occupied: *\([0-9]*\) .*/\1/p')
  [ "${occupied:-0}" -gt 100 ] || fail "nbv info reports ${occupied:-no} occupied voxels"

  "$NBV" export --map m.vdb --ply occ.ply >/dev/null || fail "export occupied"
  $PY "$HERE/read_ply.py" occ.ply >occ.json
  [ "$(field occ.json vertices)" = "$occupied" ] || fail "occupied export has $(field occ.json vertices) points, info says $occupied"
  [ "$(field occ.json faces)" = 0 ] || fail "points export has faces"
  [ "$(field occ.json 'list(colours)')" = "['200,40,40']" ] || fail "occupied voxels are not all class red: $(field occ.json colours)"

  "$NBV" export --map m.vdb --ply cubes.ply --cubes >/dev/null || fail "export cubes"
  $PY "$HERE/read_ply.py" cubes.ply >cubes.json
  [ "$(field cubes.json vertices)" = "$((8 * occupied))" ] || fail "cubes: $(field cubes.json vertices) vertices for $occupied voxels"
  [ "$(field cubes.json faces)" = "$((12 * occupied))" ] || fail "cubes: $(field cubes.json faces) faces for $occupied voxels"

  "$NBV" export --map m.vdb --ply marked.ply --what marked --color proximity >/dev/null || fail "export marked"
  $PY "$HERE/read_ply.py" marked.ply >marked.json
  marks=$("$NBV" info m.vdb | sed -n 's/^marked: *\([0-9]*\) .*/\1/p')
  [ "$(field marked.json vertices)" = "$marks" ] || fail "marked export has $(field marked.json vertices) points, info says $marks"
  [ "$(field marked.json 'len(colours)')" -gt 10 ] || fail "proximity colouring gives $(field marked.json 'len(colours)') colours"

  "$NBV" evaluate --map m.vdb --views dome48 --metrics pc --csv ig.csv >/dev/null || fail "evaluate"
  "$NBV" export --map m.vdb --ply frusta.ply --views dome48 --ig ig.csv --metric pc >/dev/null || fail "export frusta"
  $PY "$HERE/read_ply.py" frusta.ply >frusta.json
  [ "$(field frusta.json vertices)" = "$((occupied + 48 * 5))" ] || fail "frusta: $(field frusta.json vertices) vertices"
  [ "$(field frusta.json faces)" = "$((48 * 4))" ] || fail "frusta: $(field frusta.json faces) faces"
  # The view with the most pc is the viridis top (yellow), 5 vertices of it; the least dark blue.
  [ "$(field frusta.json "colours.get('253,231,37', 0) >= 5")" = True ] || fail "no yellow frustum for the best view"
  [ "$(field frusta.json "colours.get('68,1,84', 0) >= 5")" = True ] || fail "no dark frustum for the worst view"

  # Bad input: a named problem and no file left behind.
  if "$NBV" export --map m.vdb --ply x.ply --views dome48 --ig ig.csv --metric vg 2>err.txt; then fail "a missing column was accepted"; fi
  grep -q "ig.csv" err.txt && grep -q "'vg'" err.txt || fail "missing column: $(cat err.txt)"
  if "$NBV" export --map m.vdb --ply x.ply --views dome48 2>err.txt; then fail "--views without --ig was accepted"; fi
  grep -q -- "--ig" err.txt || fail "--views alone: $(cat err.txt)"
  [ ! -e x.ply ] || fail "a refused export left x.ply"
  echo "export: counts, colours, cubes and frusta as expected"
  exit 0
fi

[ "$MODE" = report ] || fail "mode '$MODE' is not export or report"
OUT="$3"
"$NBV" reconstruct --model bunny --iterations 3 --scene paper --json run.json --html direct.html --no-timings >/dev/null ||
  fail "reconstruct --html"
"$NBV" report run.json --html report.html >/dev/null || fail "nbv report"
cmp -s direct.html report.html || fail "reconstruct --html and nbv report of its JSON differ"
# Self-contained: no script or style fetched from anywhere.
if grep -q -E '<script[^>]* src=|<link[^>]* href=' report.html; then fail "the page loads something from outside"; fi
grep -q 'THREE' report.html || fail "three.js is not inlined"
echo '{"model": "bunny"}' >bad.json
if "$NBV" report bad.json --html bad.html 2>err.txt; then fail "a JSON without a run was accepted"; fi
grep -q "bad.json" err.txt || fail "bad JSON: $(cat err.txt)"
[ ! -e bad.html ] || fail "a refused report left bad.html"

if ! command -v chromium >/dev/null; then
  echo "SKIP: chromium is not installed (make deps installs it); the page was written and checked without a browser"
  exit 77
fi
browse() {
  timeout 120 chromium --headless=new --no-sandbox --disable-gpu --enable-unsafe-swiftshader --use-angle=swiftshader \
    --window-size=1000,800 --hide-scrollbars --virtual-time-budget=10000 --enable-logging=stderr --v=0 "$@" "file://$WORK/report.html" 2>chromium.log
}
browse --dump-dom >dom.html || { tail -20 chromium.log; fail "chromium --dump-dom"; }
status=$(grep -o '<div id="status">[^<]*</div>' dom.html || true)
case "$status" in
  *'>rendered '*) ;;
  *) fail "the page did not render: ${status:-no status element}" ;;
esac
# The page's console, as Chromium logs it (the driver's performance notes aside).
if grep 'CONSOLE' chromium.log | grep -v 'GL Driver Message' | grep -i -E 'uncaught|error'; then fail "the page logged an error"; fi
browse --screenshot="$WORK/shot.png" || { tail -20 chromium.log; fail "chromium --screenshot"; }
$PY "$HERE/screenshot_check.py" shot.png 50 || fail "the 3D view is blank"
cp shot.png "$OUT"
echo "report: rendered in Chromium ($status), screenshot at $OUT"
