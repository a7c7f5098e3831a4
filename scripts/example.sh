#!/usr/bin/env bash
# The main job, end to end on the built-in example: installs what is missing, builds, then runs
# every stage ctk has on a small robot scan and prints its report. Output goes to ./example-run.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j"$(nproc)" --target ctk
out=example-run
rm -rf "$out"
# A small robot scan of the helix holder around thesis sample 2, with Poisson noise and the
# robot's pose noise: 90 views of 360 x 360 px at 1.2 mm.
./build/tools/ctk simulate --out "$out" --phantom helix-holder --phantom sample-2 --views 90 \
  --cols 360 --rows 360 --pitch 1.2
./build/tools/ctk geometry --scan "$out/scan.json" --out "$out/geometry.json" --astra "$out/cone_vec.txt"
# Calibrate every view from the helix spheres (robot FK as the first guess), then reconstruct
# with the calibrated matrices; the simulator's truth is in $out/truth-geometry.json to compare.
./build/tools/ctk calibrate --scan "$out/scan.json" --out "$out/calibrated.json"
./build/tools/ctk reconstruct --scan "$out/scan.json" --geometry "$out/calibrated.json" --out "$out/volume.nrrd" \
  --lambda 5 --regulariser gradient
