#!/usr/bin/env bash
# The Python package's tests (python/tests) with Debian's pytest, against the Release build of
# scripts/build.sh: the bindings against the C++ tools' results, bad input, and tiled mapping on Dask equal to
# the single-process map. The real-scan tests run where the scans are found (PCL_FOT_DATA_DIR or ../shared/data).
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHONPATH="$PWD/build/python" PCL_FOT_TOOLS_DIR="$PWD/build/tools" \
  /usr/bin/python3 -m pytest -q -p no:cacheprovider -W ignore::DeprecationWarning python/tests
