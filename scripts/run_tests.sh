#!/usr/bin/env bash
# Install, build, and run every test: the Release build and the installed package from a consumer project,
# the Python package's tests, the suite under ASan and UBSan, the concurrency test under TSan, and each fuzz target for a bounded time.
# The suite runs once, in the sanitizers' tree: a run in Release as well checked the same assertions again,
# without the memory checks.
set -euo pipefail
cd "$(dirname "$0")/.."
step() {  # <script>...: runs them (several side by side, each one's output after it ends) and says how long
  local start=$SECONDS pids=() failed=0 i
  if (($# == 1)); then
    bash "scripts/$1"
  else
    mkdir -p build/step_logs
    for i in "$@"; do
      bash "scripts/$i" >"build/step_logs/$i.log" 2>&1 &
      pids+=($!)
    done
    for i in "${!pids[@]}"; do
      wait "${pids[$i]}" || failed=1
      cat "build/step_logs/${@:i+1:1}.log"
    done
  fi
  echo "== $* took $((SECONDS - start)) s"
  ((failed == 0)) || { echo "a step failed: $*" >&2; exit 1; }
}
step install_deps.sh
# The Release tree serves the package and Python tests, which do not run fot_bench; the sanitizers' tree, which
# holds the suite, leaves the benchmark out as well. Building it here cost about 200 CPU-s.
PCL_FOT_BUILD_BENCHMARKS=OFF step build.sh
# The package test and the Python tests each leave a core idle half the time (configure, pytest, Dask's start).
step test_package.sh test_python.sh
step test_sanitizers.sh
step test_fuzz.sh
echo "All tests passed in $SECONDS s."
