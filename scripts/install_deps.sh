#!/usr/bin/env bash
# Installs everything pcl_fot needs from Debian 12's own packages. Idempotent: when every package is
# already there it only asks dpkg, which takes well under a second.
set -euo pipefail

packages=(
  cmake make ninja-build g++ pkg-config lld          # build (lld links the sanitizer trees' programs)
  libpcl-dev pcl-tools libeigen3-dev libflann-dev   # PCL, Eigen, FLANN
  libboost-dev googletest libgtest-dev              # Boost, GoogleTest
  liboctomap-dev libnanoflann-dev libbenchmark-dev  # reference peers for tests and benchmarks
  xvfb x11-apps imagemagick libgl1-mesa-dri         # pcl_viewer screenshots: virtual display, software GL
  gnuplot-nox                                       # benchmark plots
  clang libclang-rt-14-dev                          # libFuzzer for the fuzz targets
  python3-dev pybind11-dev python3-numpy            # the Python package
  python3-pytest python3-dask python3-distributed   # its tests and the tiled mapping
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "Installing: ${missing[*]}"
$sudo apt-get update -q
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
