#!/bin/sh
# The per-instruction-set kernel objects (*_avx2.cpp.o, *_avx512.cpp.o, *_f16c.cpp.o) define no weak code
# (nm's W or w): an inline function they emitted out of line, compiled for AVX2, AVX-512 or F16C, could be
# the copy the linker keeps for every caller, and would then fault on a processor without those
# instructions. (Weak data, V and u, is the same bytes whichever copy is kept.)
# Usage: isa_kernels_own_their_code.sh "<object>;<object>;..." (a CMake list of a library's objects).
set -eu
checked=0
bad=0
IFS=';'
for o in $1; do
  case "$o" in
    *_avx2.cpp.o | *_avx512.cpp.o | *_f16c.cpp.o) ;;
    *) continue ;;
  esac
  checked=$((checked + 1))
  weak=$(nm -C --defined-only "$o" | awk '$2 ~ /^[Ww]$/' || true)
  if [ -n "$weak" ]; then
    echo "$o defines weak code:" >&2
    echo "$weak" >&2
    bad=1
  fi
done
if [ "$checked" -eq 0 ]; then
  echo "no *_avx2 / *_avx512 / *_f16c objects among the library's" >&2
  exit 1
fi
echo "$checked kernel objects, no weak code"
exit $bad
