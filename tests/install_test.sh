#!/usr/bin/env bash
# nbv installed as a lab installs it, then used with the clone out of reach (issue 39):
#   1. `cmake --install BUILD --prefix P` and `pip install --no-build-isolation SOURCE` into a
#      venv of Debian's Python (timed: ccache serves it the compilations of BUILD);
#   2. no path into SOURCE or BUILD is written anywhere in P or in the installed package;
#   3. in a private mount namespace with SOURCE (and BUILD) hidden under an empty tmpfs, from
#      another folder and a fresh data folder: the installed `nbv models`, `nbv models fetch`,
#      `render`, `reconstruct --json --html`, a tiny `experiment` with its plots, `report` of the
#      run moved to another folder, `report --map`, and the venv's `import nbv` with a
#      reconstruction and `python -m nbv.plots`.
# Usage: install_test.sh SOURCE BUILD. Exits 77 (skipped) where no mount namespace can be made.
set -euo pipefail
SOURCE="$(cd "$1" && pwd)"
BUILD="$(cd "$2" && pwd)"
WORK=$(mktemp -d /tmp/nbv-install-XXXXXX)
trap 'rm -rf "$WORK"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

if ! unshare -m --propagation private true 2>/dev/null; then
  echo "SKIP: no private mount namespace here (unshare -m needs root): the source tree cannot be hidden"
  exit 77
fi

cmake --install "$BUILD" --prefix "$WORK/prefix" >"$WORK/install.log" 2>&1 || { cat "$WORK/install.log"; fail "cmake --install"; }
/usr/bin/python3 -m venv --system-site-packages "$WORK/venv" || fail "python3 -m venv"
start=$(date +%s%N)
(cd "$WORK" && "$WORK/venv/bin/pip" install --no-build-isolation "$SOURCE" >"$WORK/pip.log" 2>&1) ||
  { tail -30 "$WORK/pip.log"; fail "pip install --no-build-isolation"; }
echo "pip install --no-build-isolation: $(( ($(date +%s%N) - start) / 1000000 )) ms"
site=$("$WORK/venv/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
[ -f "$site/nbv/plots.py" ] && ls "$site"/nbv/_nbv*.so >/dev/null || fail "pip installed no nbv package in $site"

for tree in "$SOURCE" "$BUILD"; do
  found=$(grep -rlaF "$tree" "$WORK/prefix" "$site/nbv" || true)
  [ -z "$found" ] || fail "the install names $tree in: $found"
done

# The rest runs with the clone hidden: an empty tmpfs over the source tree (and the build tree,
# if it lies elsewhere), in a mount namespace of its own that ends with it.
cat >"$WORK/hidden.sh" <<'EOF'
set -euo pipefail
fail() { echo "FAIL: $*"; exit 1; }
mount -t tmpfs none "$SOURCE"
case "$BUILD/" in "$SOURCE"/*) ;; *) mount -t tmpfs none "$BUILD" ;; esac
[ -z "$(ls -A "$SOURCE")" ] || fail "the source tree is still visible"
export PATH="$WORK/prefix/bin:/usr/bin:/bin" XDG_DATA_HOME="$WORK/data"
unset NBV_MODELS_DIR PYTHONPATH NBV_PYTHON
mkdir -p "$WORK/use" "$WORK/moved" "$WORK/third" && cd "$WORK/use"
[ "$(command -v nbv)" = "$WORK/prefix/bin/nbv" ] || fail "nbv on PATH is $(command -v nbv)"

nbv models >models.txt || fail "nbv models"
grep -q "^11 missing: \`nbv models fetch\` puts them in $WORK/data/nbv/models" models.txt || fail "nbv models: $(cat models.txt)"
nbv models fetch >fetch.txt 2>&1 || fail "nbv models fetch: $(cat fetch.txt)"
[ "$(ls "$WORK/data/nbv/models" | wc -l)" = 11 ] || fail "nbv models fetch wrote $(ls "$WORK/data/nbv/models")"
nbv render --model bunny --view-index 0 --out c.ply >out.txt || fail "nbv render: $(cat out.txt)"
nbv reconstruct --model bunny --iterations 3 --json run.json --html run.html --no-timings >out.txt ||
  fail "nbv reconstruct: $(cat out.txt)"
nbv experiment --models bunny --metrics pc,oa --trials 1 --iterations 2 --out exp >out.txt 2>err.txt ||
  fail "nbv experiment: $(cat err.txt)"
[ -s exp/bunny.png ] && [ -s exp/table.md ] && [ -s exp/index.html ] || fail "the experiment's files: $(ls exp)"
mv run.json "$WORK/moved/"
cd "$WORK/third"
nbv report "$WORK/moved/run.json" --html again.html >out.txt 2>&1 || fail "nbv report of a moved run: $(cat out.txt)"
cmp -s again.html "$WORK/use/run.html" || fail "the report of the moved run differs from reconstruct --html"
nbv integrate --map m.vdb --cloud "$WORK/use/c.ply" --view-index 0 >/dev/null || fail "nbv integrate"
nbv report --map m.vdb --html map.html >/dev/null || fail "nbv report --map"
"$WORK/venv/bin/python" - <<'PY' || fail "the pip-installed package"
import os
import nbv, nbv.plots
assert nbv.__file__.startswith(os.environ["VENV_SITE"]), nbv.__file__
run = nbv.reconstruct("bunny", metric="pc", iterations=2, no_timings=True)
nbv.save_run(run, "py.json")
nbv.plots.plot_runs(["py.json"], "py.png")
assert os.path.getsize("py.png") > 1000
PY
"$WORK/venv/bin/python" -m nbv.plots experiment "$WORK/use/exp/results.csv" --out-dir plots >/dev/null ||
  fail "python -m nbv.plots"
[ -s plots/bunny.png ] || fail "python -m nbv.plots wrote $(ls plots)"
echo "standalone: models fetched, rendered, reconstructed, experiment plotted, moved run and map reported, venv used"
EOF
SOURCE="$SOURCE" BUILD="$BUILD" WORK="$WORK" VENV_SITE="$site" unshare -m --propagation private bash "$WORK/hidden.sh"
