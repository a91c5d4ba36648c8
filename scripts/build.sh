#!/usr/bin/env bash
# Configures and builds pcl_fot in Release into build/ (two jobs: PCL's headers are heavy).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j2
