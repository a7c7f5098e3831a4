"""The README's example diagnosed exactly: scripts/example_run.sh up to the diagnosis (a robot base
1.3 mm off along z, nothing else), then the report must accept robot_base_frame alone, list what it
is confounded with on this trajectory, recover the offset within its stated uncertainty, and show
for every effect the threshold it had to pass.  Usage: example_diagnosis.py CTK SOURCE_DIR"""
import json
import subprocess
import sys
from pathlib import Path

ctk, source = sys.argv[1], Path(sys.argv[2])
out = Path("example-diagnosis")
subprocess.run(["bash", str(source / "scripts" / "example_run.sh"), ctk, str(out), "--until", "diagnose"], check=True,
               stdout=subprocess.DEVNULL)
report = json.loads((out / "diagnosis.json").read_text())
accepted = [e for e in report["effects"] if e["accepted"]]
failures = []
if [e["name"] for e in accepted] != ["robot_base_frame"]:
    failures.append(f"accepted {[e['name'] for e in accepted]}, expected ['robot_base_frame'] alone")
else:
    base = accepted[0]
    for name in ("holder_mount", "joint_offsets"):
        if name not in base["confounded_with"]:
            failures.append(f"robot_base_frame's confounded_with {base['confounded_with']} lacks {name}")
    # The base offset the simulator applied, in the base frame: (0, 0, 1.3) mm.
    for axis, truth in enumerate((0.0, 0.0, 1.3)):
        value, sigma = base["parameters"]["translation_mm"][axis], base["uncertainty"]["translation_mm"][axis]
        if abs(value - truth) > max(4 * sigma, 0.02):
            failures.append(f"base translation[{axis}] = {value:.4f} +- {sigma:.4f} mm, truth {truth}")
    if not base["fk_translation_rms_mm_after"] < 0.1:
        failures.append(f"robot prediction error after {base['fk_translation_rms_mm_after']} mm, expected < 0.1")
for e in report["effects"]:
    if not e.get("threshold_z", 0) > 0:
        failures.append(f"{e['name']}: no threshold_z in the report")
    elif e["accepted"] and not e["heldout_improvement_z"] > e["threshold_z"]:
        failures.append(f"{e['name']}: accepted below its threshold")
if not 0 < report.get("false_acceptance_rate", 0) < 1:
    failures.append("no false_acceptance_rate in the report")
for f in failures:
    print("FAIL:", f)
print(f"example diagnosis: {1 - bool(failures)} passed, {int(bool(failures))} failed")
sys.exit(1 if failures else 0)
