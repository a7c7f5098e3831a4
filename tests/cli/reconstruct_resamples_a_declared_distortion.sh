#!/bin/sh
# A scan declaring its detector's radial distortion is resampled onto the matrices' pinhole grid
# before it is reconstructed: simulated with k1 = 2e-5 per px^2 about (32, 32), the largest shift
# is 1.85 px at the corners. Usage: reconstruct_resamples_a_declared_distortion.sh CTK
set -eu
ctk=$1
rm -rf cli-dist
"$ctk" simulate --out cli-dist --views 4 --cols 64 --rows 64 --pitch 6.75 --output line-integrals --distortion-k1 2e-5 \
  --distortion-centre-px 32 32
python3 - <<'PY'
import json
path = "cli-dist/scan.json"
scan = json.load(open(path))
scan["detector"]["radial_distortion"] = {"k1_per_px2": 2e-5, "center_px": [32, 32]}
json.dump(scan, open(path, "w"))
PY
"$ctk" reconstruct --scan cli-dist/scan.json --geometry cli-dist/truth-geometry.json --out cli-dist/v.nrrd --size 24 --voxel 4 \
  --iterations 1
