"""A joint-7 orbit scanned with a polychromatic beam (94 kV) and no effect: the spheres' contrast
falls with the wall behind them, which leans their centres along the wall's silhouette; measured
by calibrate and modelled, the diagnosis accepts nothing (without it: a radial distortion at
t = 12.9). The same scan with a monochromatic beam measures no contrast loss and uses none.
Usage: polychromatic_orbit.py CTK"""

import json
import subprocess
import sys

ctk = sys.argv[1]
base = ["--phantom", "helix-holder", "--cols", "720", "--rows", "720", "--pitch", "0.6", "--trajectory", "circular",
        "--views", "60", "--robot-noise-mm", "0.05", "--robot-noise-deg", "0.01", "--seed", "5001"]
quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
ok = True
for name, extra in (("poly", ["--kvp", "94", "--filter-al-mm", "1"]), ("mono", [])):
    subprocess.run([ctk, "simulate", "--out", f"orbit-{name}", *base, *extra], check=True, **quiet)
    subprocess.run([ctk, "calibrate", "--scan", f"orbit-{name}/scan.json", "--out", f"orbit-{name}/cal.json"], check=True, **quiet)
    contrast = json.load(open(f"orbit-{name}/cal.report.json"))["summary"]["ball_contrast"]
    print(name, contrast)
    if name == "mono":
        ok &= contrast["used"] == 0
        continue
    ok &= contrast["used"] > 0.1 and contrast["hardening_per_line_integral"] > 10 * contrast["sigma"]
    subprocess.run([ctk, "diagnose", "--scan", f"orbit-{name}/scan.json", "--geometry", f"orbit-{name}/cal.json", "--out",
                    f"orbit-{name}/diagnosis.json"], check=True, **quiet)
    accepted = [e["name"] for e in json.load(open(f"orbit-{name}/diagnosis.json"))["effects"] if e["accepted"]]
    print("accepted:", accepted)
    ok &= accepted == []
sys.exit(0 if ok else 1)
