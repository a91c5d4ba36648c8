#!/usr/bin/env bash
# Install, build, and run every test: the Release build and the installed package from a consumer project,
# the Python package's tests, the suite under ASan and UBSan, the concurrency test under TSan, and each fuzz target for a bounded time.
# The suite runs once, in the sanitizers' tree: a run in Release as well checked the same assertions again,
# without the memory checks.
set -euo pipefail
cd "$(dirname "$0")/.."
step() {  # <script>: runs it and says how long it took
  local start=$SECONDS
  bash "scripts/$1"
  echo "== $1 took $((SECONDS - start)) s"
}
for script in install_deps.sh build.sh test_package.sh test_python.sh test_sanitizers.sh test_fuzz.sh; do
  step "$script"
done
echo "All tests passed in $SECONDS s."
