"""Every C++ source and header of the project is formatted as .clang-format says: lists the files
clang-format would change (with the first differing lines of each) and fails on any.
Usage: check_format.py <source dir> [clang-format]"""
import pathlib
import subprocess
import sys

FOLDERS = ["libgeom", "libproj", "librecon", "libcalib", "libplan", "phantoms", "tools", "python", "tests", "benchmarks"]


def main():
    root = pathlib.Path(sys.argv[1])
    tool = sys.argv[2] if len(sys.argv) > 2 else "clang-format"
    files = sorted(p for folder in FOLDERS for p in (root / folder).rglob("*") if p.suffix in (".cpp", ".hpp", ".h"))
    if not files:
        sys.exit(f"no sources found under {root}")
    unformatted = []
    for f in files:
        try:
            formatted = subprocess.run([tool, f"--style=file:{root / '.clang-format'}", str(f)], check=True,
                                       capture_output=True, text=True).stdout
        except FileNotFoundError:
            sys.exit(f"{tool} not found: scripts/setup.sh installs it (Debian package clang-format)")
        if formatted != f.read_text():
            unformatted.append(f.relative_to(root))
    for f in unformatted:
        print(f"not formatted: {f} (clang-format -i {f})")
    print(f"{len(files) - len(unformatted)} of {len(files)} files formatted")
    sys.exit(1 if unformatted else 0)


if __name__ == "__main__":
    main()
