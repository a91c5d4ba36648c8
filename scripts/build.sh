#!/usr/bin/env bash
# Configures and builds pcl_fot in Release into build/: the library, the tools, fot_bench and the Python package
# in build/python (two jobs: PCL's headers are heavy). The test suite has its own tree, built with the sanitizers (scripts/test_sanitizers.sh).
# PCL_FOT_BUILD_BENCHMARKS=OFF leaves fot_bench out (scripts/run_tests.sh does: its tests do not run it).
set -euo pipefail
cd "$(dirname "$0")/.."
# Ninja for new build trees (a tree configured before keeps its generator): it schedules the two jobs better
# than make's recursive Makefiles. The other scripts do the same.
export CMAKE_GENERATOR=${CMAKE_GENERATOR:-Ninja}
# The Python package is built for Debian's interpreter, the one install_deps.sh installs numpy and Dask for.
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DPCL_FOT_BUILD_TESTS=OFF -DPython_EXECUTABLE=/usr/bin/python3 \
  -DPCL_FOT_BUILD_BENCHMARKS="${PCL_FOT_BUILD_BENCHMARKS:-ON}"
cmake --build build -j2
