#!/usr/bin/env bash
# Installs the built library into a scratch prefix and builds and runs a C++-only consumer project against
# it with find_package(pcl_fot): the basic use, and the templates with a custom point type, mixed types and
# double. (Each header compiles on its own: the suite's build checks that once.) Expects build/ from
# scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
export CMAKE_GENERATOR=${CMAKE_GENERATOR:-Ninja}  # see scripts/build.sh
prefix="$PWD/build/package_test/prefix"
rm -rf build/package_test
cmake --install build --prefix "$prefix" >/dev/null
cmake -S test/consumer -B build/package_test/consumer -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/package_test/consumer -j2 >build/package_test/build.log 2>&1 ||
  { cat build/package_test/build.log; exit 1; }
LD_LIBRARY_PATH="$prefix/lib" build/package_test/consumer/consumer
LD_LIBRARY_PATH="$prefix/lib" build/package_test/consumer/point_types
echo "package test: the consumer and its point types built against $prefix, and ran"
