#!/usr/bin/env bash
# Installs the built library into a scratch prefix and builds and runs a C++-only consumer project against
# it with find_package(pcl_fot). Expects build/ from scripts/build.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
prefix="$PWD/build/package_test/prefix"
rm -rf build/package_test
cmake --install build --prefix "$prefix" >/dev/null
cmake -S test/consumer -B build/package_test/consumer -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build/package_test/consumer -j2 >/dev/null
LD_LIBRARY_PATH="$prefix/lib" build/package_test/consumer/consumer
echo "package test: the consumer built against $prefix and ran"
