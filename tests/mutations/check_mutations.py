#!/usr/bin/python3
"""Each of the suite's longest tests still catches what it guards: a mutation of the product per
test (tests/mutations/mutations.json), built in a worktree of a commit, must make every test it
names fail. A test that passes on its mutant is reported as blind and the run exits 1.

The worktree and its build (--work) are kept between runs, so a second run builds only what the
mutations touch. Sources are restored after each mutation, whatever happens.

  /usr/bin/python3 tests/mutations/check_mutations.py --commit HEAD --work /tmp/ctk-mutants \\
      --out benchmarks/results/mutations.json
"""

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2]


def sh(command, cwd, log=None):
    with open(log, "a") if log else subprocess.DEVNULL as out:
        return subprocess.run(command, cwd=cwd, stdout=out, stderr=subprocess.STDOUT).returncode


def worktree(commit, work, jobs, log):
    tree, build = work / "tree", work / "build"
    if not tree.exists():
        subprocess.run(["git", "worktree", "add", "--detach", str(tree), commit], cwd=SOURCE, check=True)
    else:
        subprocess.run(["git", "checkout", "--detach", "--force", commit], cwd=tree, check=True)
    # The shared data the real-data tests read sits beside the source tree.
    shared = tree.parent / "shared"
    if not shared.exists():
        shared.symlink_to(SOURCE.parent / "shared")
    if not (build / "CMakeCache.txt").exists():
        if sh(["cmake", "-S", str(tree), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release", "-DCTK_BUILD_TESTS=ON",
               "-DCTK_WARNINGS_AS_ERRORS=ON"], tree, log):
            sys.exit(f"configuring the worktree failed: see {log}")
    if sh(["cmake", "--build", str(build), "-j", str(jobs)], tree, log):
        sys.exit(f"building the unmutated worktree failed: see {log}")
    return tree, build


def ctest(build, name, log):
    return sh(["ctest", "--test-dir", str(build), "-R", f"^{name}$", "--output-on-failure"], build, log)


def gtest(build, name, log):
    """A gtest case (Suite.Case) run from its suite's binary: CTest knows the binary, not the case."""
    binaries = [b for b in sorted((build / "tests").glob("test_*"))
                if b.is_file() and "." not in b.name and os.access(b, os.X_OK)]
    for binary in binaries:
        listed = subprocess.run([str(binary), "--gtest_list_tests", f"--gtest_filter={name}"], capture_output=True, text=True)
        if name.split(".")[1] in listed.stdout:
            return sh([str(binary), f"--gtest_filter={name}"], build / "test-tmp", log)
    sys.exit(f"{name}: no gtest binary lists it")


def run_test(build, name, log):
    is_gtest = "." in name and name.split(".")[0][:1].isupper()
    return gtest(build, name, log) if is_gtest else ctest(build, name, log)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--commit", default="HEAD")
    p.add_argument("--work", type=Path, default=Path("/tmp/ctk-mutants"))
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--only", help="run only the mutations whose tests include this name")
    p.add_argument("--out", type=Path)
    a = p.parse_args()
    a.work.mkdir(parents=True, exist_ok=True)
    log = a.work / "log.txt"
    commit = subprocess.run(["git", "rev-parse", a.commit], cwd=SOURCE, capture_output=True, text=True,
                            check=True).stdout.strip()
    tree, build = worktree(commit, a.work, a.jobs, log)
    mutations = json.loads((tree / "tests/mutations/mutations.json").read_text())["mutations"]
    results, blind = [], 0
    for m in mutations:
        if a.only and a.only not in m["tests"]:
            continue
        file = tree / m["file"]
        original = file.read_text()
        if original.count(m["find"]) != 1:
            sys.exit(f"{m['file']}: the text to mutate is not there exactly once: {m['find']}")
        start = time.time()
        try:
            file.write_text(original.replace(m["find"], m["replace"]))
            for target in m["targets"]:
                if sh(["cmake", "--build", str(build), "-j", str(a.jobs), "--target", target], tree, log):
                    sys.exit(f"the mutant of {m['file']} does not build ({target}): see {log}")
            outcome = {name: "fails" if run_test(build, name, log) else "PASSES" for name in m["tests"]}
        finally:
            file.write_text(original)
        blind += sum(v == "PASSES" for v in outcome.values())
        results.append({**m, "outcome": outcome, "seconds": round(time.time() - start, 1)})
        print(f"{m['file']}: {m['catches']}: " + ", ".join(f"{k} {v}" for k, v in outcome.items()), flush=True)
    for m in mutations:  # the worktree back as committed, its build too
        for target in m["targets"]:
            sh(["cmake", "--build", str(build), "-j", str(a.jobs), "--target", target], tree, log)
    if a.out:
        a.out.write_text(json.dumps({"commit": commit, "mutations": results, "blind_tests": blind}, indent=1) + "\n")
    print(f"{len(results)} mutations, {sum(len(r['outcome']) for r in results)} tests, {blind} blind")
    sys.exit(1 if blind else 0)


if __name__ == "__main__":
    main()
