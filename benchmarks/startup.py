#!/usr/bin/env python3
"""What a `ctk` process costs before it does anything: two builds' `ctk --version` run in turns
(old, new, new, old, ...: a drift over the run favours neither), each run's CPU time (user +
system, from the kernel's accounting of the child) and wall time; the verdict is the median of
the paired ratios old / new. Every test process and every command pays this once.

Usage: benchmarks/startup.py --old OLD/ctk --new NEW/ctk [--rounds 20] [--json FILE]"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import time

from diagnosis_population import cpu_name


def one_run(ctk):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run([ctk, "--version"], check=True, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, wall


def shared_libraries(ctk):
    out = subprocess.run(["ldd", ctk], capture_output=True, text=True).stdout
    return sum(1 for line in out.splitlines() if "=>" in line or line.strip().startswith("/"))


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--old", required=True)
    p.add_argument("--new", required=True)
    p.add_argument("--rounds", type=int, default=20)
    p.add_argument("--json")
    a = p.parse_args()
    for ctk in (a.old, a.new):
        one_run(ctk)  # the first run of each warms the page cache
    runs = {"old": [], "new": []}
    for r in range(a.rounds):
        for which in (("old", "new") if r % 2 == 0 else ("new", "old")):
            runs[which].append(one_run(a.old if which == "old" else a.new))
    cpu_ratio = [o[0] / n[0] for o, n in zip(runs["old"], runs["new"])]
    wall_ratio = [o[1] / n[1] for o, n in zip(runs["old"], runs["new"])]
    result = {
        "benchmark": "startup", "cpu": cpu_name(), "cores": os.cpu_count(), "rounds": a.rounds,
        "command": "ctk --version",
        "old": {"binary": a.old, "shared_libraries": shared_libraries(a.old),
                "cpu_seconds_median": statistics.median(c for c, _ in runs["old"]),
                "wall_seconds_median": statistics.median(w for _, w in runs["old"])},
        "new": {"binary": a.new, "shared_libraries": shared_libraries(a.new),
                "cpu_seconds_median": statistics.median(c for c, _ in runs["new"]),
                "wall_seconds_median": statistics.median(w for _, w in runs["new"])},
        "cpu_ratio_old_over_new": {"median": statistics.median(cpu_ratio), "min": min(cpu_ratio), "max": max(cpu_ratio)},
        "wall_ratio_old_over_new": {"median": statistics.median(wall_ratio), "min": min(wall_ratio), "max": max(wall_ratio)},
    }
    print(f"{a.rounds} rounds on {result['cpu']}: CPU {result['old']['cpu_seconds_median'] * 1e3:.0f} -> "
          f"{result['new']['cpu_seconds_median'] * 1e3:.0f} ms (old / new {result['cpu_ratio_old_over_new']['median']:.2f}, "
          f"{min(cpu_ratio):.2f}-{max(cpu_ratio):.2f}), wall {result['old']['wall_seconds_median'] * 1e3:.0f} -> "
          f"{result['new']['wall_seconds_median'] * 1e3:.0f} ms; {result['old']['shared_libraries']} -> "
          f"{result['new']['shared_libraries']} shared libraries")
    if a.json:
        tmp = a.json + ".tmp"
        with open(tmp, "w") as f:
            json.dump(result, f, indent=2)
            f.write("\n")
        os.replace(tmp, a.json)


if __name__ == "__main__":
    main()
