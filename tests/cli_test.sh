#!/usr/bin/env bash
# The nbv command as a user runs it: --help, integrate/convert/info, and every error path
# exits non-zero (< 128) with one line naming the file, leaving existing files intact.
set -u
NBV_TEST_SCRIPT="$(cd "$(dirname "$0")" && pwd)/$(basename "$0")"
NBV="$(cd "$(dirname "$1")" && pwd)/$(basename "$1")"
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

for sub in "" integrate convert info render viewspace evaluate workload reconstruct experiment; do
  $NBV $sub --help >help.txt 2>&1 || fail "nbv $sub --help exits non-zero"
  grep -q "Usage" help.txt || fail "nbv $sub --help prints no usage"
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

# Sensor: views and rendering (needs `make models`, which `make test` runs first).
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

# Information gain: the bunny map above, scored by the fast and the reference evaluator.
$NBV evaluate --map bunny.vdb --views views.txt --metrics oa,pc,vg --csv ig.csv >out.txt 2>&1 || fail "evaluate: $(cat out.txt)"
[ "$(head -1 ig.csv)" = "view,oa,pc,vg" ] || fail "evaluate header: $(head -1 ig.csv)"
[ "$(wc -l <ig.csv)" -eq 49 ] || fail "evaluate writes one row per view"
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
[ "$(head -1 ot.csv)" = "view,entropy,oa,uv,rsv,rse,pc,vg,kr,random" ] || fail "all metrics: $(head -1 ot.csv)"
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
expect_error "reconstruct nan gamma" "gamma nan" -- $NBV reconstruct --model bunny --gamma nan --json run.json
cmp -s run.json run_keep.json || fail "a failed reconstruct changed run.json"

# Experiment: two shards merged give the rows one run gives (times aside), and a table.
exp() { $NBV experiment --models bunny --metrics pc,random --trials 2 --iterations 2 --threads 1 "$@"; }
exp --out whole >/dev/null 2>&1 || fail "experiment"
exp --shard 1/2 --out part1 >/dev/null 2>&1 && exp --shard 2/2 --out part2 >/dev/null 2>&1 || fail "experiment shards"
$NBV experiment --merge part1 part2 --out merged >/dev/null 2>&1 || fail "experiment --merge"
cmp -s <(cut -d, -f1-8 whole/results.csv) <(cut -d, -f1-8 merged/results.csv) || fail "merged shards differ from one run"
[ "$(wc -l <whole/results.csv)" -eq 9 ] || fail "results.csv: 2 metrics x 2 trials x 2 iterations + header"
grep -q '^| bunny | pc | 2 |' whole/table.md || fail "table.md: $(cat whole/table.md)"
expect_error "merge twice" "also in another shard" -- $NBV experiment --merge part1 part1 --out twice
expect_error "bad shard" "3/2" -- $NBV experiment --models bunny --shard 3/2 --out x
expect_error "merge missing" "nothere" -- $NBV experiment --merge nothere --out x

$NBV frobnicate >/dev/null 2>&1; rc=$?; { [ $rc -ne 0 ] && [ $rc -lt 128 ]; } || fail "unknown subcommand exit $rc"
ls -a | grep -q '\.tmp-' && fail "temporary files left behind: $(ls -a)"

if [ "$failures" -eq 0 ]; then echo "cli: all checks passed"; else echo "cli: $failures failed"; exit 1; fi
