#!/usr/bin/env bash
# Installs the Debian packages ctk needs, only those that are missing.
#   setup.sh          what the main job needs: build the `ctk` command and run it
#   setup.sh --tests  that, and what the test suite, the benchmarks and the Python module add
# Idempotent: when everything is present it makes no network call and returns in well under a second.
set -euo pipefail

run_packages=(
  build-essential cmake pkg-config
  libeigen3-dev          # linear algebra
  libceres-dev           # least squares (pose fits, bundle adjustment)
  libopencv-core-dev libopencv-imgproc-dev   # circle detection, image filters (these modules only)
  libopenimageio-dev     # image formats beyond plain TIFFs (EXR, tiled TIFF, ...), loaded on first use
  openimageio-tools      # its CMake package file refers to these binaries
  libopenexr-dev         # EXR
  libtiff-dev            # TIFF projections and volumes read and written directly (libdeflate)
  libpng-dev             # PNG pictures
  libhdf5-dev            # HDF5 volumes, NXtomo
  libgeographiclib-dev   # equal-area map projection
  libhealpix-cxx-dev     # sphere pixelisation
  libcli11-dev           # command line
  libpugixml-dev         # XML (RTK geometry files)
  libcairo2-dev fonts-dejavu-core   # report pictures: antialiased lines, text in DejaVu Sans
  nlohmann-json3-dev     # JSON
  libhwy-dev             # SIMD with runtime dispatch (Highway)
  libboost-dev           # header-only statistics (Student's t quantiles of the diagnosis' acceptance)
)
test_packages=(
  libgtest-dev libgmock-dev   # tests
  libbenchmark-dev       # benchmarks
  libopenmpi-dev openmpi-bin   # runs spread over ranks (mpirun -np N ctk reconstruct|calibrate)
  clang-format           # tests/format: the sources as .clang-format says
  clang-tidy             # tests/tidy: the base layers checked by .clang-tidy
  python3                # benchmarks/yardstick.py: the benchmark checked from outside (standard library only)
  python3-dev pybind11-dev python3-numpy   # the Python module (import ctk)
  python3-scipy python3-pytest python3-matplotlib   # its tests (scipy's solvers on the operator) and examples
  python3-h5py python3-tifffile python3-pil   # other tools' readers and writers, against ctk's files
  chromium               # headless, to check that the HTML reports render
)

packages=("${run_packages[@]}")
what="run"
if [[ "${1:-}" == "--tests" ]]; then
  packages+=("${test_packages[@]}")
  what="run and test"
elif [[ $# -gt 0 ]]; then
  echo "usage: setup.sh [--tests]" >&2
  exit 2
fi

missing=()
for p in "${packages[@]}"; do
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} $what packages present"
  exit 0
fi

echo "setup: installing ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "setup: done"
