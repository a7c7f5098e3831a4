#!/usr/bin/env python3
"""clang-tidy with the repository's .clang-tidy over every product source in a build's
compile_commands.json (libraries, phantoms, tools, Python binding; tests and benchmarks are not
product). Prints each finding and exits 1 when there is any.
Usage: check_tidy.py BUILD_DIR [--jobs N] [--under libcore libgeom ...]"""
import argparse
import concurrent.futures
import json
import os
import pathlib
import re
import shutil
import subprocess
import sys

PRODUCT = ("libcore", "libgeom", "libproj", "librecon", "libcalib", "libplan", "phantoms", "tools", "python")


def main():
    p = argparse.ArgumentParser()
    p.add_argument("build")
    p.add_argument("--jobs", type=int, default=os.cpu_count())
    p.add_argument("--clang-tidy", default=shutil.which("clang-tidy") or "clang-tidy")
    p.add_argument("--under", nargs="*", default=PRODUCT, help="only these top-level folders (default: every product folder)")
    a = p.parse_args()
    root = pathlib.Path(__file__).resolve().parents[2]
    commands = json.loads((pathlib.Path(a.build) / "compile_commands.json").read_text())
    files = sorted({c["file"] for c in commands
                    if pathlib.Path(c["file"]).resolve().is_relative_to(root)
                    and pathlib.Path(c["file"]).resolve().relative_to(root).parts[0] in a.under})
    if not files:
        print(f"no product sources in {a.build}/compile_commands.json")
        return 1

    def tidy(path):
        r = subprocess.run([a.clang_tidy, "-p", a.build, "--quiet", path], capture_output=True, text=True)
        findings = [line for line in r.stdout.splitlines() if re.search(r": (warning|error): ", line)]
        return path, findings, r.stdout if findings else ""

    failed = 0
    seen = set()
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        for path, findings, text in pool.map(tidy, files):
            new = [f for f in findings if f not in seen]  # a header's finding is reported once
            seen.update(findings)
            if new:
                failed += 1
                print(text)
    print(f"clang-tidy: {len(files)} sources, {len(seen)} findings")
    return 1 if seen else 0


if __name__ == "__main__":
    sys.exit(main())
