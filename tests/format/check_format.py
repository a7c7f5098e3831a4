"""Every C++ source and header of the project is formatted as .clang-format says: lists the files
clang-format would change (with the first differing lines of each) and fails on any.
Usage: check_format.py <source dir> [clang-format]"""
import concurrent.futures
import os
import pathlib
import subprocess
import sys

FOLDERS = ["libcore", "libgeom", "libmeasure", "libproj", "librecon", "libcalib", "libplan", "phantoms", "tools", "python", "tests", "benchmarks"]


def main():
    root = pathlib.Path(sys.argv[1])
    tool = sys.argv[2] if len(sys.argv) > 2 else "clang-format"
    files = sorted(p for folder in FOLDERS for p in (root / folder).rglob("*") if p.suffix in (".cpp", ".hpp", ".h"))
    if not files:
        sys.exit(f"no sources found under {root}")
    # One clang-format per core over a share of the files (its start-up costs more than a file):
    # --dry-run names each file it would change.
    def violations(share):
        try:
            r = subprocess.run([tool, "--dry-run", f"--style=file:{root / '.clang-format'}", *map(str, share)],
                               capture_output=True, text=True)
        except FileNotFoundError:
            sys.exit(f"{tool} not found: scripts/setup.sh installs it (Debian package clang-format)")
        if r.returncode != 0:
            sys.exit(f"{tool} failed: {r.stderr.strip()}")
        return {line.split(":", 1)[0] for line in r.stderr.splitlines() if "[-Wclang-format-violations]" in line}

    jobs = os.cpu_count() or 1
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        named = set().union(*pool.map(violations, [files[i::jobs] for i in range(jobs)]))
    unformatted = [f.relative_to(root) for f in files if str(f) in named]
    for f in unformatted:
        print(f"not formatted: {f} (clang-format -i {f})")
    print(f"{len(files) - len(unformatted)} of {len(files)} files formatted")
    sys.exit(1 if unformatted else 0)


if __name__ == "__main__":
    main()
