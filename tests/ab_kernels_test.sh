#!/usr/bin/env bash
# scripts/ab_kernels.sh refuses what it cannot run, with exit 2 and a message naming it, before
# it builds anything: no arguments, a build folder without the A/B binary, a name that is not a
# commit, an unknown instruction set, a round count that is not a number.
# Usage: ab_kernels_test.sh BUILD_DIR
set -uo pipefail
BUILD=$1
HERE=$(cd "$(dirname "$0")" && pwd)
SCRIPT="$HERE/../scripts/ab_kernels.sh"
git -C "$HERE/.." rev-parse --git-dir > /dev/null 2>&1 || { echo "not a git checkout: skipped"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

expect() {  # expect MESSAGE ARGS...: exit 2 and MESSAGE in stderr
  local message=$1
  shift
  bash "$SCRIPT" "$@" > "$work/out.txt" 2> "$work/err.txt"
  local status=$?
  [ $status -eq 2 ] || fail "$*: exit $status, expected 2: $(cat "$work/err.txt")"
  grep -qF -- "$message" "$work/err.txt" || fail "$*: no '$message' in: $(cat "$work/err.txt")"
}
expect "usage:"
expect "$work/none/bench/nbv_ab_kernels is missing" "$work/none" HEAD
expect "'no-such-commit' is not a commit" "$BUILD" no-such-commit avx2 1
expect "ISA 'sse' is not avx512, avx2 or scalar" "$BUILD" HEAD sse 1
expect "ROUNDS 'ten' is not a whole number >= 1" "$BUILD" HEAD avx2 ten
echo "ok"
