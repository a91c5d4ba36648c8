#!/usr/bin/env bash
# Install, build, and run every test: the Release build and the installed package from a consumer project,
# the Python package's tests, the suite under ASan and UBSan, the concurrency test under TSan, and each fuzz target for a bounded time.
# The suite runs once, in the sanitizers' tree: a run in Release as well checked the same assertions again,
# without the memory checks.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
bash scripts/test_package.sh
bash scripts/test_python.sh
bash scripts/test_sanitizers.sh
bash scripts/test_fuzz.sh
echo "All tests passed."
