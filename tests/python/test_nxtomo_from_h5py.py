"""NXtomo files as other tools write them, through h5py (how CIL and most labs write NeXus): every
string kind h5py writes reads exactly (the units and the entry found), in a process that has not
imported h5py (HDF5 converts no string between ASCII and UTF-8 without h5py's own converters),
and files that point outside themselves, or declare what they do not store, are refused naming
the dataset."""
import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

FRAMES = 12


def string_of(kind: str, text: str):
    """`text` as h5py stores it for each way a writer may hand it over."""
    return {
        "str": lambda: text,                                              # variable length, UTF-8
        "bytes": lambda: np.bytes_(text),                                 # fixed length, exactly the text
        "padded": lambda: np.array(text.encode(), dtype="S16"),            # fixed length, null-padded beyond it
        "vlen-ascii": lambda: np.array(text.encode(), dtype=h5py.string_dtype("ascii")),
        "array": lambda: np.array([text.encode()]),                       # a one-element array
    }[kind]()


def write_nxtomo(path, strings="str", data=None, units=None, definition=None, frames=FRAMES):
    s = lambda text: string_of(strings, text)
    with h5py.File(path, "w") as f:
        entry = f.create_group("entry")
        entry.attrs["NX_class"] = s("NXentry")
        entry["definition"] = s("NXtomo") if definition is None else definition
        detector = entry.create_group("instrument/detector")
        if data is None:
            detector["data"] = np.random.default_rng(1).integers(100, 1000, (frames, 8, 10)).astype(np.uint16)
        else:
            data(detector)
        detector["image_key"] = np.array([1, 2] + [0] * (frames - 2), dtype=np.int32)
        for name, value in (("x_pixel_size", 0.2), ("y_pixel_size", 0.25), ("distance", 300.0)):
            detector[name] = value
            detector[name].attrs["units"] = s("mm") if units is None else units
        source = entry.create_group("instrument/source")
        source.attrs["NX_class"] = s("NXsource")
        source["distance"] = -0.2
        source["distance"].attrs["units"] = s("m")
        sample = entry.create_group("sample")
        sample["rotation_angle"] = np.linspace(0, 360, frames, endpoint=False)
        sample["rotation_angle"].attrs["units"] = s("degree")


def ctk_import(ctk_command, nexus, out):
    return subprocess.run([ctk_command, "import", "nxtomo", "--nexus", str(nexus), "--out", str(out)],
                          capture_output=True, text=True, timeout=60)


@pytest.mark.parametrize("strings", ["str", "bytes", "padded", "vlen-ascii", "array"])
def test_every_string_kind_h5py_writes_reads_exactly(tmp_path, ctk_command, strings):
    nexus = tmp_path / "scan.nx"
    write_nxtomo(nexus, strings)
    done = ctk_import(ctk_command, nexus, tmp_path / "scan.json")
    assert done.returncode == 0, done.stderr
    scan = json.loads((tmp_path / "scan.json").read_text())
    # 0.2 and 0.25 mm pixels ("mm" read whole), 0.2 m + 300 mm from source to detector ("m" and "mm").
    assert scan["detector"]["pixel_pitch_mm"] == pytest.approx([0.2, 0.25], rel=1e-12)
    assert scan["source_to_detector_mm"] == pytest.approx(500.0, rel=1e-12)
    assert scan["projections"]["count"] == FRAMES - 2
    # From Python, in a process that never imported h5py.
    probe = ("import ctk, sys; nx = ctk.read_nxtomo(sys.argv[1]); "
             "assert 'h5py' not in sys.modules; print(nx['x_pixel_size_mm'], nx['source_to_sample_mm'])")
    read = subprocess.run([sys.executable, "-c", probe, str(nexus)], capture_output=True, text=True, env=os.environ)
    assert read.returncode == 0, read.stderr
    assert [float(x) for x in read.stdout.split()] == pytest.approx([0.2, 200.0], rel=1e-12)


def refusal(ctk_command, tmp_path, **kwargs):
    nexus = tmp_path / "scan.nx"
    write_nxtomo(nexus, **kwargs)
    done = ctk_import(ctk_command, nexus, tmp_path / "scan.json")
    assert not (tmp_path / "scan.json").exists() and not (tmp_path / "scan.frames").exists()
    return done


def test_damaged_strings_are_refused_naming_the_key(tmp_path, ctk_command):
    done = refusal(ctk_command, tmp_path, units=5)
    assert done.returncode == 2 and "attribute 'units' of dataset '/entry/instrument/detector/x_pixel_size'" in done.stderr
    done = refusal(ctk_command, tmp_path, definition=7)
    assert done.returncode == 2 and "dataset '/entry/definition': expected one string" in done.stderr


def test_files_that_point_outside_themselves_are_refused(tmp_path, ctk_command):
    os.mkfifo(tmp_path / "fifo")  # what an external link or storage might name: a read would hang
    (tmp_path / "other.bin").write_bytes(b"x" * (FRAMES * 8 * 10 * 2))
    cases = {
        "is, or lies behind, a link to another file":
            lambda d: d.__setitem__("data", h5py.ExternalLink(str(tmp_path / "fifo"), "/data")),
        "external storage":
            lambda d: d.create_dataset("data", (FRAMES, 8, 10), np.uint16,
                                       external=[(str(tmp_path / "other.bin"), 0, h5py.h5f.UNLIMITED)]),
        "virtual dataset": lambda d: d.create_virtual_dataset("data", virtual_layout()),
        "stores no values": lambda d: d.create_dataset("data", (200000, 8, 10), np.uint16, chunks=(1, 8, 10)),
        "stores 12 of its 200000 chunks": lambda d: partly_written(d),
    }
    for message, data in cases.items():
        done = refusal(ctk_command, tmp_path, data=data)
        assert done.returncode == 2, (message, done.stderr)
        assert "dataset '/entry/instrument/detector/data'" in done.stderr and message in done.stderr, done.stderr


def test_per_frame_lists_declaring_more_values_than_frames_are_refused_before_reading(tmp_path, ctk_command):
    """A few kilobytes may declare 10^12 image keys or angles (chunked, never written): the count is
    checked against the frames before anything is allocated (it had asked for 8 TB)."""
    for dataset in ("instrument/detector/image_key", "sample/rotation_angle"):
        nexus = tmp_path / "scan.nx"
        write_nxtomo(nexus)
        with h5py.File(nexus, "a") as f:
            units = f["entry/" + dataset].attrs.get("units")
            del f["entry/" + dataset]
            huge = f.create_dataset("entry/" + dataset, (10 ** 12,), np.float64, chunks=(4096,), compression="gzip")
            if units is not None:
                huge.attrs["units"] = units
        assert nexus.stat().st_size < 100_000
        done = ctk_import(ctk_command, nexus, tmp_path / "scan.json")
        assert done.returncode == 2, done.stderr
        assert f"dataset '/entry/{dataset}'" in done.stderr, done.stderr
        assert f"declares 1000000000000 values; expected at most {FRAMES}" in done.stderr, done.stderr
        assert not (tmp_path / "scan.json").exists()


def virtual_layout():
    layout = h5py.VirtualLayout(shape=(FRAMES, 8, 10), dtype=np.uint16)
    layout[:] = h5py.VirtualSource("missing.h5", "data", shape=(FRAMES, 8, 10))
    return layout


def partly_written(detector):
    data = detector.create_dataset("data", (200000, 8, 10), np.uint16, chunks=(1, 8, 10), compression="gzip")
    data[:FRAMES] = 500


def test_an_import_killed_half_way_leaves_the_earlier_one_whole(tmp_path, ctk_command):
    """The frames go into a hidden folder put in place in one step: an import killed while it
    writes them leaves the earlier import's scan and frames exactly as they were, and the next
    import removes what the killed one left."""
    nexus = tmp_path / "many.nx"
    write_nxtomo(nexus, frames=3000)
    out = tmp_path / "scan.json"
    assert ctk_import(ctk_command, nexus, out).returncode == 0

    def fingerprint():
        files = [out, tmp_path / "scan.matrices.json"] + sorted((tmp_path / "scan.frames").iterdir())
        return [(f.name, f.read_bytes()) for f in files]

    before = fingerprint()
    hidden = lambda: [p for p in tmp_path.iterdir() if p.name.startswith(".")]
    run = subprocess.Popen([ctk_command, "import", "nxtomo", "--nexus", str(nexus), "--out", str(out)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 30
    while run.poll() is None and time.monotonic() < deadline:
        if any(p.is_dir() and sum(1 for _ in p.iterdir()) >= 200 for p in hidden()):
            run.kill()
            break
        time.sleep(0.002)
    assert run.wait() == -signal.SIGKILL, "the import ended before it could be killed half way"
    assert hidden(), "the killed import left no hidden folder: it did not write into one"
    assert fingerprint() == before
    assert ctk_import(ctk_command, nexus, out).returncode == 0
    assert not hidden(), [p.name for p in hidden()]


def test_ctrl_c_after_the_last_frame_of_an_h5py_file_leaves_nothing(tmp_path):
    """Ctrl-C in Python just after the last frame is copied, when only the publishing step can
    still see it (Python notices a signal up to a poll later): five such imports of a file h5py
    wrote leave nothing, and an import left alone then publishes the scan, its matrices and frames."""
    nexus = tmp_path / "scan.nx"
    write_nxtomo(nexus)
    probe = """
import os, signal, sys, pathlib
import ctk
nexus, folder = sys.argv[1], pathlib.Path(sys.argv[2])
def ctrl_c(done, total):
    if done == total:
        os.kill(os.getpid(), signal.SIGINT)
for k in range(5):
    try:
        ctk.import_nxtomo(nexus, folder / "interrupted.json", progress=ctrl_c)
        sys.exit(f"no KeyboardInterrupt in run {k}")
    except KeyboardInterrupt:
        pass
    left = sorted(p.name for p in folder.iterdir() if p.name != "scan.nx")
    assert left == [], (k, left)
scan = ctk.import_nxtomo(nexus, folder / "whole.json")
assert scan["projections"]["count"] == PROJECTIONS and "h5py" not in sys.modules
print(sorted(p.name for p in folder.iterdir()))
""".replace("PROJECTIONS", str(FRAMES - 2))
    done = subprocess.run([sys.executable, "-c", probe, str(nexus), str(tmp_path)], capture_output=True, text=True,
                          env=os.environ, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["['scan.nx',", "'whole.frames',", "'whole.json',", "'whole.matrices.json']"]
