#!/usr/bin/env bash
# The test suite built with AddressSanitizer and UndefinedBehaviorSanitizer (its only run), and the concurrency
# test built with ThreadSanitizer, each in its own build tree. Any report fails the run. Both trees compile the
# templates for the point types their tests use only (PCL_FOT_POINT_TYPES), and line tables only for stack
# traces (-g1). The ASan tree is clang's, which compiles the suite faster than GCC; its tools and test programs
# leave the peers' headers (PCL, Eigen, OctoMap, ...) uninstrumented (cmake/sanitizer_ignorelist.txt). lld links each test
# program in a seventh of the time ld takes.
set -euo pipefail
cd "$(dirname "$0")/.."
export CMAKE_GENERATOR=${CMAKE_GENERATOR:-Ninja}  # see scripts/build.sh

configure() {  # <build dir> <point types> <sanitizer flags> [<cmake argument>...]
  local dir=$1 types=$2 flags=$3
  shift 3
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
        -DPCL_FOT_BUILD_BENCHMARKS=OFF -DPCL_FOT_BUILD_PYTHON=OFF -DPCL_FOT_POINT_TYPES="$types" \
        -DCMAKE_CXX_FLAGS="$flags -fno-omit-frame-pointer" -DCMAKE_EXE_LINKER_FLAGS="$flags -fuse-ld=lld" \
        -DCMAKE_SHARED_LINKER_FLAGS="$flags -fuse-ld=lld" "$@" >/dev/null
}

echo "== AddressSanitizer + UndefinedBehaviorSanitizer: the test suite; ThreadSanitizer: readers in parallel"
# Under ASan, Eigen switches to its own aligned allocator; PCL's libraries were built with the system one,
# and both must agree, since an Eigen-aligned PCL object may be freed on the other side.
CC=clang CXX=clang++ configure build-asan "pcl::PointXYZ;pcl::PointNormal" \
  "-fsanitize=address,undefined -fno-sanitize-recover=all -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
cmake --build build-asan -j2
# One test program: the headers the suite precompiles for all its programs would cost it more than they save.
configure build-tsan "pcl::PointXYZ" "-fsanitize=thread" -DCMAKE_DISABLE_PRECOMPILE_HEADERS=ON
cmake --build build-tsan -j2 --target test_concurrency

# The TSan program runs beside the suite: on its own it kept one core idle half its time.
TSAN_OPTIONS="halt_on_error=1 suppressions=$PWD/test/tsan.supp" build-tsan/test/test_concurrency \
  >build-tsan/test_concurrency.log 2>&1 &
tsan=$!
failed=0
# LeakSanitizer would report what VTK and PCL keep until exit. pcl_viewer, in the Viewer tests, is not
# instrumented and ignores these options.
ASAN_OPTIONS=detect_leaks=0:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan --output-on-failure -j2 || failed=1
echo "== ThreadSanitizer: readers in parallel on real maps and searches"
wait "$tsan" || failed=1
cat build-tsan/test_concurrency.log
exit "$failed"
