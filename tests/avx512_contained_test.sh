#!/usr/bin/env bash
# The AVX-512 code stays in the AVX-512 functions: every function of the given binaries whose
# machine code uses an AVX-512 register (zmm, the mask registers k0-k7, xmm/ymm 16-31) or an
# EVEX-only instruction must be one of the AVX-512 walks or their checks (a name holding
# "Avx512" or "avx512"). A standard or shared inline function compiled inside an AVX-512 target
# region would break this, and the linker may keep that copy for callers on any CPU (see
# kernels/src/avx512_target_begin.hpp). Usage: avx512_contained_test.sh OBJDUMP BINARY...
set -uo pipefail
OBJDUMP=$1
shift
status=0
for binary in "$@"; do
  [ -f "$binary" ] || { echo "FAIL: no binary $binary"; exit 1; }
  found=$("$OBJDUMP" -d --no-show-raw-insn -C "$binary" | awk '
    /^[0-9a-f]+ <.*>:$/ { fn = substr($0, index($0, "<")); next }
    /%zmm|%[xy]mm(1[6-9]|2[0-9]|3[01])|%k[0-7]|vpternlog|vpmovm2|2m[ \t]|\{1to[0-9]/ {
      if (!(fn in seen)) { seen[fn] = 1; print fn }
    }')
  avx512_functions=$(printf '%s\n' "$found" | grep -c . || true)
  outside=$(printf '%s\n' "$found" | grep -v -e 'Avx512' -e 'avx512' | grep . || true)
  if [ -n "$outside" ]; then
    echo "FAIL: $binary: AVX-512 instructions outside the AVX-512 functions:"
    printf '%s\n' "$outside" | cut -c1-300 | head -20
    status=1
  else
    echo "$binary: $avx512_functions functions with AVX-512 instructions, all of the AVX-512 walks or their checks"
  fi
done
exit $status
