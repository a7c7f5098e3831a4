#!/usr/bin/env python3
"""Every run's HTML page renders in headless Chromium: each picture shown, the run's key numbers on
the page, the verdict (what was found, and where a run leads the next command) above the fold of a
1400 x 900 window, and the page's path printed by the command. Usage: html_reports.py <ctk> <chromium>"""
import json
import pathlib
import re
import shutil
import subprocess
import sys

ctk, chromium = sys.argv[1], sys.argv[2]
work = pathlib.Path("cli-html").absolute()
shutil.rmtree(work, ignore_errors=True)
work.mkdir()


def run(*args):
    result = subprocess.run([ctk, *map(str, args)], capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"ctk {' '.join(map(str, args))} failed:\n{result.stdout}\n{result.stderr}")
    return result.stdout


def rendered(page):
    """The page's DOM after Chromium loaded it (and its script counted the pictures)."""
    dom = subprocess.run([chromium, "--headless", "--no-sandbox", "--disable-gpu", "--virtual-time-budget=10000",
                          "--window-size=1400,900", "--dump-dom", page.as_uri()], capture_output=True, text=True, timeout=120)
    if dom.returncode != 0 or "<html" not in dom.stdout:
        sys.exit(f"chromium could not render {page}:\n{dom.stderr[-2000:]}")
    return dom.stdout


def check(page, expected_pictures, numbers, next_command=None, printed=None):
    dom = rendered(page)
    bottom = re.search(r'data-verdict-bottom="(\d+)"', dom)
    if not bottom or int(bottom.group(1)) > 900:
        sys.exit(f"{page.name}: the verdict is not above the fold of a 1400 x 900 window ({bottom and bottom.group(1)} px)")
    if next_command and f"next: <code>{next_command}" not in dom:
        sys.exit(f"{page.name}: no 'next: {next_command}' under the verdict")
    if printed is not None and f"report page: {page}" not in printed:
        sys.exit(f"{page.name}: the command did not print the page's path")
    missing = re.search(r'data-pictures-missing="(\d+)"', dom)
    shown = re.search(r'id="pictures-shown">(\d+) of (\d+)<', dom)
    if not missing or not shown:
        sys.exit(f"{page.name}: the page's picture count did not run")
    if missing.group(1) != "0" or int(shown.group(2)) != expected_pictures:
        sys.exit(f"{page.name}: {shown.group(1)} of {shown.group(2)} pictures shown, expected {expected_pictures}")
    for n in numbers:
        if n not in dom:
            sys.exit(f"{page.name}: '{n}' is not on the page")
    print(f"{page.name}: renders, {shown.group(1)} of {shown.group(2)} pictures shown, {len(numbers)} numbers found")


scan = work / "sim" / "scan.json"
run("simulate", "--out", work / "sim", "--views", 24, "--cols", 360, "--rows", 360, "--pitch", 1.2)
said = run("calibrate", "--scan", scan, "--out", work / "cal.json")
report = json.loads((work / "cal.report.json").read_text())
check(work / "cal.report.html", len(report["pictures"]),
      ["ctk calibrate", "calibrated 24 of 24 views", "median_rms_px", "%.3g" % report["summary"]["median_rms_px"]],
      next_command="ctk diagnose --scan", printed=said)

run("reconstruct", "--scan", scan, "--geometry", work / "cal.json", "--out", work / "v.nrrd", "--size", 48, "--iterations", 2)
log = json.loads((work / "v.log.json").read_text())
check(work / "v.report.html", 4, ["ctk reconstruct", "epoch limit (2) reached", "stop_reason", "ctk_version", "convergence"])

said = run("diagnose", "--scan", scan, "--geometry", work / "cal.json", "--out", work / "d.json")
diagnosis = json.loads((work / "d.json").read_text())
check(work / "d.html", len(diagnosis["pictures"]), ["ctk diagnose", "effects", "unexplained"], next_command="ctk ", printed=said)

small = work / "small" / "scan.json"
run("simulate", "--out", work / "small", "--views", 36, "--cols", 64, "--rows", 64, "--pitch", 6.75, "--output",
    "line-integrals")
run("refine", "--scan", small, "--out", work / "r.json", "--effects", "detector_offset")
check(work / "r.html", 4, ["ctk refine", "markerless", "detector_offset"])

run("plan", "--out", work / "plan", "--phantom", "sample-2", "--views", 8, "--scout-nside", 1, "--cols", 180, "--rows",
    180, "--pitch", 2.4, "--coarse-size", 32, "--coarse-voxel", 3)
check(work / "plan" / "planned" / "plan.html", 1, ["ctk plan", "views calibrated", "ctk-plan/1"])
