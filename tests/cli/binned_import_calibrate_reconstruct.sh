#!/bin/sh
# Binning: an NXtomo scan imported with --bin 2 reconstructs its balls where the vendor put them,
# and a simulated 720 x 720 scan binned by calibrate gives matrices for the binned pixels (within
# 0.1 binned px of the binned truth) that reconstruct with --bin 2 takes.
# Usage: binned_import_calibrate_reconstruct.sh CTK WRITE_VENDOR_SCANS
set -eu
ctk=$1
vendor=$2
rm -rf cli-bin
"$vendor" write cli-bin
"$ctk" import nxtomo --nexus cli-bin/nxtomo/scan.nx --out cli-bin/nx.json --bin 2
"$ctk" reconstruct --scan cli-bin/nx.json --out cli-bin/nx.nrrd --method fdk --size 64 --voxel 0.6
"$vendor" check cli-bin/nx.nrrd nxtomo
"$ctk" simulate --out cli-bin/sim --views 12 --cols 720 --rows 720 --pitch 0.6
"$ctk" calibrate --scan cli-bin/sim/scan.json --bin 2 --out cli-bin/cal.json
python3 - <<'PY'
import json
c = json.load(open("cli-bin/cal.json"))
t = json.load(open("cli-bin/sim/truth-geometry.json"))
assert c["detector"]["cols"] == 360 and abs(c["detector"]["pixel_pitch_mm"][0] - 1.2) < 1e-12, c["detector"]


def project(P, X):
    return [sum(P[4 * r + k] * X[k] for k in range(3)) + P[4 * r + 3] for r in range(3)]


# A binned pixel's centre is at (full - 0.5) / 2.
d = [max(abs(a[i] / a[2] - ((b[i] / b[2]) - 0.5) / 2) for i in (0, 1))
     for cv, tv in zip(c["views"], t["views"]) for X in ((20, 0, -30), (-20, 15, 10), (0, -25, 35))
     for a, b in [(project(cv["P"], X), project(tv["P"], X))]]
print("largest difference from the binned truth %.3f px" % max(d))
assert max(d) < 0.1
PY
"$ctk" reconstruct --scan cli-bin/sim/scan.json --bin 2 --geometry cli-bin/sim/truth-geometry.json --out cli-bin/v.nrrd --size 48 \
  --iterations 2
