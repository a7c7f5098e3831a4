#!/usr/bin/env python3
"""RTK's geometry XML through the command line as a user would use it: a simulated robot scan's
true geometry leaves with `ctk geometry --geometry ... --rtk`, comes back with `ctk import rtk`
(the detector's size read from the first projection), and every view must project points of the
holder where the true matrix does, to 1e-6 px; a damaged file is refused naming it, exit 2, with
nothing written.  Usage: rtk_geometry_round_trip.py CTK"""
import argparse
import json
import pathlib
import shutil
import subprocess
import sys

from failures import report


def project(P, X):
    h = [sum(P[4 * r + c] * X[c] for c in range(3)) + P[4 * r + 3] for r in range(3)]
    return h[0] / h[2], h[1] / h[2]


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("ctk")
    a = parser.parse_args()
    work = pathlib.Path("rtk-geometry-round-trip")
    shutil.rmtree(work, ignore_errors=True)
    run = lambda *args: subprocess.run([a.ctk, *map(str, args)], capture_output=True, text=True)
    failures = []
    sim = work / "sim"
    r = run("simulate", "--out", sim, "--trajectory", "cap", "--views", "10", "--cols", "96", "--rows", "80", "--pitch", "4.5",
            "--phantom", "helix-holder")
    if r.returncode:
        return report([f"simulate: {r.stderr}"])
    r = run("geometry", "--scan", sim / "scan.json", "--geometry", sim / "truth-geometry.json", "--out", work / "g.json",
            "--rtk", work / "g.xml")
    if r.returncode or "RTK geometry of the 10 posed views" not in r.stdout:
        failures.append(f"geometry --rtk: exit {r.returncode}, {r.stdout} {r.stderr}")
    scan = json.loads((sim / "scan.json").read_text())
    p = scan["projections"]
    frames = lambda key: [sim / f for f in ([p[key]] if isinstance(p[key], str) else p[key])]
    imported = work / "imported" / "scan.json"
    imported.parent.mkdir(parents=True)
    r = run("import", "rtk", "--out", imported, "--geometry", work / "g.xml", "--files", sim / p["files"], "--count", p["count"],
            "--pitch", scan["detector"]["pixel_pitch_mm"][0], "--flat", *frames("flat"), "--dark",
            *frames("dark"))
    if r.returncode or "detector 96 x 80 px" not in r.stdout:
        return report(failures + [f"import rtk: exit {r.returncode}, {r.stdout} {r.stderr}"])
    truth = {v["index"]: v["P"] for v in json.loads((sim / "truth-geometry.json").read_text())["views"] if v.get("P")}
    back = {v["index"]: v["P"] for v in json.loads((imported.parent / "scan.matrices.json").read_text())["views"]}
    spheres = json.loads((sim / "truth.json").read_text())["holder_spheres_mm"]
    worst = max(max(abs(x - y) for x, y in zip(project(back[i], X), project(P, X))) for i, P in truth.items() for X in spheres)
    print(f"{len(truth)} views, largest difference {worst:.2e} px")
    if len(back) != len(truth) or worst > 1e-6:
        failures.append(f"{len(back)} views back of {len(truth)}, largest difference {worst} px")
    # A joint-7 orbit turns the holder about its own z: exported, that axis is RTK's y, about which
    # rtkfdk reconstructs, so every view has the same out-of-plane and in-plane angles and only the
    # gantry angle turns, in equal steps through joint 7's 332 degrees.
    orbit = work / "orbit"
    r = run("simulate", "--out", orbit, "--trajectory", "circular", "--views", "8", "--cols", "96", "--rows", "80", "--pitch",
            "4.5", "--phantom", "helix-holder", "--robot-noise-mm", "0", "--robot-noise-deg", "0")
    r = r.returncode or run("geometry", "--scan", orbit / "scan.json", "--geometry", orbit / "truth-geometry.json", "--out",
                            work / "orbit.json", "--rtk", work / "orbit.xml").returncode
    if r:
        failures.append("the orbit's export failed")
    else:
        import xml.etree.ElementTree as ET
        root = ET.parse(work / "orbit.xml").getroot()
        fixed = {e.tag: float(e.text) for e in root if e.tag != "Projection"}
        per_view = [{e.tag: float(e.text) for e in proj if e.tag != "Matrix"} for proj in root.iter("Projection")]
        angle = lambda tag: [v.get(tag, fixed.get(tag, 0.0)) for v in per_view]
        gantry = sorted(angle("GantryAngle"))
        steps = [b - a for a, b in zip(gantry, gantry[1:])]  # joint 7 turns through 332 degrees in equal steps
        for tag in ("OutOfPlaneAngle", "InPlaneAngle"):
            values = angle(tag)
            if max(values) - min(values) > 1e-9 or (tag == "OutOfPlaneAngle" and abs(values[0]) > 1e-9):
                failures.append(f"orbit exported with {tag} {values}: its axis is not RTK's y")
        if max(steps) - min(steps) > 1e-6 or not 300 < sum(steps) < 360:
            failures.append(f"orbit's gantry angles {gantry}: expected 7 equal steps through joint 7's range (about 332 degrees)")
    # A damaged file: named, exit 2, nothing written.
    damaged = work / "damaged.xml"
    damaged.write_text((work / "g.xml").read_text().replace("<GantryAngle>", "<GantryAngle>x", 1))
    out = work / "refused" / "scan.json"
    out.parent.mkdir()
    r = run("import", "rtk", "--out", out, "--geometry", damaged, "--files", sim / p["files"], "--count", p["count"], "--pitch",
            "4.5", "--kind", "line_integrals")
    if r.returncode != 2 or str(damaged) not in r.stderr or "Projection[0].GantryAngle" not in r.stderr or any(out.parent.iterdir()):
        failures.append(f"damaged file: exit {r.returncode}, {r.stderr}, wrote {list(out.parent.iterdir())}")
    return report(failures)


if __name__ == "__main__":
    sys.exit(main())
