#!/bin/bash
# A compiler launcher that appends each compile's CPU seconds (user, system), wall seconds and source file to
# $TIME_COMPILE_LOG (default /tmp/hfbake-compile-times.log), one line each:
#   CCACHE_DISABLE=1 BUILD_DIR=/tmp/demo-build CMAKE_CXX_COMPILER_LAUNCHER=$PWD/docs/tools/time_compile.sh \
#     ./setup.sh demo
#   sort -n -r /tmp/hfbake-compile-times.log | head       # the costliest files
src=$(printf '%s\n' "$@" | grep -E '\.(cpp|cxx|cc)$' | tail -1)
exec /usr/bin/time -a -o "${TIME_COMPILE_LOG:-/tmp/hfbake-compile-times.log}" -f "%U %S %e $src" "$@"
