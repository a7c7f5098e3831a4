#!/usr/bin/env bash
# The main job, end to end on the built-in example: installs what is missing, builds, then runs
# every stage ctk has on a small robot scan and prints its report. Output goes to ./example-run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh   # the run set only: no test, benchmark or Python packages
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DCTK_BUILD_TESTS=OFF -DCTK_BUILD_BENCHMARKS=OFF -DCTK_BUILD_PYTHON=OFF \
      -DCTK_WITH_MPI=OFF >/dev/null
cmake --build build -j"$(nproc)" --target ctk
bash scripts/example_run.sh ./build/tools/ctk example-run
