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
# Reconstruct with the geometry the robot predicts (calibration from the spheres comes next and
# will replace it); the truth the simulator kept is in $out/truth-geometry.json for comparison.
./build/tools/ctk reconstruct --scan "$out/scan.json" --geometry "$out/geometry.json" --out "$out/volume.nrrd" \
  --lambda 5 --regulariser gradient
