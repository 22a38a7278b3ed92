#!/bin/bash
# The ray walks of an earlier commit against this build's, side by side in one process
# (bench/ab_kernels.cpp): builds BEFORE's libnbv_kernels.so in a git worktree under build-ab/,
# then runs nbv_ab_kernels on each workload with both libraries. Run by `make ab-kernels`.
#
#   scripts/ab_kernels.sh BUILD_DIR BEFORE [ISA] [ROUNDS] [WORKLOADS]
#
# BUILD_DIR: a release build of this tree with nbv_ab_kernels (the "after"). BEFORE: a commit.
# ISA: avx512, avx2 or scalar; default the widest this CPU and build run (`nbv --version`).
# ROUNDS: default 10. WORKLOADS: default "mark proximity full released" (see ab_kernels.cpp;
# full and released need `make models`). Each line of the output names the library, its
# fastest round, lower quartile and median, and what it computed, which must be equal.
set -euo pipefail

usage() {
  echo "usage: $0 BUILD_DIR BEFORE [avx512|avx2|scalar] [ROUNDS] [\"mark proximity full released\"]" >&2
  exit 2
}
[ $# -ge 2 ] || usage
build=$1
before=$2
rounds=${4:-10}
workloads=${5:-mark proximity full released}

ab=$build/bench/nbv_ab_kernels
after_lib=$build/kernels/libnbv_kernels.so
for f in "$ab" "$after_lib" "$build/apps/nbv"; do
  [ -e "$f" ] || { echo "$0: $f is missing: build $build first (make build)" >&2; exit 2; }
done
isa=${3:-$("$build/apps/nbv" --version | sed -n 's/^ray walks: \([a-z0-9]*\).*/\1/p')}
case $isa in avx512 | avx2 | scalar) ;; *) echo "$0: ISA '$isa' is not avx512, avx2 or scalar" >&2; exit 2 ;; esac
case $rounds in '' | *[!0-9]* | 0) echo "$0: ROUNDS '$rounds' is not a whole number >= 1" >&2; exit 2 ;; esac

repo=$(git -C "$(dirname "$0")" rev-parse --show-toplevel 2>/dev/null) || {
  echo "$0: not in a git checkout: BEFORE's sources come from git" >&2
  exit 2
}
sha=$(git -C "$repo" rev-parse --verify --quiet "$before^{commit}") || {
  echo "$0: '$before' is not a commit of $repo" >&2
  exit 2
}
short=${sha:0:10}
work=$repo/build-ab
source_dir=$work/src-$short
build_dir=$work/build-$short
mkdir -p "$work"
if [ ! -d "$source_dir" ]; then
  git -C "$repo" worktree add --detach --quiet "$source_dir" "$sha"
fi
# Only the kernels library, in a release build with the default options (as `make build`).
cmake -S "$source_dir" -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DNBV_BUILD_TESTS=OFF \
  -DNBV_BUILD_BENCHMARKS=OFF -DNBV_BUILD_APPS=OFF -DNBV_BUILD_EXAMPLES=OFF -DNBV_BUILD_PYTHON=OFF \
  >"$work/configure-$short.log" 2>&1 || { echo "$0: configuring $before failed: see $work/configure-$short.log" >&2; exit 1; }
cmake --build "$build_dir" -j "$(nproc)" --target nbv_kernels >"$work/build-$short.log" 2>&1 ||
  { echo "$0: building $before's kernels failed: see $work/build-$short.log" >&2; exit 1; }

# Copies under names that say which build each is (nbv_ab_kernels prints the names).
cp "$build_dir/kernels/libnbv_kernels.so" "$work/before-$short.so"
cp "$after_lib" "$work/after.so"
echo "before: $before ($short), after: $build ($(git -C "$repo" describe --always --dirty)); $isa, $rounds rounds"
for workload in $workloads; do
  echo "== $workload"
  "$ab" "$isa" "$rounds" "$workload" "$work/before-$short.so" "$work/after.so"
done
