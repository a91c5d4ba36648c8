#!/usr/bin/env bash
# Configures and builds pcl_fot in Release into build/: the library, the tools and fot_bench (two jobs: PCL's
# headers are heavy). The test suite has its own tree, built with the sanitizers (scripts/test_sanitizers.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPCL_FOT_BUILD_TESTS=OFF
cmake --build build -j2
