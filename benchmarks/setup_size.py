#!/usr/bin/env python3
"""What scripts/setup.sh installed on a fresh machine, per package set, measured from dpkg's records.

Run after `scripts/setup.sh --tests` on a fresh Debian machine:
    /usr/bin/python3 benchmarks/setup_size.py --since 2026-12-07
It takes the packages dpkg installed on or after that day, follows the Depends and Pre-Depends of
each set's packages through what is installed (an alternative counts as the one installed), and sums
their Installed-Size. Each set's figure is what setup.sh installs for it alone; the two sets' union
must account for everything installed since the day, which the script checks.
"""
import argparse
import json
import pathlib
import re
import subprocess
import sys


def installed_since(day: str) -> set[str]:
    names = set()
    for line in pathlib.Path("/var/log/dpkg.log").read_text().splitlines():
        fields = line.split()
        if len(fields) > 3 and fields[2] == "install" and fields[0] >= day:
            names.add(fields[3].split(":")[0])
    return names


def package_table():
    out = subprocess.run(["dpkg-query", "-W", "-f", "${Package}\t${Installed-Size}\t${Depends}, ${Pre-Depends}\t${Provides}\n"],
                         capture_output=True, text=True, check=True).stdout
    sizes, depends, provided_by = {}, {}, {}
    for line in out.splitlines():
        name, size, deps, provides = line.split("\t")
        sizes[name] = int(size or 0)
        depends[name] = [d for d in deps.split(",") if d.strip()]
        for p in provides.split(","):
            p = p.strip().split(" ")[0]
            if p:
                provided_by.setdefault(p, name)
    return sizes, depends, provided_by


def closure(roots, depends, provided_by):
    def installed_choice(alternatives: str):
        for a in alternatives.split("|"):
            name = a.strip().split(" ")[0].split(":")[0]
            if name in depends:
                return name
            if name in provided_by:
                return provided_by[name]
        return None

    seen, stack = set(), list(roots)
    while stack:
        p = stack.pop()
        if p in seen or p not in depends:
            continue
        seen.add(p)
        stack.extend(c for c in map(installed_choice, depends[p]) if c)
    return seen


def setup_sets(setup: pathlib.Path):
    text = setup.read_text()

    def array(name):
        body = re.search(name + r"=\((.*?)\n\)", text, re.S).group(1)
        return [w for line in body.splitlines() for w in line.split("#")[0].split()]

    return array("run_packages"), array("test_packages")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--since", required=True, help="the day setup.sh ran (YYYY-MM-DD, as dpkg.log writes it)")
    parser.add_argument("--setup", default=str(pathlib.Path(__file__).resolve().parent.parent / "scripts" / "setup.sh"))
    args = parser.parse_args()
    new = installed_since(args.since)
    if not new:
        sys.exit(f"setup_size: dpkg installed nothing on or after {args.since}")
    sizes, depends, provided_by = package_table()
    run, tests = setup_sets(pathlib.Path(args.setup))
    result = {"since": args.since, "installed": len(new), "installed_gib": round(sum(sizes.get(p, 0) for p in new) / 2**20, 3)}
    for label, roots in (("run", run), ("run_and_tests", run + tests)):
        pulled = closure(roots, depends, provided_by) & new
        result[label] = {"packages": len(pulled), "gib": round(sum(sizes[p] for p in pulled) / 2**20, 3)}
    unexplained = sorted(new - closure(run + tests, depends, provided_by))
    result["installed_by_something_else"] = unexplained
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
