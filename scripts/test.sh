#!/usr/bin/env bash
# Installs what is missing, builds everything and runs the whole test suite through CTest.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh --tests
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DCTK_BUILD_TESTS=ON -DCTK_BUILD_BENCHMARKS=ON -DCTK_BUILD_PYTHON=ON \
      -DCTK_WITH_MPI=ON -DCTK_WARNINGS_AS_ERRORS=ON >/dev/null
cmake --build build -j"$(nproc)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
# The base layers', the measurements' and the projector's tests again under AddressSanitizer and UndefinedBehaviorSanitizer,
# any finding fatal (a separate build: -O1, no benchmarks, no Python, no MPI; the projector's SIMD
# kernels for every target make it about 10 minutes on 2 cores, their tests 1 minute).
cmake -S . -B build-sanitize -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DCTK_SANITIZE=ON \
      -DCTK_BUILD_BENCHMARKS=OFF -DCTK_BUILD_PYTHON=OFF -DCTK_WITH_MPI=OFF -DCTK_WARNINGS_AS_ERRORS=ON >/dev/null
cmake --build build-sanitize --target test_core test_image_io test_geom test_measure test_proj -j"$(nproc)"
# fontconfig keeps its configuration for the process's lifetime: not a leak of ours.
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizer/lsan.supp:print_suppressions=0"
build-sanitize/tests/test_core --gtest_brief=1
build-sanitize/tests/test_image_io --gtest_brief=1
build-sanitize/tests/test_geom --gtest_brief=1
build-sanitize/tests/test_measure --gtest_brief=1
build-sanitize/tests/test_proj --gtest_brief=1
echo "sanitizers: test_core, test_image_io, test_geom, test_measure and test_proj clean under AddressSanitizer and UndefinedBehaviorSanitizer"
