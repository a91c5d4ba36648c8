#!/usr/bin/env bash
# Install, build, and run every test: the suite, the installed package from a consumer project, the suite
# under ASan and UBSan, the concurrency test under TSan, and each fuzz target for a bounded time.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j2
bash scripts/test_package.sh
bash scripts/test_sanitizers.sh
bash scripts/test_fuzz.sh
echo "All tests passed."
