"""A polychromatic beam behind the holder's wall, nothing else undeclared: on a joint-7 orbit the
wall's silhouette stays on the same detector columns, and the balls' contrast falling where the
wall is thicker pulled their centres like a radial distortion (distortion accepted at t = 12.9).
The calibration must measure the contrast loss (between 0.15 and 0.45 per unit line integral at
94 kV behind 1 mm of aluminium), calibrate every view within 0.01 px of the true matrices, and the
diagnosis accept nothing.  Usage: polychromatic_orbit.py CTK SOURCE_DIR"""
import json
import shutil
import subprocess
import sys
from pathlib import Path

ctk, source = sys.argv[1], Path(sys.argv[2])
sys.path.insert(0, str(source / "benchmarks"))
from diagnosis_population import calibration_figures  # noqa: E402

out = Path("polychromatic-orbit")
shutil.rmtree(out, ignore_errors=True)
run = lambda args: subprocess.run([ctk] + args, check=True, stdout=subprocess.DEVNULL)
run(["simulate", "--out", str(out), "--phantom", "helix-holder", "--cols", "720", "--rows", "720", "--pitch", "0.6",
     "--trajectory", "circular", "--views", "40", "--robot-noise-mm", "0.05", "--robot-noise-deg", "0.01", "--seed", "5001",
     "--kvp", "94", "--filter-al-mm", "1"])
run(["calibrate", "--scan", str(out / "scan.json"), "--out", str(out / "geometry.json")])
run(["diagnose", "--scan", str(out / "scan.json"), "--geometry", str(out / "geometry.json"), "--out", str(out / "d.json")])
failures = []
loss = json.loads((out / "geometry.report.json").read_text()).get("contrast_loss", {"used": False, "rate_per_line_integral": 0, "sigma": 0})
if not (loss["used"] and 0.15 < loss["rate_per_line_integral"] < 0.45):
    failures.append(f"contrast loss {loss['rate_per_line_integral']:.3f} (used: {loss['used']}), expected 0.15-0.45, used")
figures = calibration_figures(out, "geometry.json", 720)
if figures["calibrated"] != figures["eligible"] or not figures["median_difference_px"] < 0.01:
    failures.append(f"{figures['calibrated']} of {figures['eligible']} views calibrated, median "
                    f"{figures['median_difference_px']:.4f} px from the truth (expected all, under 0.01 px)")
report = json.loads((out / "d.json").read_text())
accepted = [e["name"] for e in report["effects"] if e["accepted"]]
if accepted:
    failures.append(f"the diagnosis accepted {accepted} on a scan with no undeclared effect")
for f in failures:
    print("FAIL:", f)
print(f"contrast loss {loss['rate_per_line_integral']:.3f} +- {loss['sigma']:.3f}; median "
      f"{figures['median_difference_px']:.4f} px from the truth; accepted {accepted}")
sys.exit(1 if failures else 0)
