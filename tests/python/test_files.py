"""Files from Python: round trips of scan, geometry and cone_vec documents, the command line's
reconstruction reproduced bit for bit, and every kind of bad input raising the named exception."""
import json
import pathlib
import subprocess

import numpy as np
import pytest

import ctk
from conftest import run


@pytest.fixture(scope="module")
def simulated(tmp_path_factory, ctk_command) -> pathlib.Path:
    folder = tmp_path_factory.mktemp("sim") / "scan"
    run([ctk_command, "simulate", "--out", str(folder), "--views", "12", "--cols", "64", "--rows", "64", "--pitch", "6.75",
         "--phantom", "helix-holder"])
    return folder


def test_scan_and_geometry_round_trip(simulated, tmp_path):
    scan = ctk.read_scan(simulated / "scan.json")
    assert scan["format"] == "ctk-scan/1"
    # Written elsewhere, a scan's relative names no longer resolve: it is refused, naming the key.
    with pytest.raises(ctk.InputError) as refused:
        ctk.write_scan(scan, tmp_path / "scan.json")
    assert refused.value.file.endswith("scan.json") and refused.value.key
    assert not (tmp_path / "scan.json").exists()
    ctk.write_scan(scan, simulated / "copy.json")
    assert ctk.read_scan(simulated / "copy.json") == scan

    geometry = ctk.read_geometry(simulated / "truth-geometry.json")
    ctk.write_geometry(geometry, tmp_path / "g.json")
    assert ctk.read_geometry(tmp_path / "g.json") == geometry
    indices, P = ctk.geometry_matrices(geometry)
    assert indices == list(range(12)) and P.shape == (12, 3, 4)


def test_rtk_geometry_round_trip_and_refusals(tmp_path, real_data):
    # The walnut's calibrated views (tilted, offset detectors, images stored as a mirror of what
    # the source sees) out to RTK's XML and back; the file names the pixel map that holds them.
    rows = ctk.read_cone_vec(real_data / "walnut4-tubeV1-10views" / "scan_geom_corrected.geom")
    P = ctk.matrices_from_cone_vec(rows[:12], (972, 768), (0.1496, 0.1496))
    ctk.write_rtk_geometry(P, tmp_path / "g.xml", (972, 768), (0.1496, 0.1496))
    assert "ctk pixel map: as-stored" in (tmp_path / "g.xml").read_text()
    back = ctk.read_rtk_geometry(tmp_path / "g.xml", (972, 768), (0.1496, 0.1496))
    points = np.array([[x, y, z, 1.0] for x in (-10, 10) for y in (-10, 10) for z in (-10, 10)])
    for a, b in zip(P, back):
        pa, pb = points @ a.T, points @ b.T
        np.testing.assert_allclose(pb[:, :2] / pb[:, 2:], pa[:, :2] / pa[:, 2:], rtol=0, atol=1e-9)
    with pytest.raises(ValueError, match=r"matrices\[0\]: the detector is mirrored under the pixel map flipped"):
        ctk.write_rtk_geometry(P, tmp_path / "m.xml", (972, 768), (0.1496, 0.1496), rows="flipped")
    assert not (tmp_path / "m.xml").exists()
    (tmp_path / "bad.xml").write_text("<RTKThreeDCircularGeometry version='3'><Projection/></RTKThreeDCircularGeometry>")
    with pytest.raises(ctk.InputError, match="SourceToIsocenterDistance") as e:
        ctk.read_rtk_geometry(tmp_path / "bad.xml", (972, 768), (0.1496, 0.1496))
    assert e.value.file == str(tmp_path / "bad.xml")


def test_cone_vec_rows_and_matrices_convert_both_ways(real_data):
    rows = ctk.read_cone_vec(real_data / "walnut4-tubeV1-10views" / "scan_geom_corrected.geom")
    assert rows.shape == (1201, 12)
    P = ctk.matrices_from_cone_vec(rows[:20], (972, 768), (0.1496, 0.1496))
    back = ctk.cone_vec_from_matrices(P, (972, 768), (0.1496, 0.1496))
    np.testing.assert_allclose(back, rows[:20], rtol=0, atol=1e-6 * np.abs(rows[:20]).max())
    # Every ray of the matrices goes through its pixel as the vectors place it.
    s, d, u, v = rows[0, :3], rows[0, 3:6], rows[0, 6:9], rows[0, 9:12]
    point = s + 0.5 * (d + 100.5 * u - 40.25 * v - s)  # half way to pixel (row 445.25, col 484.5)
    uvw = P[0] @ np.append(point, 1)
    np.testing.assert_allclose(uvw[:2] / uvw[2], [(768 - 1) / 2 + 100.5, (972 - 1) / 2 - 40.25], atol=1e-6)


def test_python_reconstructs_the_command_lines_volume_bit_for_bit(simulated, tmp_path, ctk_command):
    out = tmp_path / "volume.nrrd"
    run([ctk_command, "reconstruct", "--scan", str(simulated / "scan.json"), "--geometry", str(simulated / "truth-geometry.json"),
         "--out", str(out), "--size", "24", "--voxel", "2.5", "--method", "wls-cg", "--iterations", "3"])
    header, _, data = out.read_bytes().partition(b"\n\n")
    assert b"type: float" in header and b"encoding: raw" in header and b"endian: little" in header
    cli = np.frombuffer(data, dtype="<f4").reshape(24, 24, 24)

    m = ctk.load_measurements(simulated / "scan.json", simulated / "truth-geometry.json")
    A = m.projector((24, 24, 24), 2.5)
    r = ctk.wls_cg(A, m.line_integrals, weights=m.weights, iterations=3)
    np.testing.assert_array_equal(r.x, cli)
    # The forward projection is the command line's projector too: its residual is what the log says.
    log = json.loads((tmp_path / "volume.log.json").read_text())
    residual = A.forward(r.x) - m.line_integrals
    data_term = 0.5 * float(np.sum((m.weights if m.weights is not None else 1) * residual.astype(np.float64) ** 2))
    assert data_term == pytest.approx(log["solver"]["iterations"][-1]["data_term"], rel=1e-4)
    # The whole workflow from Python is the command line's, without the files.
    seen = []
    w = ctk.reconstruct(simulated / "scan.json", simulated / "truth-geometry.json", size=(24, 24, 24), voxel_mm=2.5,
                        method="wls-cg", iterations=3, progress=lambda done, total: seen.append((done, total)))
    np.testing.assert_array_equal(w.volume, cli)
    assert seen[-1] == (3, 3)
    assert w.voxel_mm == 2.5 and w.origin_mm == pytest.approx(log["volume"]["origin_mm"])
    assert w.report["views_used"] == log["views_used"] and w.report["memory_plan"] == log["memory_plan"]
    with pytest.raises(ValueError, match="os-sqs"):
        ctk.reconstruct(simulated / "scan.json", method="art")


def test_volumes_in_every_format_read_back_bitwise_and_as_other_tools_read_them(simulated, tmp_path, ctk_command):
    rng = np.random.default_rng(7)
    x = rng.standard_normal((3, 4, 5)).astype(np.float32)
    for name in ("v.nrrd", "v.mha", "v.mhd", "v.tif", "v.h5"):
        ctk.write_volume(x, tmp_path / name, voxel_mm=(0.5, 0.25, 2.0), origin_mm=(1.0, -2.0, 3.5))
        y, layout = ctk.read_volume(tmp_path / name)
        assert y.dtype == np.float32 and y.shape == (3, 4, 5)
        np.testing.assert_array_equal(y, x)
        assert layout == {"voxel_mm": [0.5, 0.25, 2.0], "origin_mm": [1.0, -2.0, 3.5]}
    # MetaImage's detached voxels are the raw float32 array numpy writes, x fastest.
    np.testing.assert_array_equal(np.fromfile(tmp_path / "v.raw", dtype="<f4").reshape(3, 4, 5), x)
    # The command line writes what the reader reads, and refuses an unknown extension before any work.
    run([ctk_command, "reconstruct", "--scan", str(simulated / "scan.json"), "--out", str(tmp_path / "r.h5"), "--size", "8",
         "--iterations", "1"])
    r, layout = ctk.read_volume(tmp_path / "r.h5")
    assert r.shape == (8, 8, 8) and np.all(np.isfinite(r))
    refused = subprocess.run([ctk_command, "reconstruct", "--scan", str(simulated / "scan.json"), "--out",
                              str(tmp_path / "r.vol")], capture_output=True, text=True)
    assert refused.returncode == 2 and ".nrrd" in refused.stderr and not list(tmp_path.glob("r.vol*"))
    with pytest.raises(ctk.InputError):
        ctk.read_volume(tmp_path / "v.png")


def test_bad_inputs_raise_the_named_exception(simulated, tmp_path):
    with pytest.raises(ctk.InputError, match="no such file") as missing:
        ctk.read_scan(tmp_path / "none.json")
    assert missing.value.file.endswith("none.json")
    (tmp_path / "text.json").write_text("{not json")
    with pytest.raises(ctk.InputError):
        ctk.read_geometry(tmp_path / "text.json")
    geometry = ctk.read_geometry(simulated / "truth-geometry.json")
    geometry["format"] = "ctk-geometry/9"
    with pytest.raises(ctk.InputError) as wrong_format:
        ctk.write_geometry(geometry, tmp_path / "g.json")
    assert wrong_format.value.key == "format"
    geometry = ctk.read_geometry(simulated / "truth-geometry.json")
    del geometry["views"][3]["P"]
    with pytest.raises(ctk.InputError, match="P"):
        ctk.write_geometry(geometry, tmp_path / "g.json")
    assert not (tmp_path / "g.json").exists()
    (tmp_path / "d.json").write_text('{"format": "ctk-geometry/1"}')
    with pytest.raises(ctk.InputError) as not_a_report:
        ctk.read_diagnosis(tmp_path / "d.json")
    assert not_a_report.value.key == "format"
    with pytest.raises(ValueError, match=r"\(views, 12\)"):
        ctk.matrices_from_cone_vec(np.zeros((3, 11)), (8, 8))
    with pytest.raises(ctk.InputError):
        ctk.read_image(tmp_path / "text.json")
    assert issubclass(ctk.InputError, ValueError)


def test_outputs_that_name_no_file_and_numbers_that_describe_no_projection_are_refused_as_the_command_line_does(
        simulated, tmp_path):
    geometry = ctk.read_geometry(simulated / "truth-geometry.json")
    with pytest.raises(ctk.InputError, match="names no file"):
        ctk.write_geometry(geometry, "")
    with pytest.raises(ctk.InputError, match="a name of 256 bytes; file systems take at most 255"):
        ctk.write_geometry(geometry, tmp_path / ("g" * 251 + ".json"))
    legal = tmp_path / ("g" * 245 + ".json")  # 250 bytes: its temporary's name gives way
    ctk.write_geometry(geometry, legal)
    assert ctk.read_geometry(legal)["views"] == geometry["views"]
    assert [p.name for p in tmp_path.iterdir()] == [legal.name]
    with pytest.raises(ValueError, match="out: expected the scan folder to write, got an empty name"):
        ctk.simulate("")
    with pytest.raises(ValueError, match="describes no cone-beam projection: are the pitch and distances in mm"):
        ctk.circular_matrices([0.0, 1.0], (64, 64), (100, 100), sod=0.001, sdd=0.002)
    (tmp_path / "empty.vec").write_text("")
    with pytest.raises(ctk.InputError, match="no rows of 12 numbers"):
        ctk.read_cone_vec(tmp_path / "empty.vec")


def test_an_import_never_writes_over_its_inputs(simulated):
    image = simulated / "projections" / sorted(p.name for p in (simulated / "projections").iterdir())[0]
    before = image.read_bytes()
    P = ctk.circular_matrices([0.0], (64, 64), (6.75, 6.75), sod=500, sdd=1000)
    with pytest.raises(ctk.InputError, match="out"):
        ctk.import_scan(image, P, [image], (64, 64), (6.75, 6.75))
    assert image.read_bytes() == before
    with pytest.raises(ValueError, match="one per file"):
        ctk.import_scan(simulated / "other.json", np.concatenate([P, P]), [image], (64, 64), (6.75, 6.75))
    with pytest.raises(ValueError, match="RefineScanOptions.coarsening"):
        ctk.refine(simulated / "scan.json", coarsening=0.5)


def test_other_tools_scans_read_as_the_command_line_imports_them(tmp_path, ctk_command):
    import os
    run([os.environ["CTK_VENDOR_SCANS"], "write", str(tmp_path)])
    nx = ctk.read_nxtomo(tmp_path / "nxtomo" / "scan.nx")
    assert nx["frames"].shape == (96, 80, 96) and nx["frames"].dtype == np.float32
    assert [int((nx["image_key"] == k).sum()) for k in range(4)] == [90, 3, 2, 1]
    assert nx["x_pixel_size_mm"] == pytest.approx(0.8) and nx["source_to_sample_mm"] == pytest.approx(200)
    run([ctk_command, "import", "nxtomo", "--nexus", str(tmp_path / "nxtomo" / "scan.nx"), "--out", str(tmp_path / "nx.json")])
    first = int(np.flatnonzero(nx["image_key"] == 0)[0])
    assert np.array_equal(ctk.read_image(tmp_path / "nx.frames" / "proj_00000.tif"), nx["frames"][first])

    nikon = ctk.read_xtekct(tmp_path / "nikon" / "ball.xtekct")
    assert nikon["matrices"].shape == (90, 3, 4) and nikon["detector_shape"] == (80, 96)
    assert [pathlib.Path(f).name for f in nikon["files"][:2]] == ["ball_0001.tif", "ball_0002.tif"]
    run([ctk_command, "import", "nikon", "--xtekct", str(tmp_path / "nikon" / "ball.xtekct"), "--out", str(tmp_path / "nk.json")])
    _, imported = ctk.geometry_matrices(ctk.read_geometry(tmp_path / "nk.matrices.json"))
    assert np.allclose(imported, nikon["matrices"], rtol=1e-12, atol=1e-9)
    with pytest.raises(ctk.InputError, match="not an HDF5 file"):
        ctk.read_nxtomo(tmp_path / "nk.json")


def test_vendor_scans_import_from_python_as_from_the_command_line(tmp_path, ctk_command):
    import os
    import signal
    run([os.environ["CTK_VENDOR_SCANS"], "write", str(tmp_path)])
    nexus, xtekct = tmp_path / "nxtomo" / "scan.nx", tmp_path / "nikon" / "ball.xtekct"
    run([ctk_command, "import", "nxtomo", "--nexus", str(nexus), "--out", str(tmp_path / "cli-nx.json")])
    run([ctk_command, "import", "nikon", "--xtekct", str(xtekct), "--out", str(tmp_path / "cli-nk.json")])
    seen = []
    scan = ctk.import_nxtomo(nexus, tmp_path / "nx.json", progress=lambda done, total: seen.append((done, total)))
    assert scan["projections"]["count"] == 90 and seen[-1] == (95, 95)
    scan = ctk.import_nikon(xtekct, tmp_path / "nk.json", bin=2)
    assert scan["detector"]["binning"] == 2
    for mine, theirs in (("nx", "cli-nx"), ("nk", "cli-nk")):
        _, P = ctk.geometry_matrices(ctk.read_geometry(tmp_path / f"{mine}.matrices.json"))
        _, Q = ctk.geometry_matrices(ctk.read_geometry(tmp_path / f"{theirs}.matrices.json"))
        assert np.array_equal(P, Q), mine
    assert np.array_equal(ctk.read_image(tmp_path / "nx.frames" / "proj_00007.tif"),
                          ctk.read_image(tmp_path / "cli-nx.frames" / "proj_00007.tif"))

    # Refusals name the keyword; a progress callable that raises stops the copy, leaving nothing.
    with pytest.raises(ValueError, match="sod: expected a finite distance above 0"):
        ctk.import_nxtomo(nexus, tmp_path / "bad.json", sod=-5)
    with pytest.raises(ctk.InputError, match="out: would overwrite the input nexus"):
        ctk.import_nxtomo(nexus, nexus)

    def stop(done, total):
        if done == 10:
            raise RuntimeError("enough")
    with pytest.raises(RuntimeError, match="enough"):
        ctk.import_nxtomo(nexus, tmp_path / "stopped.json", progress=stop)
    assert not (tmp_path / "stopped.json").exists() and not (tmp_path / "stopped.matrices.json").exists()
    assert not (tmp_path / "stopped.frames").exists()

    # Ctrl-C while the frames are copied, and after the last one, where the copy has nothing left to
    # look for it and only the publishing step does (Python sees the signal up to a poll later;
    # without that step's look, 19 of 30 such runs left their files): five times over.
    for moment in ("10", "last", "last", "last", "last", "last"):
        def ctrl_c(done, total):
            if done == (10 if moment == "10" else total):
                os.kill(os.getpid(), signal.SIGINT)
        with pytest.raises(KeyboardInterrupt):
            ctk.import_nxtomo(nexus, tmp_path / "interrupted.json", progress=ctrl_c)
        assert sorted(p.name for p in tmp_path.glob("interrupted*")) == [], moment


def test_voxelise_puts_a_phantom_where_read_volume_says_its_voxels_are(tmp_path):
    # One sphere of radius 2 mm at (5, -3, 10) mm: on a 1 mm grid whose voxel 0 is centred at
    # (-8, -8, 0), the voxel around its centre is (x 13, y 5, z 10), as (z, y, x) in the array;
    # every voxel 3 mm or more from the centre (all 8 sample points outside) is air.
    phantom = tmp_path / "sphere.json"
    phantom.write_text(json.dumps({"format": "ctk-phantom/1", "primitives": [
        {"type": "sphere", "center_mm": [5, -3, 10], "radius_mm": 2, "attenuation_per_mm": 0.1}]}))
    v = ctk.voxelise([str(phantom)], (16, 12, 20), (1.0, 1.0, 1.0), (-8.0, -8.0, 0.0))
    assert v.shape == (16, 12, 20) and v.dtype == np.float32
    assert v[10, 5, 13] == pytest.approx(0.1)
    z, y, x = np.indices(v.shape)
    far = (x - 8 - 5) ** 2 + (y - 8 + 3) ** 2 + (z - 10) ** 2 >= 9
    assert np.all(v[far] == 0) and v.sum() == pytest.approx(0.1 * 4 / 3 * np.pi * 8, rel=0.1)
    # Written and read back, the same voxels sit at the same places.
    out = tmp_path / "v.nrrd"
    ctk.write_volume(v, out, (1.0, 1.0, 1.0), (-8.0, -8.0, 0.0))
    back, layout = ctk.read_volume(out)
    np.testing.assert_array_equal(back, v)
    assert tuple(layout["origin_mm"]) == (-8.0, -8.0, 0.0)
    with pytest.raises(ValueError, match="shape"):
        ctk.voxelise([str(phantom)], (0, 2, 2), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    with pytest.raises(ctk.InputError, match="not a built-in phantom"):
        ctk.voxelise(["no-such-phantom"], (2, 2, 2), (1.0, 1.0, 1.0), (0.0, 0.0, 0.0))


def test_voxelise_per_material_splits_the_truth_by_material(tmp_path):
    # A PVC block with a hole cut in it (the hole is PVC too) and a copper bead beside it: two
    # materials, each its primitives alone, adding up to the whole.
    phantom = tmp_path / "two.json"
    phantom.write_text(json.dumps({"format": "ctk-phantom/1", "primitives": [
        {"type": "box", "center_mm": [0, 0, 5], "size_mm": [6, 6, 6], "attenuation_per_mm": 0.046, "material": "pvc"},
        {"type": "cylinder", "center_mm": [0, 0, 5], "radius_mm": 1, "height_mm": 6, "attenuation_per_mm": -0.046,
         "material": "pvc"},
        {"type": "sphere", "center_mm": [6, 0, 5], "radius_mm": 1.5, "attenuation_per_mm": 1.43, "material": "copper"}]}))
    grid = ((12, 12, 20), (1.0, 1.0, 1.0), (-6.0, -6.0, 0.0))
    parts = ctk.voxelise_per_material([str(phantom)], *grid)
    assert list(parts) == ["pvc", "copper"]
    np.testing.assert_allclose(parts["pvc"] + parts["copper"], ctk.voxelise([str(phantom)], *grid), atol=1e-7)
    assert parts["pvc"].max() == pytest.approx(0.046) and parts["pvc"].min() >= 0  # the hole inside its block
    assert parts["copper"].max() == pytest.approx(1.43) and parts["copper"][5, 6, 6] == 0  # the block's centre
