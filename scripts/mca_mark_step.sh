#!/bin/bash
# A static estimate of the AVX-512 mark walk's step (kernels/src/mark_rays_packet.hpp, Store
# mode), to compare builds on a CPU that cannot time them: llvm-mca's cycles per step of the
# step loop as the compiler emitted it.
#
#   scripts/mca_mark_step.sh [--show] OBJECT [OBJECT...]
#
# OBJECT: a compiled mark_rays_avx512.cpp.o, this build's at
# build/kernels/CMakeFiles/nbv_kernels.dir/src/ or an earlier commit's under
# build-ab/build-<commit>/ (`make ab-kernels BEFORE=<commit>` builds it). The step is the loop
# that ends in `cmp $0xff,%cl; jne HEAD` (have all eight lanes ended?), read from HEAD to the
# 32-byte store of the lanes' offsets that the byte stores then read back. The model is
# llvm-mca's Ice Lake server: Debian's LLVM 14 has none for Zen 4 or Zen 5. An estimate
# compares two builds' code; a timing on an AVX-512 CPU (make ab-kernels) decides.
# --show prints each step's instructions too.
set -euo pipefail

usage() {
  echo "usage: $0 [--show] OBJECT [OBJECT...]  (OBJECT: a mark_rays_avx512.cpp.o)" >&2
  exit 2
}
show=0
if [ "${1:-}" = --show ]; then
  show=1
  shift
fi
[ $# -ge 1 ] || usage
mca=$(command -v llvm-mca || command -v llvm-mca-14) ||
  { echo "$0: llvm-mca not found (Debian package llvm-14, which clang installs)" >&2; exit 2; }
for obj; do
  [ -f "$obj" ] || { echo "$0: $obj: no such file" >&2; exit 2; }
done

step=$(mktemp)
trap 'rm -f "$step"' EXIT
for obj; do
  # Instructions as "address<TAB>text"; the first `cmp $0xff,%cl` followed by a backward jne
  # closes the step loop, whose head is the jne's target.
  if ! objdump -d --no-show-raw-insn "$obj" |
    awk -F'\t' '
      /^ +[0-9a-f]+:\t/ { n++; sub(/^ +/, "", $1); sub(/:$/, "", $1); at[n] = $1; text[n] = $2 }
      END {
        for (i = 1; i < n; i++) {
          if (text[i] !~ /^cmp +\$0xff,%cl$/ || text[i + 1] !~ /^jne /) continue
          split(text[i + 1], jump, / +/)
          for (j = 1; j < i && at[j] != jump[2]; j++) {}
          if (j == i) continue
          for (; j <= i; j++) {
            if (text[j] ~ /^nop/) continue
            print text[j]
            if (text[j] ~ /^vmovdq[au](32|64)? +%ymm[0-9]+,.*\(%r[sb]p\)$/) { print "cmp $0xff,%cl"; exit 0 }
          }
        }
        exit 1
      }' >"$step"; then
    echo "$0: $obj: no AVX-512 mark step loop found (another compiler, or a build without the AVX-512 walks?)" >&2
    exit 1
  fi
  cycles=$("$mca" -mcpu=icelake-server -iterations=1000 "$step" 2>/dev/null | sed -n 's/^Total Cycles: *\([0-9]*\)$/\1/p')
  [ -n "$cycles" ] || { echo "$0: llvm-mca read no cycles from $obj's step" >&2; exit 1; }
  awk -v obj="$obj" -v cycles="$cycles" -v count="$(wc -l <"$step")" 'BEGIN {
    printf "%s: %.1f cycles per step (%d instructions; llvm-mca, Ice Lake server)\n", obj, cycles / 1000, count }'
  [ $show -eq 0 ] || sed 's/^/    /' "$step"
done
