#!/usr/bin/env bash
# The nbv command as a user runs it: --help, integrate/convert/info, and every error path
# exits non-zero (< 128) with one line naming the file, leaving existing files intact.
set -u
NBV_TEST_SCRIPT="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
NBV="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
PLOTS="${2:-1}"  # 0: this nbv was built without its Python package, so experiments draw no plots
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# expect_error NAME EXPECTED_FRAGMENT -- command...
expect_error() {
  local name="$1" fragment="$2"; shift 3
  "$@" >out.txt 2>err.txt
  local rc=$?
  if [ "$rc" -eq 0 ] || [ "$rc" -ge 128 ]; then fail "$name: exit code $rc"; fi
  if [ "$(wc -l <err.txt)" -ne 1 ]; then fail "$name: expected one error line, got: $(cat err.txt)"; fi
  grep -qF -- "$fragment" err.txt || fail "$name: error does not mention '$fragment': $(cat err.txt)"
}

for sub in "" integrate convert info render viewspace evaluate decide workload reconstruct experiment export report models; do
  $NBV $sub --help >help.txt 2>&1 || fail "nbv $sub --help exits non-zero"
  grep -q "^Usage: nbv${sub:+ $sub} \[OPTIONS\]" help.txt || fail "nbv $sub --help prints no usage naming 'nbv $sub': $(head -3 help.txt)"
done

printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0.305 0.005 0.005\n0.305 0.105 0.055\n2.5 0 0\n' > scan.ply
$NBV integrate --map map.vdb --cloud scan.ply --origin 0.005 0.005 0.005 >out.txt 2>&1 || fail "integrate: $(cat out.txt)"
grep -q "3 points (2 hits, 1 beyond max range, 0 skipped)" out.txt || fail "integrate summary: $(cat out.txt)"
$NBV info map.vdb >info1.txt || fail "info"
grep -q "resolution:  0.01 m" info1.txt || fail "info resolution: $(cat info1.txt)"
$NBV integrate --map map.vdb --cloud scan.ply --origin 0.005 0.005 0.005 >/dev/null || fail "second integrate"
$NBV info map.vdb >info2.txt
grep -q "occupied:  2 " info2.txt || fail "two hits make two occupied voxels: $(cat info2.txt)"
$NBV integrate --map coarse.vdb --cloud scan.ply --origin 0 0 0 --resolution 0.05 >/dev/null || fail "integrate --resolution"
grep -q "0.05 m" <($NBV info coarse.vdb) || fail "new map takes --resolution"
# Every field of the map configuration is a flag (--p-hit for p_hit), kept by the .vdb map.
$NBV integrate --map tuned.vdb --cloud scan.ply --origin 0 0 0 --p-hit 0.8 --free-threshold 0.25 >/dev/null ||
  fail "integrate --p-hit --free-threshold"
grep -q "p_hit 0.8, .*free_threshold 0.25" <($NBV info tuned.vdb) || fail "a new map takes --p-hit: $($NBV info tuned.vdb)"
expect_error "another p_hit" "tuned.vdb: map has p_hit 0.8, --p-hit asks for 0.75" -- \
  $NBV integrate --map tuned.vdb --cloud scan.ply --origin 0 0 0 --p-hit 0.75
expect_error "a bad p_miss" "--p-miss: invalid map configuration: p_miss = 0.6 (must be in (0, 0.5))" -- \
  $NBV integrate --map new2.vdb --cloud scan.ply --origin 0 0 0 --p-miss 0.6

$NBV convert map.vdb map.ot >/dev/null || fail "convert to .ot"
$NBV convert map.ot map.bt >/dev/null || fail "convert to .bt"
$NBV convert map.bt back.vdb >/dev/null || fail "convert to .vdb"
grep -q "measured:    $(grep measured: info2.txt | awk '{print $2}') voxels" <($NBV info map.bt) || fail "convert keeps the voxel count"
command -v vdb_print >/dev/null && { vdb_print map.vdb >/dev/null 2>&1 || fail "vdb_print cannot read map.vdb"; }

# Errors: one line naming the file, and nothing damaged.
cp map.vdb keep.vdb
expect_error "missing cloud" "nothere.ply" -- $NBV integrate --map map.vdb --cloud nothere.ply --origin 0 0 0
printf 'ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n' > short.ply
expect_error "truncated cloud" "short.ply" -- $NBV integrate --map map.vdb --cloud short.ply --origin 0 0 0
printf 'ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n' > none.ply
expect_error "empty cloud" "none.ply" -- $NBV integrate --map map.vdb --cloud none.ply --origin 0 0 0
expect_error "nan origin" "origin" -- $NBV integrate --map map.vdb --cloud scan.ply --origin nan 0 0
expect_error "resolution mismatch" "map.vdb" -- $NBV integrate --map map.vdb --cloud scan.ply --origin 0 0 0 --resolution 0.02
expect_error "bad resolution" "resolution" -- $NBV integrate --map new.vdb --cloud scan.ply --origin 0 0 0 --resolution -1
expect_error "voxel cap" "above the cap of 3" -- $NBV integrate --map map.vdb --cloud scan.ply --origin 0 0.3 0 --max-voxels 3
cmp -s map.vdb keep.vdb || fail "a failed integrate changed map.vdb"
[ -e new.vdb ] && fail "a failed integrate created new.vdb"

head -c 300 map.vdb > broken.vdb; cp broken.vdb broken_keep.vdb
expect_error "truncated map" "broken.vdb" -- $NBV integrate --map broken.vdb --cloud scan.ply --origin 0 0 0
cmp -s broken.vdb broken_keep.vdb || fail "an unreadable map given to integrate was changed"
head -c 100 map.ot > broken.ot
expect_error "truncated .ot" "broken.ot" -- $NBV info broken.ot
head -c 60 /dev/urandom > garbage.bt
expect_error "garbage .bt" "garbage.bt" -- $NBV convert garbage.bt out.vdb
[ -e out.vdb ] && fail "a failed convert left out.vdb"
mkdir adir.vdb
expect_error "directory" "adir.vdb" -- $NBV info adir.vdb
expect_error "unknown extension" "map.xyz" -- $NBV convert map.vdb map.xyz
expect_error "missing map" "nomap.vdb" -- $NBV info nomap.vdb
# A fuzzer finding (tests/fuzz/findings): a corrupt buffer length inside a grid.
expect_error "corrupt blosc length" "blosc_length.vdb: truncated or corrupt" -- \
  $NBV info "$(dirname "$NBV_TEST_SCRIPT")/fuzz/findings/blosc_length.vdb"
expect_error "half floats under another type" \
  "half_float_as_double.vdb: metadata 'is_saved_as_half_float' has type 'double', expected 'bool'" -- \
  $NBV info "$(dirname "$NBV_TEST_SCRIPT")/fuzz/findings/half_float_as_double.vdb"
# A pruned OctoMap tree of 134 M free voxels (a fuzzer's file) is a map of tiles; a file whose map
# would exceed --max-map-mb (before or after the subcommand) is refused naming the cap.
$NBV info "$(dirname "$NBV_TEST_SCRIPT")/fuzz/findings/expands_to_many_voxels.bt" >info.txt 2>err.txt &&
  grep -q "^measured:    134639936 voxels" info.txt || fail "a pruned .bt: $(cat info.txt err.txt)"
expect_error "a map above --max-map-mb" "more than the cap of 1.0 MB" -- \
  $NBV info "$(dirname "$NBV_TEST_SCRIPT")/bad_inputs/map/huge_volume.ot" --max-map-mb 1
expect_error "--max-map-mb before the subcommand" "more than the cap of 1.0 MB" -- \
  $NBV --max-map-mb 1 info "$(dirname "$NBV_TEST_SCRIPT")/bad_inputs/map/huge_volume.ot"

# Sensor: views and rendering (needs the standard models: `make test` runs `nbv models fetch` first).
$NBV viewspace --kind dome48 --out views.txt >/dev/null || fail "viewspace"
[ "$(head -1 views.txt)" = "48" ] || fail "viewspace file does not start with 48"
grep -q -- "-0 " views.txt && fail "viewspace file has negative zeros"
$NBV render --model bunny --view-index 0 --out b0.ply --depth-png b0.png >out.txt 2>&1 || fail "render: $(cat out.txt)"
[ "$(head -c 8 b0.png | od -An -tx1 | tr -d ' \n')" = "89504e470d0a1a0a" ] || fail "depth image is not a PNG"
$NBV integrate --map bunny.vdb --cloud b0.ply --origin 0.6 0 0.15 >/dev/null || fail "integrate a rendered view"
$NBV render --model bunny --view-index 3 --viewspace views.txt --out b3.ply >/dev/null || fail "render from a view file"
expect_error "view index" "view-index 48" -- $NBV render --model bunny --view-index 48 --out x.ply
expect_error "missing model" "nomodel.off" -- $NBV render --model nomodel.off --view-index 0 --out x.ply
printf 'OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n' > badindex.off
expect_error "bad mesh" "badindex.off" -- $NBV render --model badindex.off --view-index 0 --out x.ply
printf '2\n0 0 0 0 0 0 1\n' > short_views.txt
expect_error "bad view file" "short_views.txt" -- $NBV render --model bunny --view-index 0 --viewspace short_views.txt --out x.ply
[ -e x.ply ] && fail "a failed render left x.ply"
# The depth picture's orientation: rows go along the optical frame's +y, columns along +x (TUM,
# OpenCV). An upright camera (optical y = world down, x = world +y) above a tall box with a small
# cube at world +y: everything below the middle row, the cube right of the middle column.
printf 'OFF\n16 24 0\n' > towers.off
for box in "-0.05 0.05 -0.05 0.05 0 0.5" "-0.025 0.025 0.2 0.25 0.4 0.45"; do
  set -- $box
  for z in $5 $6; do for y in $3 $4; do for x in $1 $2; do echo "$x $y $z"; done; done; done >> towers.off
done
for o in 0 8; do
  printf '3 %d %d %d\n' $((o)) $((o+2)) $((o+3)) $((o)) $((o+3)) $((o+1)) $((o+4)) $((o+5)) $((o+7)) $((o+4)) $((o+7)) $((o+6)) \
    $((o)) $((o+1)) $((o+5)) $((o)) $((o+5)) $((o+4)) $((o+2)) $((o+6)) $((o+7)) $((o+2)) $((o+7)) $((o+3)) \
    $((o)) $((o+4)) $((o+6)) $((o)) $((o+6)) $((o+2)) $((o+1)) $((o+3)) $((o+7)) $((o+1)) $((o+7)) $((o+5))
done >> towers.off
printf '1\n0.6 0 0.6 -0.5 -0.5 0.5 0.5\n' > upright.txt   # z = -x (towards the towers), y = -z, x = +y
$NBV render --model towers.off --viewspace upright.txt --view-index 0 --out t.ply --depth-png t.png --depth-png16 t16.png \
  >out.txt 2>&1 || fail "render the towers: $(cat out.txt)"
for png in t.png t16.png; do
  /usr/bin/python3 -c "
import sys, numpy as np, matplotlib.image as image
depth = image.imread('$png')
rows, cols = np.nonzero(depth)
assert depth.shape == (480, 752), depth.shape
assert len(rows) > 1000 and rows.min() > 240, ('something above the middle row', rows.min())
right = cols[cols > 376]
assert 100 < len(right) < 0.2 * len(cols), ('the small cube is not right of the middle', len(right), len(cols))
" 2>err.txt || fail "$png is not in the optical frame's orientation: $(tail -1 err.txt)"
done

# Information gain: the bunny map above, scored by the fast and the reference evaluator.
$NBV evaluate --map bunny.vdb --views views.txt --metrics oa,pc,vg --csv ig.csv >out.txt 2>&1 || fail "evaluate: $(cat out.txt)"
[ "$(head -1 ig.csv)" = "view,oa,pc,vg" ] || fail "evaluate header: $(head -1 ig.csv)"
[ "$(wc -l <ig.csv)" -eq 49 ] || fail "evaluate writes one row per view"
# "-" is standard output: the file alone there, the report on standard error; nothing on a
# failure, and no temporary file left (they go to TMPDIR).
mkdir -p tmp_stdout
export TMPDIR="$PWD/tmp_stdout"
$NBV evaluate --map bunny.vdb --views views.txt --metrics oa,pc,vg --csv - >stdout.csv 2>err.txt || fail "evaluate --csv -: $(cat err.txt)"
cmp -s ig.csv stdout.csv || fail "evaluate --csv - differs from --csv ig.csv"
grep -q "wrote -" err.txt || fail "evaluate --csv -: no report on standard error: $(cat err.txt)"
$NBV viewspace --kind dome48 --out - 2>/dev/null | cmp -s views.txt - || fail "viewspace --out - differs from views.txt"
expect_error "missing map to stdout" "nothere.vdb" -- $NBV evaluate --map nothere.vdb --csv -
[ -s out.txt ] && fail "a failed evaluate --csv - wrote to standard output: $(head -c 200 out.txt)"
expect_error "two outputs to stdout" "at most one output may go to standard output" -- $NBV reconstruct --model bunny --json - --html -
expect_error "a map to stdout" "no extension to tell the map format by" -- $NBV convert bunny.vdb -
[ -z "$(ls -A tmp_stdout)" ] || fail "temporary files of standard output were left: $(ls tmp_stdout)"
unset TMPDIR
$NBV evaluate --map bunny.vdb --metrics oa,pc,vg --reference --csv ref.csv >/dev/null || fail "evaluate --reference"
awk -F, 'NR == FNR { a[FNR] = $0; next } FNR > 1 { split(a[FNR], f, ","); for (i = 2; i <= NF; ++i) {
  d = f[i] - $i; if (d < 0) d = -d; m = $i < 0 ? -$i : $i; if (d > 1e-6 * (m + 1e-12)) bad = 1 } }
  END { exit bad }' ig.csv ref.csv || fail "fast and reference evaluations differ"
$NBV evaluate --map bunny.vdb --threads 1 --metrics oa,pc,vg --csv ig1.csv >/dev/null && cmp -s ig.csv ig1.csv ||
  fail "1 and 2 threads give different tables"
# Every instruction set gives the same table; one this CPU or build lacks is refused by name.
for isa in scalar avx2 avx512; do
  if $NBV evaluate --map bunny.vdb --metrics oa,pc,vg --isa $isa --csv isa.csv >out.txt 2>err.txt; then
    cmp -s ig.csv isa.csv || fail "evaluate --isa $isa differs from the default instruction set"
  else
    grep -qF -- "--isa $isa: not available" err.txt || fail "evaluate --isa $isa: $(cat err.txt)"
  fi
done
$NBV evaluate --map map.ot --metrics all --rays 40 --csv ot.csv >/dev/null || fail "evaluate an .ot map"
[ "$(head -1 ot.csv)" = "view,$($NBV evaluate --help | tr -s " \n" " " | sed -n "s/.*a comma-separated list of: \([a-z, ]*\).*/\1/p" | sed "s/, /,/g; s/ *$//")" ] || fail "all metrics: $(head -1 ot.csv)"
cp ig.csv ig_keep.csv
expect_error "unknown metric" "bogus" -- $NBV evaluate --map bunny.vdb --metrics oa,bogus --csv ig.csv
expect_error "bad ray set" "sparse" -- $NBV evaluate --map bunny.vdb --rays sparse --csv ig.csv
expect_error "stride 0" "0" -- $NBV evaluate --map bunny.vdb --rays 0 --csv ig.csv
expect_error "evaluate missing map" "nomap.vdb" -- $NBV evaluate --map nomap.vdb --csv ig.csv
expect_error "snapshot cap" "more than the limit" -- $NBV evaluate --map bunny.vdb --max-snapshot-mb 0 --csv ig.csv
expect_error "evaluate bad views" "short_views.txt" -- $NBV evaluate --map bunny.vdb --views short_views.txt --csv ig.csv
cmp -s ig.csv ig_keep.csv || fail "a failed evaluate changed ig.csv"

# Reconstruction: a short run, its JSON, and the same output for the same seed.
$NBV reconstruct --model bunny --metric pc --iterations 3 --seed 4 --threads 1 --json run.json >run.txt 2>&1 ||
  fail "reconstruct: $(cat run.txt)"
[ "$(grep -c '^ *[0-9]' run.txt)" -eq 3 ] || fail "reconstruct prints one line per iteration: $(cat run.txt)"
for key in model metric seed iterations view coverage entropy_bits seconds_ig auc_coverage auc_entropy; do
  grep -q "\"$key\"" run.json || fail "run.json has no $key"
done
# Determinism: same inputs and seed, byte-identical JSON and CSV at 1 and 2 threads.
for t in 1 2; do
  $NBV reconstruct --model bunny --metric rse --iterations 3 --seed 4 --threads $t --no-timings --json det$t.json >/dev/null 2>&1 ||
    fail "reconstruct --no-timings"
  $NBV experiment --models bunny --metrics oa,random --trials 2 --iterations 2 --threads $t --no-timings --out det$t >/dev/null 2>&1 ||
    fail "experiment --no-timings"
done
cmp -s det1.json det2.json || fail "reconstruct: same seed, different JSON at 1 and 2 threads"
cmp -s det1/results.csv det2/results.csv || fail "experiment: same seeds, different results.csv at 1 and 2 threads"
grep -qE '^\| bunny \| oa \| 2 \| .* \| - \|$' det1/table.md || fail "table.md: times shown though --no-timings dropped them"
$NBV evaluate --map bunny.vdb --metrics all --threads 2 --csv det2.csv >/dev/null && cmp -s det2.csv <($NBV evaluate \
  --map bunny.vdb --metrics all --threads 1 --csv det1.csv >/dev/null && cat det1.csv) || fail "evaluate: 1 and 2 threads differ"
cp run.json run_keep.json
expect_error "reconstruct unknown metric" "bogus" -- $NBV reconstruct --model bunny --metric bogus --json run.json
expect_error "reconstruct bad weight" "x*pc" -- $NBV reconstruct --model bunny --metric 'x*pc' --json run.json
expect_error "reconstruct gamma" "gamma" -- $NBV reconstruct --model bunny --gamma 2 --json run.json
expect_error "reconstruct missing model" "nomodel.off" -- $NBV reconstruct --model nomodel.off --json run.json
echo 0 > no_views.txt
expect_error "reconstruct empty viewspace" "no_views.txt: the viewspace holds no view" -- \
  $NBV reconstruct --model bunny --viewspace no_views.txt --json run.json
expect_error "evaluate empty viewspace" "no_views.txt" -- $NBV evaluate --map bunny.vdb --views no_views.txt --csv ig.csv
expect_error "reconstruct 0 iterations" "not in range 1" -- $NBV reconstruct --model bunny --iterations 0 --json run.json
expect_error "reconstruct nan gamma" "--gamma: nan" -- $NBV reconstruct --model bunny --gamma nan --json run.json
cmp -s run.json run_keep.json || fail "a failed reconstruct changed run.json"
# The oracle plans by the ground truth: a planner of reconstruct, not an IG metric of evaluate.
$NBV reconstruct --model bunny --metric oracle --iterations 3 --json oracle.json >/dev/null 2>err.txt ||
  fail "reconstruct --metric oracle: $(cat err.txt)"
grep -q '"metric": "oracle"' oracle.json && grep -q '"rays": 0' oracle.json || fail "the oracle's run: $(head -3 oracle.json)"
expect_error "decide --metric oracle" "oracle" -- $NBV decide --map bunny.vdb --metric oracle
# Each reconstruction option is a flag and a field of the run's JSON; --max-seconds stops a run
# after the scan that ends past it (here the first).
$NBV reconstruct --model bunny --iterations 5 --max-seconds 1e-9 --g-thresh none --max-ray-depth 1.2 --json timed.json \
  >/dev/null 2>err.txt || fail "reconstruct --max-seconds: $(cat err.txt)"
grep -q '"stop": "max_seconds"' timed.json || fail "--max-seconds did not stop the run: $(grep stop timed.json)"
grep -q '"max_ray_depth": 1.2' timed.json && grep -q '"g_thresh": null' timed.json && grep -q '"max_seconds": 1e-09' timed.json ||
  fail "the run's JSON lacks its options: $(head -12 timed.json)"
expect_error "reconstruct --max-seconds 0" "--max-seconds: 0 must be finite and > 0" -- \
  $NBV reconstruct --model bunny --max-seconds 0 --json run.json
expect_error "reconstruct --gamma none" "--gamma: 'none' is not a number" -- $NBV reconstruct --model bunny --gamma none --json run.json

# Experiment: two shards merged give the rows one run gives (times aside), and a table.
exp() { $NBV experiment --models bunny --metrics pc,random --trials 2 --iterations 2 --threads 1 "$@"; }
exp --out whole >/dev/null 2>&1 || fail "experiment"
exp --shard 1/2 --out part1 >/dev/null 2>&1 && exp --shard 2/2 --out part2 >/dev/null 2>&1 || fail "experiment shards"
$NBV experiment --merge part1 part2 --out merged >/dev/null 2>&1 || fail "experiment --merge"
cmp -s <(cut -d, -f1-8 whole/results.csv) <(cut -d, -f1-8 merged/results.csv) || fail "merged shards differ from one run"
[ "$(wc -l <whole/results.csv)" -eq 9 ] || fail "results.csv: 2 metrics x 2 trials x 2 iterations + header"
grep -q '^| bunny | pc | 2 |' whole/table.md || fail "table.md: $(cat whole/table.md)"
grep -qE '^\| bunny \| pc \| 2 \| .* \| [0-9]+\.[0-9]{3} \|$' whole/table.md || fail "table.md: pc's decisions untimed"
expect_error "compare_conditions on short runs" "need at least 10 (coverage @10)" -- \
  /usr/bin/python3 "$(dirname "$NBV_TEST_SCRIPT")/../scripts/compare_conditions.py" short=whole
# The report page of the model and the index that links it and shows the plot and the table.
[ -f whole/bunny.html ] || fail "experiment: no bunny.html report"
grep -q 'href="bunny.html"' whole/index.html || fail "index.html: $(cat whole/index.html)"
[ "$PLOTS" = 0 ] || grep -q 'src="bunny.png"' whole/index.html || fail "index.html shows no plot: $(cat whole/index.html)"
grep -q '<td> bunny </td><td> pc </td>' whole/index.html || fail "index.html has no Table 1 row for bunny, pc"
cmp -s det1/bunny.html det2/bunny.html || fail "experiment: the report page differs at 1 and 2 threads"
expect_error "merge twice" "part1: is shard 1/2 again (part1 is that shard too)" -- $NBV experiment --merge part1 part1 --out twice
expect_error "bad shard" "3/2" -- $NBV experiment --models bunny --shard 3/2 --out x
expect_error "merge missing" "nothere" -- $NBV experiment --merge nothere --out x

# What a new user trips on (issue 18): each defect of a fresh clone, as the user met it.
expect_error "unknown subcommand" "unknown subcommand 'frobnicate' (known: integrate," -- $NBV frobnicate
$NBV --version >out.txt 2>&1 || fail "--version exits non-zero"
grep -q "^nbv [0-9]*\.[0-9]*\.[0-9]*$" out.txt && grep -qE "ray walks: (avx512|avx2|scalar)" out.txt ||
  fail "--version: $(cat out.txt)"
expect_error "unknown flag" "unknown option '--mpa' for 'nbv evaluate' (did you mean --map?)" -- \
  $NBV evaluate --mpa bunny.vdb --csv x.csv
expect_error "generic output" "unknown option '--out' for 'nbv export' (its outputs: --ply)" -- \
  $NBV export --map bunny.vdb --out x.ply
expect_error "generic output, two" "unknown option '--out' for 'nbv reconstruct' (its outputs: --json, --html)" -- \
  $NBV reconstruct --model bunny --out run.json
expect_error "flag named as typed" "--max-ray-depth: -1 is not" -- $NBV evaluate --map bunny.vdb --max-ray-depth -1 --csv x.csv
expect_error "unwritable output" "nodir/ig.csv: cannot write: the folder nodir does not exist" -- \
  $NBV evaluate --map bunny.vdb --csv nodir/ig.csv
expect_error "unwritable map" "nodir/m.bt" -- $NBV convert bunny.vdb nodir/m.bt
expect_error "not a model" "neither.off: no such file, and not a standard model name (bunny, armadillo" -- \
  $NBV render --model neither.off --view-index 0 --out x.ply
NBV_MODELS_DIR=$WORK/none expect_error "model not fetched" "is not in $WORK/none: run \`nbv models fetch\`" -- \
  $NBV render --model bunny --view-index 0 --out x.ply
for cmd in "reconstruct --model bunny --iterations 1" "evaluate --map bunny.vdb --csv m.csv"; do
  for flag in --metric --metrics; do
    $NBV $cmd $flag pc >/dev/null 2>err.txt || fail "$cmd $flag: $(cat err.txt)"
  done
done
# Views: a Fibonacci sphere with nothing below the base; render names the origin that integrate takes.
$NBV viewspace --kind fibonacci --count 100 --radius 0.6 --target 0 0 0.2 --min-z 0 --out fib.txt >/dev/null ||
  fail "viewspace fibonacci"
awk 'NR == 1 { n = $1; next } $3 < 0 { bad = 1 } END { exit !(n > 50 && n < 100 && NR == n + 1 && !bad) }' fib.txt ||
  fail "fibonacci --min-z 0: $(head -2 fib.txt)"
$NBV render --model bunny --view-index 5 --out v5.ply >out.txt || fail "render view 5"
origin=$(sed -n 's/^origin: //p' out.txt)
[ -n "$origin" ] || fail "render prints no origin: $(cat out.txt)"
$NBV integrate --map o1.vdb --cloud v5.ply --origin $origin >/dev/null || fail "integrate --origin"
$NBV integrate --map o2.vdb --cloud v5.ply --view-index 5 >/dev/null || fail "integrate --view-index"
cmp -s <($NBV info o1.vdb | tail -n +2) <($NBV info o2.vdb | tail -n +2) || fail "--view-index and --origin differ"
expect_error "origin twice" "either as --origin" -- $NBV integrate --map o3.vdb --cloud v5.ply --origin 0 0 0 --view-index 5
# info: both rules of "occupied" on a one-scan map.
$NBV info o1.vdb >info.txt
grep -q "^  occupied:  0 (class occupied of the metrics: P > 0.8)" info.txt &&
  grep -qE "^  occupied for OctoMap: [1-9][0-9]* \(isNodeOccupied: L >= 0" info.txt || fail "info: $(cat info.txt)"
# OctoMap files: no stray output (liboctomap's progress) beside the note on what the copy leaves
# out, and a warning when pc or vg cannot see marks.
$NBV convert bunny.vdb quiet.bt >/dev/null 2>err.txt || fail "convert to .bt"
[ "$(grep -vc '^nbv: note: quiet.bt leaves out ' err.txt)" = 0 ] || fail "convert to .bt printed on stderr: $(cat err.txt)"
$NBV evaluate --map quiet.bt --metrics pc,vg,oa --rays 40 --csv bt.csv >/dev/null 2>err.txt || fail "evaluate .bt"
[ "$(grep -c "warning: quiet.bt has no proximity marks" err.txt)" -eq 1 ] || fail "no-marks warning: $(cat err.txt)"
$NBV evaluate --map bunny.vdb --metrics pc,vg --rays 40 --csv vdb.csv >/dev/null 2>err.txt
[ -s err.txt ] && fail "a .vdb map with marks warned: $(cat err.txt)"
# Weighted sums: normalised by default, so the weights compare metrics of different scales.
views_of() { $NBV reconstruct --model bunny --iterations 6 --seed 1 --threads 1 "$@" | awk '$1 ~ /^[0-9]+$/ && NF > 2 { printf "%s ", $2 }'; }
pc_views=$(views_of --metric pc)
mixed_views=$(views_of --metric '0.5*pc+0.5*vg')
[ "$mixed_views" != "$pc_views" ] || fail "0.5*pc+0.5*vg picks pc's views"
[ "$(views_of --metric '0.5*pc+0.5*vg' --weighting raw)" = "$pc_views" ] || fail "--weighting raw: pc drowns vg"
[ "$(views_of --metric 'pc*0.5 + vg * 0.5')" = "$mixed_views" ] || fail "pc*0.5 and spaces"
expect_error "trailing +" "--metric: utility 'pc+' has an empty term" -- $NBV reconstruct --model bunny --metric 'pc+'
expect_error "repeated metric" "names 'pc' twice" -- $NBV reconstruct --model bunny --metric 'pc+0.5*pc'
expect_error "zero weight" "the weight must be finite and positive" -- $NBV reconstruct --model bunny --metric '0*pc'
expect_error "negative weight" "the weight must be finite and positive" -- $NBV reconstruct --model bunny --metric '-1*pc'
expect_error "nan weight" "the weight must be finite and positive" -- $NBV reconstruct --model bunny --metric 'nan*pc'
# Experiments on mesh files: every file under --out, named by the mesh's stem, unique.
mkdir -p a b
cp "$($NBV models | sed -n 's/^dino  *//p')" a/elephant.off || fail "no dino.off: $($NBV models)"
cp a/elephant.off b/elephant.off
$NBV experiment --models a/elephant.off,"$WORK/b/elephant.off" --metrics pc --trials 1 --iterations 2 --out expm \
  >out.txt 2>&1 || fail "experiment on mesh files: $(cat out.txt)"
if [ "$PLOTS" = 0 ]; then
  grep -q "no plots: this nbv was built without its Python package" out.txt || fail "no note on the missing plots: $(cat out.txt)"
else
  [ -f expm/elephant.png ] && [ -f expm/elephant-2.png ] || fail "plots of mesh files: $(ls expm)"
fi
[ "$(ls a b)" = "$(printf 'a:\nelephant.off\n\nb:\nelephant.off')" ] || fail "files left beside the meshes: $(ls a b)"
grep -q '^| elephant-2 | pc | 1 | [0-9.]* |' expm/table.md || fail "one trial has no spread: $(cat expm/table.md)"
grep -q '| final coverage |' expm/table.md || fail "table.md has no final coverage"
grep -qE '(0000000000[1-9]|9999999999[0-9])(,|$)' expm/results.csv && fail "results.csv: not shortest floats"
expect_error "non-empty --out" "expm: the --out folder is not empty: it holds another sweep (models ([\"bunny\"] against" -- \
  $NBV experiment --models bunny --metrics pc --trials 1 --iterations 1 --out expm
$NBV experiment --models bunny --metrics pc --trials 2 --iterations 2 --out expm --force >/dev/null 2>&1 ||
  fail "experiment --force"
grep -q '| pc | 2 | .* ± .* (se ' expm/table.md || fail "table.md: no standard error"
# Scene conditions (issue 20): presets and flags on render, reconstruct and experiment.
$NBV render --model bunny --view-index 0 --out bare.ply >bare.txt || fail "render bare"
$NBV render --model bunny --view-index 0 --ground-plane --out ground.ply >ground.txt || fail "render --ground-plane"
n_bare=$(sed -n 's/.*: \([0-9]*\) points (\([0-9]*\) on the object).*/\1 \2/p' bare.txt)
n_ground=$(sed -n 's/.*: \([0-9]*\) points (\([0-9]*\) on the object).*/\1 \2/p' ground.txt)
read -r all_bare obj_bare <<<"$n_bare"; read -r all_ground obj_ground <<<"$n_ground"
{ [ "$all_bare" = "$obj_bare" ] && [ "$all_ground" -gt "$all_bare" ] && [ "$obj_ground" -le "$obj_bare" ]; } ||
  fail "ground plane: bare $n_bare, with plane $n_ground"
$NBV render --model bunny --view-index 0 --scene released --out released.ply >/dev/null || fail "render --scene released"
$NBV render --model bunny --view-index 0 --no-return clear --out clear.ply >clear.txt || fail "render --no-return clear"
grep -q "360960 points" clear.txt || fail "no-return clear gives a point per pixel: $(cat clear.txt)"
expect_error "bad crop" "--crop: each minimum" -- $NBV render --model bunny --view-index 0 --crop 1 0 0 1 0 1 --out x.ply
expect_error "bad scene" "--scene" -- $NBV reconstruct --model bunny --scene gazebo
$NBV reconstruct --model bunny --iterations 3 --seed 2 --scene paper --up y --visibility released --json scene.json \
  >/dev/null || fail "reconstruct --scene paper"
grep -q '"scene": {"name": "paper+up=y", "ground_plane": true, "no_return": "drop", "crop": null, "up": "y", "visibility": "released"}' \
  scene.json || fail "scene in the JSON: $(grep scene scene.json)"
grep -q '"ties": 1, "gap": [0-9]' scene.json || fail "ties and gap in the JSON"
head -1 whole/results.csv | grep -q ',ties,gap,rays,ray_share$' || fail "results.csv has no ties, gap, rays and ray_share"
# An experiment's runs, side by side on a shared object, are the runs of nbv reconstruct.
$NBV experiment --models bunny --metrics rse --trials 2 --iterations 3 --scene released --no-timings --out expr >/dev/null 2>&1 ||
  fail "experiment --scene released"
$NBV reconstruct --model bunny --metric rse --iterations 3 --seed 1 --scene released --no-timings --json r1.json >/dev/null
[ "$(awk -F, '$3 == 1 { printf "%s %s ", $5, $6 }' expr/results.csv)" = \
  "$(grep -o '"view": [0-9]*, "coverage": [0-9.e-]*' r1.json | awk '{ printf "%s %s ", $2, $4 }' | tr -d ',')" ] ||
  fail "experiment trial 1 differs from nbv reconstruct --seed 1"
# Depth images and TUM folders (issue 22): a rendered sequence, integrated frame by frame either way.
$NBV viewspace --kind fibonacci --count 3 --radius 0.6 --target 0 0 0.15 --out three.txt >/dev/null
$NBV render --model bunny --views three.txt --tum-out tum >out.txt || fail "render --tum-out: $(cat out.txt)"
[ "$(grep -vc '^#' tum/depth.txt)" -eq 3 ] && [ "$(grep -vc '^#' tum/groundtruth.txt)" -eq 3 ] || fail "tum folder lists"
[ "$(od -An -tu1 -j24 -N2 tum/depth/000000.png | tr -s ' ')" = " 16 0" ] || fail "tum depth images are not 16-bit greyscale"
$NBV integrate --map tum.vdb --tum tum >out.txt 2>err.txt || fail "integrate --tum: $(cat err.txt)"
grep -q "integrated 3 scans" out.txt || fail "integrate --tum: $(cat out.txt)"
grep -q "3/3 frames" err.txt || fail "integrate --tum shows no progress"
for i in 0 1 2; do
  $NBV integrate --map frames.vdb --depth tum/depth/00000$i.png --pose $(grep -v '^#' tum/groundtruth.txt | sed -n "$((i + 1))p" | cut -d' ' -f2-) \
    >/dev/null || fail "integrate --depth frame $i"
done
cmp -s <($NBV info tum.vdb | tail -n +2) <($NBV info frames.vdb | tail -n +2) || fail "--tum and --depth --pose differ"
# A numbered folder and a pose file without timestamps (issue 43): the same map as --tum.
mkdir numbered && cp tum/depth/*.png numbered/ && grep -v '^#' tum/groundtruth.txt | cut -d' ' -f2- >poses.txt
$NBV integrate --map numbered.vdb --frames numbered --poses poses.txt >out.txt 2>err.txt || fail "integrate --frames: $(cat err.txt)"
cmp -s <($NBV info tum.vdb | tail -n +2) <($NBV info numbered.vdb | tail -n +2) || fail "--frames --poses and --tum differ"
# A dataset's camera with a negative focal length and a room-scale range, stored in the map.
$NBV integrate --map room.vdb --frames numbered --poses poses.txt --camera 752 480 448.1 -448.1 376.5 239.5 \
  --max-range 3 --min-range 0.1 >out.txt 2>err.txt || fail "integrate with fy < 0: $(cat err.txt)"
$NBV info room.vdb | grep -q "max_range 3 m, .*min_range 0.1 m" || fail "nbv info does not show the map's ranges: $($NBV info room.vdb)"
expect_error "another range" "room.vdb: map has max_range 3 m, --max-range asks for 2" -- \
  $NBV integrate --map room.vdb --frames numbered --poses poses.txt --max-range 2
$NBV render --model bunny --view-index 2 --depth-png16 d16.png --out d16.ply >/dev/null || fail "render --depth-png16"
[ "$(od -An -tu1 -j24 -N2 d16.png | tr -s ' ')" = " 16 0" ] || fail "--depth-png16 is not 16-bit greyscale"
$NBV integrate --map d16.vdb --depth d16.png --view-index 2 --no-return clear >/dev/null || fail "integrate --depth --view-index"
expect_error "depth without pose" "either as --pose" -- $NBV integrate --map x.vdb --depth d16.png
expect_error "two inputs" "give one input" -- $NBV integrate --map x.vdb --depth d16.png --cloud d16.ply --pose 0 0 0 0 0 0 1
expect_error "bad camera" "--camera: invalid camera: fx = 0" -- $NBV integrate --map x.vdb --depth d16.png --view-index 2 \
  --camera 752 480 0 448 376.5 240.5

# Anytime decisions (issue 21): the exhaustive argmax at a fraction of the rays.
$NBV decide --map bunny.vdb --metric pc --rays 4 --check --json decision.json >out.txt 2>&1 || fail "decide: $(cat out.txt)"
grep -q "^chosen view [0-9]*: .* in \[.*\]" out.txt && grep -q "% of the exhaustive count)" out.txt ||
  fail "decide prints: $(cat out.txt)"
grep -q "within epsilon: yes" out.txt || fail "decide is not within epsilon: $(cat out.txt)"
$NBV decide --map bunny.vdb --metric kr --rays 4 --epsilon 0 --check >out.txt 2>&1 && grep -q "same view: yes" out.txt ||
  fail "decide --epsilon 0 is not the exhaustive argmax: $(cat out.txt)"
expect_error "decide epsilon" "--epsilon: 2 must be in [0, 1)" -- $NBV decide --map bunny.vdb --epsilon 2
expect_error "budget without anytime" "--budget-ms needs --anytime" -- $NBV reconstruct --model bunny --budget-ms 5
expect_error "epsilon without anytime" "--epsilon needs --anytime" -- $NBV reconstruct --model bunny --epsilon 0.1
# The anytime options are a table: the run's JSON holds each, as `nbv decide --json` does.
$NBV reconstruct --model bunny --iterations 2 --anytime --delta 0.05 --budget-ms 500 --json anytime.json >/dev/null ||
  fail "reconstruct --anytime --delta --budget-ms"
grep -q '"anytime": {"epsilon": 0.01, "delta": 0.05, "budget_ms": 500}' anytime.json ||
  fail "the run's anytime object: $(grep anytime anytime.json)"
$NBV reconstruct --model bunny --metric 0.5*pc+0.5*vg --rays 8 --iterations 3 --anytime --threads 1 --no-timings \
  --json any1.json >/dev/null && $NBV reconstruct --model bunny --metric 0.5*pc+0.5*vg --rays 8 --iterations 3 --anytime \
  --threads 2 --no-timings --json any2.json >/dev/null && cmp -s any1.json any2.json ||
  fail "reconstruct --anytime: 1 and 2 threads differ"
grep -q '"anytime": {"epsilon": 0.01, "delta": 0.01, "budget_ms": null}' any1.json || fail "anytime in the JSON"
printf '#!/bin/sh\necho "plot: matplotlib exploded" >&2\nexit 3\n' > fakepython; chmod +x fakepython
NBV_PYTHON=$WORK/fakepython $NBV experiment --models bunny --metrics pc --trials 1 --iterations 1 --out expf >out.txt 2>err.txt
rc=$?
{ [ $rc -ne 0 ] && [ $rc -lt 128 ]; } || fail "a failed plot exits $rc"
grep -q "plot: matplotlib exploded" err.txt || fail "a failed plot hides the script's message: $(cat err.txt)"
ls -a | grep -q '\.tmp-' && fail "temporary files left behind: $(ls -a)"

# What a new user tripped on (issue 39). Progress into a log file: lines, no carriage returns.
$NBV experiment --models bunny --metrics pc --trials 2 --iterations 1 --out explog >out.txt 2>log.txt ||
  fail "experiment into a log: $(cat log.txt)"
grep -q $'\r' log.txt && fail "the progress wrote carriage returns into a log file"
grep -q '^2/2 runs, .* elapsed, ETA ' log.txt || fail "the progress wrote no last line into the log: $(cat log.txt)"
expect_error "an --out that cannot be made" "/proc/nbv-x: cannot make the folder: " -- \
  $NBV experiment --models bunny --metrics pc --trials 1 --iterations 1 --out /proc/nbv-x
# A copy into OctoMap's formats says what it leaves out, once; a .vdb copy says nothing.
$NBV convert bunny.vdb copy.ot >out.txt 2>err.txt || fail "convert to .ot: $(cat err.txt)"
[ "$(grep -c 'proximity marks' err.txt)" = 1 ] && grep -q 'a .vdb keeps everything' err.txt ||
  fail "convert to .ot drops the marks without a word: $(cat err.txt)"
$NBV convert bunny.vdb copy.bt >out.txt 2>err.txt && grep -q "the probabilities (.bt keeps only occupied or free)" err.txt ||
  fail "convert to .bt: $(cat err.txt)"
$NBV convert bunny.vdb copy.vdb >out.txt 2>err.txt && [ ! -s err.txt ] || fail "convert to .vdb: $(cat err.txt)"
# One scan leaves no voxel occupied (P = 0.7 < 0.8): the export says why and what shows them.
$NBV integrate --map one.vdb --cloud b0.ply --origin 0.6 0 0.15 >/dev/null || fail "integrate one scan"
$NBV export --map one.vdb --ply none.ply >out.txt 2>err.txt || fail "export of one scan: $(cat err.txt)"
grep -q "none of the map's [0-9]* measured voxels is occupied (P > 0.8): one hit leaves P = 0.7" err.txt &&
  grep -q -- "--what all --color probability" err.txt || fail "export of one scan says nothing: $(cat err.txt)"
# `nbv models` lists each standard model where it is found, and where it looks.
$NBV models >out.txt 2>&1 || fail "nbv models: $(cat out.txt)"
[ "$(grep -c '\.off$' out.txt)" = 11 ] && grep -q '^looked for in: ' out.txt || fail "nbv models: $(cat out.txt)"
NBV_MODELS_DIR=$WORK/none $NBV models >out.txt 2>&1 && grep -q "^11 missing: \`nbv models fetch\` puts them in $WORK/none" out.txt ||
  fail "nbv models with none: $(cat out.txt)"

if [ "$failures" -eq 0 ]; then echo "cli: all checks passed"; else echo "cli: $failures failed"; exit 1; fi
