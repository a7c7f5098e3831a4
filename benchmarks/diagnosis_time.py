#!/usr/bin/env python3
"""What a change to the diagnosis costs, paired: two builds diagnose the same calibrated scans in turns, and the
wall time of each `ctk diagnose` run is compared (median over the rounds, and the ratio new / old of the medians).
The scans' reports must agree on what was accepted, which the script checks.

  diagnosis_time.py --old OLD/ctk --new NEW/ctk --scan S/scan.json --geometry S/geometry.json [...] [--rounds 3] [--json F]
"""
import argparse
import json
import pathlib
import platform
import statistics
import subprocess
import sys
import tempfile
import time


def cpu_name():
    for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
        if line.startswith("model name"):
            return line.split(":", 1)[1].strip()
    return platform.processor()


def diagnose(ctk, scan, geometry, out):
    start = time.perf_counter()
    subprocess.run([ctk, "diagnose", "--scan", scan, "--geometry", geometry, "--out", out], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    seconds = time.perf_counter() - start
    accepted = [e["name"] for e in json.loads(pathlib.Path(out).read_text())["effects"] if e["accepted"]]
    return seconds, accepted


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--old", required=True)
    p.add_argument("--new", required=True)
    p.add_argument("--scan", action="append", required=True)
    p.add_argument("--geometry", action="append", required=True)
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--json")
    a = p.parse_args()
    if len(a.scan) != len(a.geometry):
        sys.exit("diagnosis_time: one --geometry per --scan")
    cases = []
    with tempfile.TemporaryDirectory() as work:
        for scan, geometry in zip(a.scan, a.geometry):
            times = {"old": [], "new": []}
            accepted = {}
            for r in range(a.rounds):
                for which in (("old", "new") if r % 2 == 0 else ("new", "old")):
                    seconds, accepted[which] = diagnose(getattr(a, which), scan, geometry, f"{work}/{which}.json")
                    times[which].append(seconds)
            case = {"scan": scan, "old_s": times["old"], "new_s": times["new"],
                    "new_over_old": statistics.median(times["new"]) / statistics.median(times["old"]),
                    "accepted_old": accepted["old"], "accepted_new": accepted["new"]}
            print(json.dumps(case))
            cases.append(case)
    result = {"cpu": cpu_name(), "rounds": a.rounds, "old": a.old, "new": a.new, "cases": cases,
              "command": " ".join(sys.argv)}
    if a.json:
        pathlib.Path(a.json).write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
