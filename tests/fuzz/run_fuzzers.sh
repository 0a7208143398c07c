#!/usr/bin/env bash
# Runs each libFuzzer harness of a -DHFBAKE_FUZZ=ON build for a bounded time under ASan + UBSan, starting
# from its seed corpus (tests/fuzz/corpus/<name>, the job files in jobs/, bench/, tests/accuracy/ and tests/nightly/fields/, every regression input), and fails
# on any finding (a crash, an uncaught exception, UB, a leak, a timeout, more than the RSS limit, a
# multi-line error message). New corpus entries go to a scratch folder, never into the source tree.
#   tests/fuzz/run_fuzzers.sh BUILD_DIR SECONDS [NAME ...]      (names: job height_image environment report shard)
# FUZZ_TIMEOUT (default 60 s): an input slower than this is a finding. OpenEXR allocates and clears an
# attribute's declared size (up to 2 GiB) before it notices a short file: under ASan on a loaded machine such
# an input takes seconds (tens at nice 19 beside other work).
# A finding's input is kept as <scratch>/<name>/crash-*, a sanitizer's report as <scratch>/<name>/sanitizer.<pid>;
# add the input to tests/fuzz/regressions/<name>/ once fixed.
# Leaks are checked once, when each run ends (ASan's detect_leaks), not after every input (libFuzzer's
# -detect_leaks): OpenImageIO and OpenColorIO keep caches that look like a leak per input and would make every
# input a full leak scan. NEW_FUNC lines are not printed (-print_funcs=0: no symbolizer processes).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${1:?usage: run_fuzzers.sh BUILD_DIR SECONDS [NAME ...]}
seconds=${2:?seconds per fuzzer}
shift 2
names=("$@")
[ ${#names[@]} -gt 0 ] || names=(job height_image environment report shard)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/hfbake-fuzz.XXXXXX")
status=0
for name in "${names[@]}"; do
  exe="$build/tests/fuzz/fuzz_$name"
  [ -x "$exe" ] || { echo "run_fuzzers: $exe is missing (build with -DHFBAKE_FUZZ=ON)" >&2; exit 2; }
  mkdir -p "$scratch/$name/corpus"
  seeds=("$root/tests/fuzz/corpus/$name")
  [ -d "$root/tests/fuzz/regressions/$name" ] && seeds+=("$root/tests/fuzz/regressions/$name")
  [ "$name" = job ] && seeds+=("$root/jobs" "$root/jobs/examples" "$root/bench" "$root/tests/accuracy" "$root/tests/nightly/fields")
  echo "run_fuzzers: fuzz_$name for $seconds s"
  # Sanitizer reports go to files of their own: hfbake's image reader holds stderr in a temporary while a
  # library decodes (io/image_input.cpp), and a report written there would be lost with the process.
  if ! ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0:intercept_tls_get_addr=0:log_path=$scratch/$name/sanitizer \
      LSAN_OPTIONS=suppressions=$root/tests/sanitizers/lsan.supp \
      UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:log_path=$scratch/$name/sanitizer \
      "$exe" -max_total_time="$seconds" -timeout="${FUZZ_TIMEOUT:-60}" -rss_limit_mb=3072 -max_len=65536 -print_final_stats=1 \
        -detect_leaks=0 -print_funcs=0 \
        -artifact_prefix="$scratch/$name/" "$scratch/$name/corpus" "${seeds[@]}" \
        >"$scratch/$name/log.txt" 2>&1; then
    echo "run_fuzzers: fuzz_$name FOUND SOMETHING: $scratch/$name/log.txt, inputs $scratch/$name/crash-*" >&2
    grep -m5 -E "ERROR|SUMMARY|finding|runtime error" "$scratch/$name/log.txt" "$scratch/$name"/sanitizer.* >&2 || true
    status=1
    continue
  fi
  grep -E "stat::number_of_executed_units|stat::average_exec_per_sec|stat::peak_rss_mb" "$scratch/$name/log.txt" |
    tr '\n' ' '
  echo "corpus: $(ls "$scratch/$name/corpus" | wc -l) new inputs"
done
[ $status = 0 ] && rm -rf "$scratch"
exit $status
