#!/usr/bin/env bash
# scripts/mca_mark_step.sh on this build's AVX-512 mark walk: it finds the step loop and
# estimates it, and the step moves the lanes' byte offsets in 32-bit integer lanes (S::O:
# vpaddd, no conversion from doubles inside the step; docs/performance-log.md has the estimates of
# both forms). Then its refusals: no object (exit 2), a missing file (exit 2), an object
# without the AVX-512 step (exit 1), each named.
# Usage: mca_mark_step_test.sh OBJECT...  (the objects of nbv_kernels; the test picks
# mark_rays_avx512.cpp.o and mark_rays_avx2.cpp.o among them)
set -uo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
SCRIPT="$HERE/../scripts/mca_mark_step.sh"
command -v llvm-mca > /dev/null || command -v llvm-mca-14 > /dev/null || { echo "no llvm-mca: skipped"; exit 77; }
avx512="" avx2=""
for o in "$@"; do
  case $o in
    */mark_rays_avx512.cpp.o) avx512=$o ;;
    */mark_rays_avx2.cpp.o) avx2=$o ;;
  esac
done
[ -n "$avx512" ] && [ -n "$avx2" ] || { echo "FAIL: no mark_rays_avx512/avx2 object among: $*"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

bash "$SCRIPT" --show "$avx512" > "$work/out.txt" 2> "$work/err.txt" || fail "exit $?: $(cat "$work/err.txt")"
grep -qE ': [0-9]+\.[0-9] cycles per step \([0-9]+ instructions' "$work/out.txt" || fail "no estimate in: $(cat "$work/out.txt")"
grep -q 'vpaddd' "$work/out.txt" || fail "the step adds no 32-bit integer lanes: $(cat "$work/out.txt")"
! grep -q 'vcvttpd2dq' "$work/out.txt" || fail "the step converts offsets from doubles: $(cat "$work/out.txt")"

expect() {  # expect STATUS MESSAGE ARGS...
  local status=$1 message=$2
  shift 2
  bash "$SCRIPT" "$@" > "$work/out.txt" 2> "$work/err.txt"
  local got=$?
  [ $got -eq "$status" ] || fail "$*: exit $got, expected $status: $(cat "$work/err.txt")"
  grep -qF -- "$message" "$work/err.txt" || fail "$*: no '$message' in: $(cat "$work/err.txt")"
}
expect 2 "usage:"
expect 2 "usage:" --show
expect 2 "$work/none.o: no such file" "$work/none.o"
expect 1 "$avx2: no AVX-512 mark step loop found" "$avx2"
echo "ok"
