#!/usr/bin/env python3
"""Two builds of `ctk` compared on the projector benchmark: do they compute the same, and is
the new one faster? Python's standard library only.

On a shared machine whole runs drift by 15-25 % within minutes (`ctk bench --repeat N` keeps
every run and shows it), more than most single changes gain, so comparing one run of each build says little. Here
the builds take turns run by run, in the order old, new, new, old, old, new, ... (a drift that
is steady over a few runs then favours neither), and each round gives a paired ratio
old seconds / new seconds per case. The median of those ratios is the verdict; the spread
shows how much to trust it.

Before timing, each build writes `ctk bench --dump` on the same problem; their forward (A x)
and back (A' y) arrays are compared byte for byte, and where they differ the largest
|new - old| / max|old| is printed.

Usage: benchmarks/paired.py --old OLD/ctk --new NEW/ctk [--rounds 6] [--views 120] [--scale 1]
                            [--old-simd TARGET] [--new-simd TARGET] [--json]
(One binary twice with two SIMD targets compares the targets.)
Exits 1 when an array differs (the builds do not compute the same), 0 otherwise.
"""
import argparse
import json
import os
import statistics
import sys
import tempfile

from yardstick import load, measurements, run_bench  # the same script folder


def bench(ctk, simd, args, extra):
    """The report of one `ctk bench` run (its reference on one view: only the fast times count)."""
    return run_bench(ctk, args, 1, ["--views", str(args.views)] + (["--simd", simd] if simd else []) + extra)[1]


def fast_seconds(report):
    return {f"{t} {d}": s["fast_seconds"] for t, d, s in measurements(report)}


def compare_dumps(old_dir, new_dir, cases):
    """{'circular forward': None (bitwise the same) or the largest relative difference, ...}"""
    result = {}
    for name in cases:
        trajectory, direction = name.split()
        file = os.path.join(trajectory, f"{direction}.raw")
        with open(os.path.join(old_dir, file), "rb") as a, open(os.path.join(new_dir, file), "rb") as b:
            if a.read() == b.read():
                result[name] = None
                continue
        count = os.path.getsize(os.path.join(old_dir, file)) // 4
        old, new = load(old_dir, file, count), load(new_dir, file, count)
        scale = max((abs(v) for v in old), default=0.0) or 1.0
        result[name] = max(abs(p - q) for p, q in zip(new, old)) / scale
    return result


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--old", required=True, help="the ctk binary to compare against")
    parser.add_argument("--new", required=True, help="the ctk binary under test")
    parser.add_argument("--rounds", type=int, default=6, help="runs of each build")
    parser.add_argument("--views", type=int, default=120, help="views per run (short runs pair more closely)")
    parser.add_argument("--scale", type=int, default=1, help="divides the standard problem's sizes")
    parser.add_argument("--old-simd", default="", help="the old build's SIMD target (ctk bench --simd); widest by default")
    parser.add_argument("--new-simd", default="", help="the new build's SIMD target")
    parser.add_argument("--json", action="store_true", help="print the verdict as JSON")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be at least 1")

    with tempfile.TemporaryDirectory() as tmp:
        dumps = {label: os.path.join(tmp, label) for label in ("old", "new")}
        bench(args.old, args.old_simd, args, ["--dump", dumps["old"]])
        report = bench(args.new, args.new_simd, args, ["--dump", dumps["new"]])
        cases = list(fast_seconds(report))
        differences = compare_dumps(dumps["old"], dumps["new"], cases)

    seconds = {"old": [], "new": []}
    for r in range(args.rounds):
        order = ("old", "new") if r % 2 == 0 else ("new", "old")
        for label in order:
            seconds[label].append(fast_seconds(bench(getattr(args, label), getattr(args, f"{label}_simd"), args, [])))
            print(f"round {r + 1}/{args.rounds}: {label} done", file=sys.stderr, flush=True)

    verdict = {"rounds": args.rounds, "views": args.views, "scale": args.scale, "cases": {}}
    for name in cases:
        old = [run[name] for run in seconds["old"]]
        new = [run[name] for run in seconds["new"]]
        ratios = [o / n for o, n in zip(old, new)]
        verdict["cases"][name] = {
            "old_seconds": old, "new_seconds": new,
            "ratio_median": statistics.median(ratios), "ratio_min": min(ratios), "ratio_max": max(ratios),
            "rounds_new_faster": sum(ratio > 1 for ratio in ratios),
            "bitwise_same": differences[name] is None,
            "max_relative_difference": differences[name] or 0.0,
        }
    if args.json:
        print(json.dumps(verdict, indent=1))
    else:
        print(f"old / new fast seconds, {args.rounds} rounds of {args.views} views (scale {args.scale}):")
        for name, c in verdict["cases"].items():
            same = "bitwise same" if c["bitwise_same"] else f"DIFFERENT (max {c['max_relative_difference']:.2e})"
            print(f"  {name:18s} median {c['ratio_median']:.3f} [{c['ratio_min']:.3f} .. {c['ratio_max']:.3f}], "
                  f"new faster in {c['rounds_new_faster']}/{args.rounds}; results {same}")
    return 0 if all(c["bitwise_same"] for c in verdict["cases"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())
