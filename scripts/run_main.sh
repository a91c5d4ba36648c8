#!/usr/bin/env bash
# The main job: install, build, and map the embedded default scene with fot_map into output/.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install_deps.sh
bash scripts/build.sh
mkdir -p output
./build/tools/fot_map -out output/fot_map "$@"
