#!/usr/bin/env bash
# hfbake setup on Debian bookworm: installs what is missing (apt-get, idempotent), builds, then
#   ./setup.sh demo   bakes jobs/demo.json and prints where the outputs went
#   ./setup.sh test   runs the whole test suite through CTest, then builds the AddressSanitizer +
#                     UndefinedBehaviorSanitizer variant (ASAN_BUILD_DIR, default build-asan) and runs the
#                     test suite again under it (see "Sanitizers" in README.md for what it leaves out)
#                     and then builds the libFuzzer harnesses with clang (FUZZ_BUILD_DIR, default build-fuzz)
#                     and runs each for FUZZ_SECONDS (default 60) under ASan + UBSan (tests/fuzz/run_fuzzers.sh)
#   ./setup.sh build  only installs and builds
#   ./setup.sh install  builds, then installs hfbake and the Python module hfbake (cmake --install: the
#                     module into the system Python's dist-packages)
# Environment: BUILD_DIR (default build), ASAN_BUILD_DIR (default build-asan), JOBS (parallel build jobs,
# default: cores), SANITIZE=0 to skip the sanitized run of `test`, FUZZ=0 to skip the fuzzers.
set -euo pipefail
cd "$(dirname "$0")"
mode=${1:-build}
build_dir=${BUILD_DIR:-build}
jobs=${JOBS:-$(nproc)}

packages=(build-essential cmake pkg-config git
  libembree-dev libtbb-dev libopenexr-dev libopenimageio-dev openimageio-tools libopencolorio-dev
  nlohmann-json3-dev libvalijson-dev libcli11-dev libgtest-dev libbenchmark-dev
  libgdal-dev gdal-bin)  # gdal-bin: gdalinfo / gdal_translate, the truth of the GeoTIFF tests
packages+=(python3-dev pybind11-dev python3-numpy)  # the Python module (python/)
packages+=(slurm-wlm munge)  # the farm's integration tests start a one-node Slurm (tests/farm)
if [ "$mode" = test ]; then
  packages+=(chromium)  # the HTML report test renders the page in headless Chromium
  packages+=(clang libclang-rt-14-dev)  # the libFuzzer harnesses (tests/fuzz): clang and its libFuzzer
  packages+=(python3)  # tests/hostile/random_jobs.py: random valid jobs baked under a time limit
  packages+=(python3-pytest python3-openimageio python3-gdal)  # the Python module's tests (python/tests)
  packages+=(qgis python3-qgis)  # the QGIS provider's test runs qgis_process (about 5 minutes to install)
fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
else
  echo "setup: all ${#packages[@]} packages present"
fi

cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$build_dir" -j "$jobs"

case "$mode" in
  build) ;;
  install)
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    $sudo cmake --install "$build_dir"
    /usr/bin/python3 -c "import hfbake; print('hfbake', hfbake.__version__, 'for Python:', hfbake.__file__)"
    ;;
  demo)
    "$build_dir/baker/cli/hfbake" bake jobs/demo.json --out out/demo --summary out/demo-summary.json
    echo
    echo "demo outputs:"
    ls -l out/demo
    echo "summary: $(pwd)/out/demo-summary.json"
    ;;
  test)
    ctest --test-dir "$build_dir" --output-on-failure -j "$jobs"
    if [ "${SANITIZE:-1}" != 0 ]; then
      asan_dir=${ASAN_BUILD_DIR:-build-asan}
      echo "setup: AddressSanitizer + UndefinedBehaviorSanitizer build in $asan_dir"
      cmake -S . -B "$asan_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DHFBAKE_SANITIZE=address,undefined \
        -DHFBAKE_BUILD_BENCHMARKS=OFF -DHFBAKE_BUILD_PYTHON=OFF >/dev/null
      cmake --build "$asan_dir" -j "$jobs"
      # Any finding fails the test that made it (UBSan halts on error, like ASan). Left out, because they
      # cannot run usefully under the sanitizers: see README.md, "Sanitizers".
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1 \
        LSAN_OPTIONS=suppressions=$(pwd)/tests/sanitizers/lsan.supp \
        UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        ctest --test-dir "$asan_dir" --output-on-failure -j "$jobs" -LE integration
    fi
    if [ "${FUZZ:-1}" != 0 ]; then
      fuzz_dir=${FUZZ_BUILD_DIR:-build-fuzz}
      echo "setup: libFuzzer harnesses (clang, ASan + UBSan) in $fuzz_dir, ${FUZZ_SECONDS:-60} s each"
      cmake -S . -B "$fuzz_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DHFBAKE_FUZZ=ON \
        -DHFBAKE_BUILD_TESTS=OFF -DHFBAKE_BUILD_BENCHMARKS=OFF -DHFBAKE_BUILD_PYTHON=OFF >/dev/null
      cmake --build "$fuzz_dir" -j "$jobs" --target fuzz_job fuzz_height_image fuzz_environment fuzz_report
      tests/fuzz/run_fuzzers.sh "$fuzz_dir" "${FUZZ_SECONDS:-60}"
    fi
    ;;
  *)
    echo "usage: $0 [build|demo|test|install]" >&2
    exit 2
    ;;
esac
