#!/usr/bin/env python3
"""Two builds of `ctk` compared on one reconstruction: is the new one faster per iteration, and
how far apart are their volumes? Python's standard library only (numpy too for the volumes, if
found).

The builds take turns, old, new, new, old, ... (a drift that is steady over a few runs then
favours neither); each run's seconds per iteration (the median over its iterations, from the
reconstruction log) make one paired ratio old / new per round. The median of the ratios is the
verdict, their range how much to trust it.

Usage: benchmarks/paired_reconstruct.py --old OLD/ctk --new build/tools/ctk --scan scan.json
           [--geometry g.json] [--rounds 4] [--out F.json] -- <ctk reconstruct options>
(the old build first in even rounds, the new one in odd rounds)
e.g.   ... -- --method os-sqs --iterations 3 --subsets 24 --size 448 --voxel 0.3
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile

from diagnosis_population import cpu_name, cpu_slug  # the same script folder


def run(ctk, scan, geometry, options, out):
    command = [ctk, "reconstruct", "--scan", scan, "--out", str(out), *options]
    if geometry:
        command += ["--geometry", geometry]
    subprocess.run(command, check=True, capture_output=True)
    log = json.loads(out.with_suffix(".log.json").read_text())
    return [it["seconds"] for it in log["solver"]["iterations"] if it["iteration"] > 0]


def largest_difference(old, new):
    """max |new - old| / max |old| of two volumes, or None without numpy or ctk's module."""
    try:
        import ctk
        import numpy as np
    except ImportError:
        return None
    a, _ = ctk.read_volume(old)
    b, _ = ctk.read_volume(new)
    return float(np.abs(b - a).max() / np.abs(a).max())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--old", required=True)
    p.add_argument("--new", required=True)
    p.add_argument("--scan", required=True)
    p.add_argument("--geometry")
    p.add_argument("--rounds", type=int, default=4)
    p.add_argument("--out", help="JSON to write (default: results/paired_reconstruct-<cpu>.json beside this script)")
    p.add_argument("options", nargs=argparse.REMAINDER, help="after --: options of ctk reconstruct")
    a = p.parse_args()
    options = a.options[1:] if a.options[:1] == ["--"] else a.options
    builds = {"old": a.old, "new": a.new}
    seconds = {"old": [], "new": []}
    with tempfile.TemporaryDirectory() as work:
        volumes = {}
        for k in range(a.rounds):
            for build in (("old", "new") if k % 2 == 0 else ("new", "old")):
                out = pathlib.Path(work) / f"{build}-{k}.nrrd"
                per_iteration = run(builds[build], a.scan, a.geometry, options, out)
                seconds[build].append(statistics.median(per_iteration))
                volumes.setdefault(build, out)
                print(f"round {k + 1}/{a.rounds}: {build} {seconds[build][-1]:.3f} s per iteration", file=sys.stderr)
        difference = largest_difference(volumes["old"], volumes["new"])
    ratios = [o / n for o, n in zip(seconds["old"], seconds["new"])]
    result = {
        "benchmark": "ctk reconstruct, two builds taking turns, seconds per iteration (median over the run's iterations)",
        "options": options,
        "scan": a.scan,
        "cpu": cpu_name(),
        "old_seconds": seconds["old"],
        "new_seconds": seconds["new"],
        "ratio_median": statistics.median(ratios),
        "ratio_min": min(ratios),
        "ratio_max": max(ratios),
        "rounds_new_faster": sum(r > 1 for r in ratios),
        "max_relative_difference": difference,
    }
    print(f"old / new seconds per iteration: median {result['ratio_median']:.3f} "
          f"({result['ratio_min']:.3f}-{result['ratio_max']:.3f}), new faster in {result['rounds_new_faster']} of "
          f"{a.rounds} rounds; volumes apart by {difference} of the old's largest value")
    out = pathlib.Path(a.out) if a.out else pathlib.Path(__file__).parent / "results" / f"paired_reconstruct-{cpu_slug()}.json"
    out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"written {out}", file=sys.stderr)


if __name__ == "__main__":
    main()
