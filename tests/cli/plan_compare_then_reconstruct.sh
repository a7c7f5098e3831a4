#!/bin/sh
# The planner against a whole-sphere and random draws (--compare), its pictures and JSON, the
# comparison again from what is on disk (--compare-only), and a drawn trajectory reconstructed.
# Usage: plan_compare_then_reconstruct.sh CTK
set -eu
ctk=$1
rm -rf cli-plan
"$ctk" plan --out cli-plan --phantom sample-2 --views 16 --scout-nside 1 --cols 360 --rows 360 --pitch 1.2 --coarse-size 48 \
  --coarse-voxel 2 --binning 2 --compare --random-draws 2 --eval-voxel 1.2 --eval-iterations 4
test -s cli-plan/planned/plan-map.png
test -s cli-plan/comparison.png
for key in rmse_per_mm rmse_outside_absorbers_per_mm draws_better_than_planned flat_counts; do
  grep -q "$key" cli-plan/comparison.json
done
tr -d ' \n' < cli-plan/comparison.json | grep -q 'size.:.50,50,100.'
grep -q ctk-plan/1 cli-plan/planned/trajectory.json
grep -q edge_tangency_weight cli-plan/planned/trajectory.json
"$ctk" plan --out cli-plan --phantom sample-2 --compare-only --random-draws 2 --eval-voxel 1.2 --eval-iterations 4
grep -q rmse_per_mm cli-plan/comparison.json
if grep -q flat_counts cli-plan/comparison.json; then
  echo "FAIL: the --compare-only comparison has flat_counts, which only a run that simulates writes"
  exit 1
fi
"$ctk" reconstruct --scan cli-plan/random/scan.json --geometry cli-plan/random/geometry.json --out cli-plan/r.nrrd --size 48 \
  --voxel 1.5 --iterations 2
