#!/usr/bin/env python3
"""The libraries form layers: each may include only the libraries below it. Lists every
`#include "ctk/<lib>/..."` in each library's sources and headers that reaches a library it may not
depend on, and exits 1 if there is one. The layers are the README's "Layout" table.
Usage: check_include_graph.py SOURCE_DIR"""
import pathlib
import re
import sys

# folder -> (its headers' namespace, the namespaces it may include besides its own)
LAYERS = {
    "libcore": ("core", set()),
    "libgeom": ("geom", {"core"}),
    "libmeasure": ("measure", {"core", "geom"}),
    "libproj": ("proj", {"core", "geom"}),
    "librecon": ("recon", {"core", "geom", "measure", "proj"}),
    "libcalib": ("calib", {"core", "geom", "measure"}),
    "phantoms": ("phantoms", {"core", "geom"}),
    "libplan": ("plan", {"core", "geom", "measure", "proj", "recon", "calib"}),
}
# One file may reach further than its library, named with what it may add: the simulated
# acquisition and the planning workflow on it are libplan's separate target ctk::plan_simulated.
EXCEPTIONS = {
    "libplan/include/ctk/plan/simulated_acquisition.hpp": {"phantoms"},
    "libplan/src/simulated_acquisition.cpp": {"phantoms"},
    "libplan/include/ctk/plan/simulated_planning_run.hpp": {"phantoms"},
    "libplan/src/simulated_planning_run.cpp": {"phantoms"},
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"ctk/([a-z_]+)/', re.M)


def main():
    root = pathlib.Path(sys.argv[1])
    upward = []
    files = 0
    for folder, (own, allowed) in LAYERS.items():
        for path in sorted((root / folder).rglob("*")):
            if path.suffix not in (".hpp", ".h", ".cpp") or not path.is_file():
                continue
            files += 1
            relative = path.relative_to(root).as_posix()
            may = allowed | {own} | EXCEPTIONS.get(relative, set())
            for target in INCLUDE.findall(path.read_text(errors="replace")):
                if target not in may:
                    upward.append(f"{relative} includes ctk/{target}/ (allowed: {', '.join(sorted(may))})")
    for line in upward:
        print("UPWARD", line)
    print(f"{files} files of {len(LAYERS)} libraries, {len(upward)} includes against the layers")
    sys.exit(1 if upward or files == 0 else 0)


if __name__ == "__main__":
    main()
