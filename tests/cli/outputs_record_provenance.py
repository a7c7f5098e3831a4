#!/usr/bin/env python3
"""Every JSON file a run writes names the build that wrote it and the command line that asked for it:
a small scan simulated, calibrated and reconstructed; each JSON output must carry
provenance.ctk_version equal to what `ctk --version` says and provenance.invocation equal to the
command that wrote it, words with spaces quoted as a shell would need.  Usage: outputs_record_provenance.py CTK"""
import json
import pathlib
import shlex
import shutil
import subprocess
import sys

from failures import report


def main():
    ctk = sys.argv[1]
    work = pathlib.Path("cli-provenance")
    shutil.rmtree(work, ignore_errors=True)
    (work / "with space").mkdir(parents=True)
    version = subprocess.run([ctk, "--version"], check=True, capture_output=True, text=True).stdout.splitlines()[0]
    version = version.removeprefix("ctk ")
    sim = str(work / "with space")
    commands = [
        [ctk, "simulate", "--out", sim, "--views", "8", "--cols", "240", "--rows", "240", "--pitch", "1.8"],
        [ctk, "calibrate", "--scan", f"{sim}/scan.json", "--out", f"{sim}/calibrated.json"],
        [ctk, "reconstruct", "--scan", f"{sim}/scan.json", "--geometry", f"{sim}/calibrated.json", "--out", f"{sim}/v.nrrd",
         "--size", "24", "--iterations", "1"],
    ]
    failures = []
    seen = set()
    for command in commands:
        before = {p: p.stat().st_mtime_ns for p in work.rglob("*.json")}
        subprocess.run(command, check=True, stdout=subprocess.DEVNULL)
        written = [p for p in work.rglob("*.json") if before.get(p) != p.stat().st_mtime_ns]
        if not written:
            failures.append(f"{command[1]} wrote no JSON file")
        for path in written:
            seen.add(path.name)
            record = json.loads(path.read_text()).get("provenance")
            if not isinstance(record, dict):
                failures.append(f"{path}: no provenance")
                continue
            if record.get("ctk_version") != version:
                failures.append(f"{path}: ctk_version {record.get('ctk_version')!r}, ctk --version says {version!r}")
            if shlex.split(record.get("invocation", "")) != command:
                failures.append(f"{path}: invocation {record.get('invocation')!r} is not {shlex.join(command)!r}")
    print("checked:", " ".join(sorted(seen)))
    return report(failures)


if __name__ == "__main__":
    sys.exit(main())
