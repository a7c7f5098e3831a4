#!/usr/bin/env bash
# Installs the Debian packages ctk builds against, only those that are missing.
# Idempotent: when everything is present it makes no network call and returns in well under a second.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev          # linear algebra
  libceres-dev           # least squares (pose fits, bundle adjustment)
  libopencv-dev          # circle detection, image filters
  libopenimageio-dev     # TIFF/EXR/PNG I/O
  openimageio-tools      # its CMake package file refers to these binaries
  libopenexr-dev         # EXR
  libtiff-dev            # TIFF projections read directly (libdeflate)
  libhdf5-dev            # HDF5 volumes
  libgeographiclib-dev   # equal-area map projection
  libhealpix-cxx-dev     # sphere pixelisation
  libcli11-dev           # command line
  libpugixml-dev         # XML (RTK geometry files)
  libcairo2-dev fonts-dejavu-core   # report pictures: antialiased lines, text in DejaVu Sans
  nlohmann-json3-dev     # JSON
  libgtest-dev libgmock-dev   # tests
  libbenchmark-dev       # benchmarks
  libhwy-dev             # SIMD with runtime dispatch (Highway)
  libopenmpi-dev openmpi-bin   # runs spread over ranks (mpirun -np N ctk reconstruct|calibrate)
  clang-format           # tests/format: the sources as .clang-format says
  clang-tidy             # tests/tidy: the base layers checked by .clang-tidy
  python3                # benchmarks/yardstick.py: the benchmark checked from outside (standard library only)
  python3-dev pybind11-dev python3-numpy   # the Python module (import ctk)
  python3-scipy python3-pytest python3-matplotlib   # its tests (scipy's solvers on the operator) and examples
  chromium               # headless, to check that the HTML reports render
)

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} build packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
