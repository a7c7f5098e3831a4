#!/usr/bin/env bash
# The main job, end to end on the built-in example: installs what is missing, builds, then runs
# every stage ctk has on a small robot scan and prints its report. Output goes to ./example-run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target ctk
out=example-run
./build/tools/ctk example --out "$out"
./build/tools/ctk geometry --scan "$out/scan.json" --out "$out/geometry.json" --astra "$out/cone_vec.txt"
