#!/usr/bin/env bash
# hfbake setup on Debian bookworm: installs what is missing (apt-get, idempotent), builds, then
#   ./setup.sh demo            installs only what hfbake needs to build and run, builds only the hfbake
#                              executable, bakes jobs/demo.json and prints where the outputs went
#   ./setup.sh install [PREFIX] as demo's build plus the Python module, then `cmake --install` into PREFIX
#                              (default /usr/local; sudo when it is not writable): PREFIX/bin/hfbake,
#                              PREFIX/share/hfbake/{schemas, hfbake.ocio}, PREFIX/share/doc/hfbake (README, docs, jobs)
#                              (docs/install.md); the Python module hfbake into Debian's system Python
#                              (/usr/lib/python3/dist-packages, docs/python.md), or, for a user who is
#                              not root installing into a PREFIX they can write (~/.local), into their
#                              own site-packages (python3 -m site --user-site)
#   ./setup.sh package         as demo's build, then a Debian package through CPack (build/hfbake_*.deb)
#   ./setup.sh build           everything a developer builds: hfbake, the tests and the benchmarks
#   ./setup.sh test            as build, plus the test-only packages (Slurm and munge for the farm tests,
#                              chromium, clang, python3); runs the whole test suite through CTest, then builds
#                              the AddressSanitizer + UndefinedBehaviorSanitizer variant (ASAN_BUILD_DIR, default
#                              build-asan) and runs the test suite again under it (docs/development.md
#                              "Sanitizers" says what it leaves out), then builds the libFuzzer harnesses with
#                              clang (FUZZ_BUILD_DIR, default build-fuzz) and runs each for FUZZ_SECONDS
#                              (default 60) under ASan + UBSan (tests/fuzz/run_fuzzers.sh)
# Environment: BUILD_DIR (default build), ASAN_BUILD_DIR (default build-asan), JOBS (parallel build jobs,
# default: cores), SANITIZE=0 to skip the sanitized run of `test`, FUZZ=0 to skip the fuzzers.
set -euo pipefail
cd "$(dirname "$0")"
mode=${1:-build}
build_dir=${BUILD_DIR:-build}
jobs=${JOBS:-$(nproc)}

case "$mode" in
  demo | install | package | build | test) ;;
  *)
    echo "usage: $0 demo | install [PREFIX] | package | build | test" >&2
    exit 2
    ;;
esac

# What compiling and running hfbake needs (the -dev packages pull in the shared libraries it runs with).
packages=(g++ make cmake pkg-config git
  libembree-dev libtbb-dev libopenexr-dev libopenimageio-dev libopencolorio-dev
  nlohmann-json3-dev libcli11-dev)
# A developer's build: GDAL's development package, the test and benchmark frameworks, GDAL's and
# OpenImageIO's tools (the truth of the GeoTIFF and texture tests), and valijson installed as a package.
# demo, install and package take GDAL's shared library alone and unpack the headers of libgdal-dev and
# libvalijson-dev into the build folder (below).
if [ "$mode" = build ] || [ "$mode" = test ]; then
  packages+=(libgdal-dev libgtest-dev libbenchmark-dev gdal-bin openimageio-tools libvalijson-dev)
  packages+=(zlib1g-dev)  # the PNG tests write interlaced PNGs, which neither GDAL nor OpenImageIO writes
else
  packages+=(libgdal32)
fi
# CPack's Debian generator finds the package's dependencies with dpkg-shlibdeps.
if [ "$mode" = package ]; then
  packages+=(dpkg-dev)
fi
# The Python module (python/): pybind11 and numpy for Debian's system Python.
if [ "$mode" = install ] || [ "$mode" = build ] || [ "$mode" = test ]; then
  packages+=(python3-dev pybind11-dev python3-numpy)
fi
if [ "$mode" = test ]; then
  packages+=(slurm-wlm munge)               # the farm's integration tests start a one-node Slurm (tests/farm)
  packages+=(chromium)                      # the HTML report test renders the page in headless Chromium
  packages+=(clang libclang-rt-14-dev)      # the libFuzzer harnesses (tests/fuzz): clang and its libFuzzer
  packages+=(python3)                       # tests/hostile/random_jobs.py: random valid jobs baked under a time limit
  packages+=(python3-pytest python3-openimageio python3-gdal)  # the Python module's tests (python/tests)
  packages+=(qgis python3-qgis)             # the QGIS provider's test runs qgis_process (about 5 minutes to install)
fi

sudo_if_needed() {
  if [ "$(id -u)" -eq 0 ]; then "$@"; else sudo "$@"; fi
}

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  sudo_if_needed apt-get update -qq
  # --force-unsafe-io: dpkg unpacks without an fsync per file (a third of the install's time on a virtual
  # disk); a machine that loses power mid-install reinstalls the packages it was unpacking.
  DEBIAN_FRONTEND=noninteractive sudo_if_needed apt-get install -y -qq --no-install-recommends \
    -o Dpkg::Options::=--force-unsafe-io "${missing[@]}"
else
  echo "setup: all ${#packages[@]} packages present"
fi

# unpack_dev PACKAGE FILE: unpacks a Debian package's files into $build_dir/dev/PACKAGE (apt-get download,
# dpkg-deb -x; nothing is installed) unless FILE is already there; prints that folder.
unpack_dev() {
  local root="$build_dir/dev/$1"
  mkdir -p "$root"
  root=$(cd "$root" && pwd)
  if [ ! -e "$root/$2" ]; then
    (cd "$root" && rm -f "$1"_*.deb &&
      { apt-get download -qq "$1" 2>/dev/null ||
        { sudo_if_needed apt-get update -qq && apt-get download -qq "$1"; }; } &&
      dpkg-deb -x "$1"_*.deb .) >&2
    echo "setup: $1 unpacked into $root" >&2
  fi
  echo "$root"
}
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

# valijson is headers only, and hfbake uses its nlohmann-json adapter alone; but Debian's libvalijson-dev
# depends on every JSON library valijson has an adapter for (Qt 5, Poco, yaml-cpp, jsoncpp, ...: about 110
# packages on a bare system). libgdal-dev depends on the -dev packages of every format and database GDAL
# reads (about 80 packages); hfbake needs only its headers and CMake files, and links the installed libgdal32.
# Without the packages, hfbake builds against their unpacked files.
dev_options=()
if ! installed libvalijson-dev; then
  root=$(unpack_dev libvalijson-dev usr/include/valijson/schema_parser.hpp)
  dev_options+=(-DVALIJSON_INCLUDE_DIR="$root/usr/include")
fi
if ! installed libgdal-dev; then
  root=$(unpack_dev libgdal-dev usr/include/gdal/gdal.h)
  # The CMake files name the library in their own tree: point it at the installed one.
  multiarch=$(gcc -print-multiarch)
  for lib in /usr/lib/"$multiarch"/libgdal.so.*.*; do
    ln -sf "$lib" "$root/usr/lib/$multiarch/"
  done
  dev_options+=(-DGDAL_DIR="$root/usr/lib/$multiarch/cmake/gdal")
fi

# The executable alone (demo, install, package), or everything with the tests and benchmarks. The options
# are given every time: a build folder configured by one mode is reconfigured by the next.
if [ "$mode" = build ] || [ "$mode" = test ]; then
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DHFBAKE_BUILD_TESTS=ON -DHFBAKE_BUILD_BENCHMARKS=ON \
    -DHFBAKE_UNITY_BUILD=OFF "${dev_options[@]}" >/dev/null
  cmake --build "$build_dir" -j "$jobs"
else
  prefix=${2:-/usr/local}
  python=OFF
  targets=(hfbake)
  python_dir=(-UHFBAKE_PYTHON_INSTALL_DIR)  # the system Python's dist-packages (python/CMakeLists.txt)
  if [ "$mode" = install ]; then
    python=ON
    targets+=(_hfbake)
    if [ "$(id -u)" != 0 ] && mkdir -p "$prefix" 2>/dev/null && [ -w "$prefix" ]; then
      python_dir=("-DHFBAKE_PYTHON_INSTALL_DIR=$(/usr/bin/python3 -m site --user-site)")
    fi
  fi
  # Position-independent code in every mode: the Python module (install) needs it, and demo's objects are
  # then install's, so `install` after `demo` compiles the module alone.
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DHFBAKE_BUILD_TESTS=OFF -DHFBAKE_BUILD_BENCHMARKS=OFF \
    -DHFBAKE_BUILD_PYTHON=$python "${python_dir[@]}" -DHFBAKE_UNITY_BUILD=ON -DCMAKE_INSTALL_PREFIX="$prefix" \
    -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
    "${dev_options[@]}" >/dev/null
  cmake --build "$build_dir" -j "$jobs" --target "${targets[@]}"
fi

case "$mode" in
  build) ;;
  demo)
    "$build_dir/baker/cli/hfbake" bake jobs/demo.json --out out/demo --summary out/demo-summary.json
    echo
    echo "demo outputs:"
    ls -l out/demo
    echo "summary: $(pwd)/out/demo-summary.json"
    echo "hfbake is at $(cd "$build_dir/baker/cli" && pwd)/hfbake; ./setup.sh install puts it on PATH"
    ;;
  install)
    mkdir -p "$prefix" 2>/dev/null || true
    if [ -w "$prefix" ]; then cmake --install "$build_dir"; else sudo_if_needed cmake --install "$build_dir"; fi
    echo "setup: installed $prefix/bin/hfbake ($("$prefix/bin/hfbake" --version))"
    /usr/bin/python3 -c "import hfbake; print('setup: Python module hfbake', hfbake.__version__, 'at', hfbake.__file__)"
    case ":$PATH:" in
      *":$prefix/bin:"*) ;;
      *) echo "setup: $prefix/bin is not on PATH: export PATH=\"$prefix/bin:\$PATH\"" ;;
    esac
    ;;
  package)
    (cd "$build_dir" && cpack -G DEB >/dev/null)
    echo "setup: $(ls "$build_dir"/hfbake_*.deb)"
    ;;
  test)
    ctest --test-dir "$build_dir" --output-on-failure -j "$jobs"
    # The sanitizer and fuzzing builds: -O1 with line tables only (what OSS-Fuzz builds with), half the
    # compile time of -O2 -g; reports still name every frame's file and line.
    sanitizer_flags="-O1 -g1 -DNDEBUG"
    if [ "${SANITIZE:-1}" != 0 ]; then
      asan_dir=${ASAN_BUILD_DIR:-build-asan}
      echo "setup: AddressSanitizer + UndefinedBehaviorSanitizer build in $asan_dir"
      cmake -S . -B "$asan_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$sanitizer_flags" \
        -DHFBAKE_SANITIZE=address,undefined -DHFBAKE_UNITY_BUILD=ON \
        -DHFBAKE_BUILD_BENCHMARKS=OFF -DHFBAKE_BUILD_PYTHON=OFF >/dev/null
      cmake --build "$asan_dir" -j "$jobs"
      # Any finding fails the test that made it (UBSan halts on error, like ASan). Left out, because they
      # cannot run usefully under the sanitizers: docs/development.md, "Sanitizers". intercept_tls_get_addr=0:
      # GCC 12's runtime takes a dynamic TLS block that happens to start 16 bytes past a page for a glibc 2.19
      # header, and LeakSanitizer's scan at exit then crashes on the range it reads from it (an exit of 1
      # with no leak, depending only on the memory layout; google/sanitizers#1322).
      ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:halt_on_error=1:intercept_tls_get_addr=0 \
        LSAN_OPTIONS=suppressions=$(pwd)/tests/sanitizers/lsan.supp:print_suppressions=0 \
        UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
        ctest --test-dir "$asan_dir" --output-on-failure -j "$jobs" -LE integration
    fi
    if [ "${FUZZ:-1}" != 0 ]; then
      fuzz_dir=${FUZZ_BUILD_DIR:-build-fuzz}
      echo "setup: libFuzzer harnesses (clang, ASan + UBSan) in $fuzz_dir, ${FUZZ_SECONDS:-60} s each"
      cmake -S . -B "$fuzz_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$sanitizer_flags" \
        -DCMAKE_CXX_COMPILER=clang++ -DHFBAKE_FUZZ=ON \
        -DHFBAKE_BUILD_TESTS=OFF -DHFBAKE_BUILD_BENCHMARKS=OFF -DHFBAKE_BUILD_PYTHON=OFF >/dev/null
      cmake --build "$fuzz_dir" -j "$jobs" --target fuzz_job fuzz_height_image fuzz_environment fuzz_report \
        fuzz_shard
      tests/fuzz/run_fuzzers.sh "$fuzz_dir" "${FUZZ_SECONDS:-60}"
    fi
    ;;
esac
