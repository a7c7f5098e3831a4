#!/bin/sh
# An interrupted reconstruction continued with --resume gives the volume of an uninterrupted run
# (to 1e-6 of its largest voxel): stopped by Ctrl-C (the state saved on the spot, exit 130) and
# killed outright (continued from the last periodic save). A state is refused, naming the option,
# by a run with other options, and removed once the run completes; the scan and geometry spelt another
# way continue it. Usage: reconstruct_resumes.sh CTK PYTHON
set -u
. "$(dirname "$0")/signals.sh"
ctk=$1
python=$2
dir=reconstruct-resumes
rm -rf "$dir" && mkdir -p "$dir" && cd "$dir" || exit 1
failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
"$ctk" simulate --out s --views 30 --cols 128 --rows 128 --pitch 3.4 --phantom helix-holder --phantom sample-1 >/dev/null 2>&1 ||
  { echo "simulate failed"; exit 1; }
recon="$ctk reconstruct --scan s/scan.json --geometry s/truth-geometry.json --size 96"  # no spaces in these paths
# The same scan spelt another way (a symbolic link, "..") is the same scan to --resume.
ln -s s s-link
respelt="$ctk reconstruct --scan ./s-link/scan.json --geometry s-link/../s/truth-geometry.json --size 96"


same_volume() {
  "$python" - "$1" "$2" <<'EOF'
import array, sys
def voxels(name):
    data = open(name, "rb").read()
    a = array.array("f")
    a.frombytes(data[data.index(b"\n\n") + 2:])
    return a
a, b = voxels(sys.argv[1]), voxels(sys.argv[2])
peak = max(abs(v) for v in a)
worst = max(abs(u - v) for u, v in zip(a, b)) / peak if len(a) == len(b) else float("inf")
print(f"{sys.argv[2]}: largest difference {worst:.2e} of the largest voxel")
sys.exit(0 if worst <= 1e-6 else 1)
EOF
}

for method in wls-cg sirt; do
  $recon --method $method --iterations 30 --out whole-$method.nrrd >/dev/null 2>&1 || fail "$method: the uninterrupted run failed"

  signal_when int-$method.log "$method: [1-9][0-9]* / " INT $recon --method $method --iterations 30 --out int-$method.nrrd
  [ "$code" -eq 130 ] || fail "$method: Ctrl-C gave exit $code, expected 130: $(tail -n 1 int-$method.log)"
  grep -q "run the same command with --resume" int-$method.log || fail "$method: Ctrl-C did not say how to continue"
  [ -e int-$method.nrrd ] && fail "$method: an interrupted run published a volume"
  $recon --method $method --iterations 30 --out int-$method.nrrd --resume > int-$method.resumed.log 2>&1 ||
    fail "$method: --resume failed: $(tail -n 1 int-$method.resumed.log)"
  grep -q "continuing $method after iteration" int-$method.resumed.log || fail "$method: the continued run did not say so"
  same_volume whole-$method.nrrd int-$method.nrrd || fail "$method: continued after Ctrl-C, not the uninterrupted volume"
  [ -e int-$method.state ] && fail "$method: the state outlived the completed run"

  signal_when kill-$method.log "$method: 1[2-9] / " KILL $recon --method $method --iterations 30 --out kill-$method.nrrd --checkpoint-every 5
  [ -s kill-$method.state ] || fail "$method: no periodic state after a kill"
  $recon --method $method --iterations 30 --out kill-$method.nrrd --lambda 0.5 --resume > refused-$method.log 2>&1
  code=$?
  { [ "$code" -eq 2 ] && grep -q "kill-$method.state: key 'run.lambda'" refused-$method.log; } ||
    fail "$method: a state continued by a run with another --lambda: exit $code, $(tail -n 1 refused-$method.log)"
  $respelt --method $method --iterations 30 --out kill-$method.nrrd --checkpoint-every 5 --resume > kill-$method.resumed.log 2>&1 ||
    fail "$method: --resume after a kill failed: $(tail -n 1 kill-$method.resumed.log)"
  grep -q "continuing $method after iteration 10" kill-$method.resumed.log || fail "$method: not continued from the last save (10)"
  same_volume whole-$method.nrrd kill-$method.nrrd || fail "$method: continued after a kill, not the uninterrupted volume"
done
echo "$failures failed"
[ "$failures" -eq 0 ]
