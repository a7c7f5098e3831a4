#!/usr/bin/env python3
"""clang-tidy with the repository's .clang-tidy over the product sources in a build's
compile_commands.json (libraries, phantoms, tools, Python binding; tests and benchmarks are not
product). Prints each finding and exits 1 when there is any.

A full run over every product source takes about 14 minutes on 2 cores (clang-tidy 14 matches its
checks over every header a source includes). So the test suite checks only what changed since the
last full run without a finding: `--record FILE` makes a full run write the commit it checked into
FILE, `--since FILE` checks the sources that differ from that commit, or include a file that does
(the build's dependency files say which), and everything when the commit is not in the history.

Usage: check_tidy.py BUILD_DIR [--jobs N] [--under libcore libgeom ...] [--record FILE | --since FILE]"""
import argparse
import concurrent.futures
import datetime
import json
import os
import pathlib
import re
import shlex
import shutil
import subprocess
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "benchmarks"))
from diagnosis_population import cpu_name  # noqa: E402  (the benchmarks' one description of the CPU)

PRODUCT = ("libcore", "libgeom", "libmeasure", "libproj", "librecon", "libplan", "libcalib", "phantoms", "tools", "python")


def git(root, *args):
    r = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)
    return r.stdout if r.returncode == 0 else None


def changed_since(root, commit):
    """Repository files that differ from `commit` in the work tree (untracked ones included), or
    None when the commit is not in this clone's history."""
    if git(root, "cat-file", "-e", f"{commit}^{{commit}}") is None:
        return None
    diff = git(root, "diff", "--name-only", commit) or ""
    untracked = git(root, "ls-files", "--others", "--exclude-standard") or ""
    return {(root / line).resolve() for line in (diff + untracked).splitlines() if line}


def dependencies(build, command):
    """What one compile command's source includes, from the depfile the build wrote beside the
    object; None when there is none (then the source is always checked)."""
    args = command.get("arguments") or shlex.split(command["command"])
    output = command.get("output") or next((args[i + 1] for i in range(len(args) - 1) if args[i] == "-o"), None)
    if output is None:
        return None
    depfile = pathlib.Path(command["directory"]) / (output + ".d")
    if not depfile.is_file():
        return None
    text = depfile.read_text().replace("\\\n", " ")
    return {pathlib.Path(p).resolve() for p in text.split(":", 1)[1].split()}


def main():
    p = argparse.ArgumentParser()
    p.add_argument("build")
    p.add_argument("--jobs", type=int, default=os.cpu_count())
    p.add_argument("--clang-tidy", default=shutil.which("clang-tidy") or "clang-tidy")
    p.add_argument("--under", nargs="*", default=PRODUCT, help="only these top-level folders (default: every product folder)")
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--record", type=pathlib.Path, help="after a full run without a finding, write the commit checked here")
    mode.add_argument("--since", type=pathlib.Path, help="check only what changed since the commit this record names")
    a = p.parse_args()
    root = pathlib.Path(__file__).resolve().parents[2]
    build = pathlib.Path(a.build)
    commands = json.loads((build / "compile_commands.json").read_text())
    product = {}
    for c in commands:
        path = pathlib.Path(c["file"]).resolve()
        if path.is_relative_to(root) and path.relative_to(root).parts[0] in a.under:
            product.setdefault(str(path), c)
    if not product:
        print(f"no product sources in {build}/compile_commands.json")
        return 1

    files = sorted(product)
    if a.record:
        if set(a.under) != set(PRODUCT):
            print("--record needs the full run: leave out --under")
            return 2
        dirty = git(root, "status", "--porcelain", "--", *PRODUCT)
        if dirty is None or dirty.strip():
            print(f"--record needs product folders without uncommitted changes:\n{dirty}")
            return 2
        checked = git(root, "rev-parse", "HEAD").strip()  # what the sources are now, not when the run ends
    if a.since:
        commit = json.loads(a.since.read_text())["commit"]
        changed = changed_since(root, commit)
        if changed is None:
            print(f"commit {commit} of {a.since} is not in this history: every source is checked")
        else:
            def touched(path):
                deps = dependencies(build, product[path])
                return deps is None or pathlib.Path(path) in changed or bool(deps & changed)
            files = [f for f in files if touched(f)]
            print(f"{len(files)} of {len(product)} sources differ from {commit[:10]} or include a file that does")

    def tidy(path):
        r = subprocess.run([a.clang_tidy, "-p", str(build), "--quiet", path], capture_output=True, text=True)
        findings = [line for line in r.stdout.splitlines() if re.search(r": (warning|error): ", line)]
        return path, findings, r.stdout if findings else ""

    start = time.monotonic()
    seen = set()
    with concurrent.futures.ThreadPoolExecutor(a.jobs) as pool:
        for path, findings, text in pool.map(tidy, files):
            new = [f for f in findings if f not in seen]  # a header's finding is reported once
            seen.update(findings)
            if new:
                print(text)
    seconds = time.monotonic() - start
    print(f"clang-tidy: {len(files)} sources, {len(seen)} findings, {seconds:.0f} s on {a.jobs} jobs")
    if a.record and not seen:
        record = {"commit": checked, "sources": len(files), "findings": 0,
                  "seconds": round(seconds), "jobs": a.jobs, "cpu": cpu_name(),
                  "clang_tidy": (subprocess.run([a.clang_tidy, "--version"], capture_output=True, text=True).stdout
                                 .split("version")[1].split()[0]),
                  "date": datetime.date.today().isoformat()}
        tmp = a.record.with_suffix(".tmp")
        tmp.write_text(json.dumps(record, indent=2) + "\n")
        tmp.replace(a.record)
        print(f"recorded {record['commit'][:10]} in {a.record}")
    return 1 if seen else 0


if __name__ == "__main__":
    sys.exit(main())
