"""A volume written in every format ctk writes, read by readers that are not ctk's: tifffile (as
Debian ships it, without imagecodecs), h5py, Pillow for the first page, and NRRD and MetaImage
readers written here from the formats' specifications the way ITK maps them to its physical
(left-posterior-superior) space. Chosen voxels must land at the same physical point, to 1e-6 mm,
with the same values; and NRRD files in the right-anterior-superior space that 3D Slicer writes
read back at the points ITK gives them."""
import re

import h5py
import numpy as np
import pytest
import tifffile
from PIL import Image

import ctk

VOXEL = (0.5, 0.75, 1.25)          # not cubic: each axis' spacing must reach the reader
ORIGIN = (-3.0, 2.5, -7.25)        # centre of voxel (0, 0, 0), holder frame (mm)
SHAPE = (6, 5, 4)                  # z, y, x
CHOSEN = [(0, 0, 0), (3, 4, 5), (1, 3, 2), (3, 0, 5)]  # (i, j, k) = (x, y, z) indices


def volume():
    return np.arange(np.prod(SHAPE), dtype=np.float32).reshape(SHAPE) * 0.5 - 7


def holder_point(i, j, k):
    return np.array(ORIGIN) + np.array(VOXEL) * (i, j, k)


def text_header(path, separator, end):
    """Header fields of NRRD ('key: value', ends at a blank line) or MetaImage ('Key = Value', ends
    after ElementDataFile), and the offset of the data."""
    fields, raw = {}, path.read_bytes()
    offset = 0
    for line in raw.split(b"\n"):
        offset += len(line) + 1
        text = line.decode("latin-1").rstrip("\r")
        if end(text):
            if separator in text:
                key, value = text.split(separator, 1)
                fields[key.strip()] = value.strip()
            break
        if text.startswith("#") or separator not in text:
            continue
        key, value = text.split(separator, 1)
        fields[key.strip()] = value.strip()
    return fields, raw, offset


def nrrd_as_itk(path):
    """(array (z, y, x), function (i, j, k) -> LPS point) as ITK's NrrdImageIO maps the header."""
    fields, raw, offset = text_header(path, ": ", lambda t: t == "")
    assert fields["type"] in ("float", "float32") and fields["encoding"] == "raw" and fields["endian"] == "little"
    sizes = [int(s) for s in fields["sizes"].split()]
    directions = np.array([[float(x) for x in v.strip("()").split(",")] for v in fields["space directions"].split()])
    origin = np.array([float(x) for x in fields["space origin"].strip("()").split(",")])
    to_lps = {"left-posterior-superior": (1, 1, 1), "right-anterior-superior": (-1, -1, 1),
              "left-anterior-superior": (1, -1, 1)}[fields["space"]]
    directions, origin = directions * to_lps, origin * np.array(to_lps)
    data = np.frombuffer(raw[offset:], dtype="<f4").reshape(sizes[::-1])
    return data, lambda i, j, k: origin + i * directions[0] + j * directions[1] + k * directions[2]


def metaimage_as_itk(path):
    fields, raw, offset = text_header(path, "=", lambda t: t.split("=")[0].strip() == "ElementDataFile")
    assert fields["ElementType"] == "MET_FLOAT" and fields.get("BinaryDataByteOrderMSB", "False") == "False"
    sizes = [int(s) for s in fields["DimSize"].split()]
    spacing = np.array([float(s) for s in fields["ElementSpacing"].split()])
    matrix = np.array([float(s) for s in fields.get("TransformMatrix", "1 0 0 0 1 0 0 0 1").split()]).reshape(3, 3)
    origin = np.array([float(s) for s in fields["Offset"].split()])
    data_file = fields["ElementDataFile"]
    payload = raw[offset:] if data_file == "LOCAL" else (path.parent / data_file).read_bytes()
    data = np.frombuffer(payload, dtype="<f4").reshape(sizes[::-1])
    # ITK: the columns of TransformMatrix are the axes' directions (MetaIO stores it row by row).
    return data, lambda i, j, k: origin + matrix.T @ (spacing * (i, j, k))


def tiff_as_tifffile(path):
    with tifffile.TiffFile(path) as tif:
        pages = tif.pages
        assert all(p.predictor == 1 for p in pages), "a predictor other readers may not decode"
        data = tif.asarray()
        x_res, y_res = pages[0].tags["XResolution"].value, pages[0].tags["YResolution"].value
        spacing_x, spacing_y = x_res[1] / x_res[0], y_res[1] / y_res[0]
        meta = tif.imagej_metadata
    origin = np.array([float(s) for s in re.search(r"ctk_origin_mm=(.*)", pages[0].description).group(1).split()])
    spacing = np.array([spacing_x, spacing_y, float(meta["spacing"])])
    return data, lambda i, j, k: origin + spacing * (i, j, k)


def hdf5_as_h5py(path):
    with h5py.File(path, "r") as f:
        data = f["volume"][...]
        voxel, origin = np.array(f["volume"].attrs["voxel_mm"]), np.array(f["volume"].attrs["origin_mm"])
    return data, lambda i, j, k: origin + voxel * (i, j, k)


@pytest.mark.parametrize("extension,reader", [
    (".nrrd", nrrd_as_itk), (".mha", metaimage_as_itk), (".mhd", metaimage_as_itk),
    (".tif", tiff_as_tifffile), (".h5", hdf5_as_h5py)])
def test_every_format_puts_each_voxel_where_other_readers_find_it(tmp_path, extension, reader):
    v = volume()
    file = tmp_path / f"volume{extension}"
    ctk.write_volume(v, file, voxel_mm=VOXEL, origin_mm=ORIGIN)
    data, point = reader(file)
    assert data.shape == SHAPE and np.array_equal(data, v)
    for i, j, k in CHOSEN:
        assert np.allclose(point(i, j, k), holder_point(i, j, k), rtol=0, atol=1e-6), (extension, i, j, k)
    back, layout = ctk.read_volume(file)
    assert np.array_equal(back, v)
    assert np.allclose(layout["origin_mm"], ORIGIN, atol=1e-12) and np.allclose(layout["voxel_mm"], VOXEL, atol=1e-12)
    if extension == ".tif":  # the first page through Pillow too: a plain float32 image
        assert np.array_equal(np.asarray(Image.open(file), dtype=np.float32), v[0])


def write_nrrd(path, data, space, directions, origin, comment=""):
    header = (f"NRRD0004\n{comment}type: float\ndimension: 3\nspace: {space}\n"
              f"sizes: {data.shape[2]} {data.shape[1]} {data.shape[0]}\n"
              "space directions: " + " ".join("(" + ",".join(repr(float(x)) for x in d) + ")" for d in directions) + "\n"
              "space origin: (" + ",".join(repr(float(x)) for x in origin) + ")\n"
              "kinds: domain domain domain\nendian: little\nencoding: raw\n\n")
    path.write_bytes(header.encode() + data.astype("<f4").tobytes())


def test_nrrd_in_other_spaces_reads_where_itk_places_it(tmp_path):
    v = volume()
    # 3D Slicer's way: RAS space, x and y running backwards so that the LPS axes run forwards.
    ras_origin = (3.0, -2.5, -7.25)  # the LPS point (-3, 2.5, -7.25)
    write_nrrd(tmp_path / "slicer.nrrd", v, "right-anterior-superior",
               [(-VOXEL[0], 0, 0), (0, -VOXEL[1], 0), (0, 0, VOXEL[2])], ras_origin)
    back, layout = ctk.read_volume(tmp_path / "slicer.nrrd")
    assert np.array_equal(back, v) and np.allclose(layout["origin_mm"], ORIGIN) and np.allclose(layout["voxel_mm"], VOXEL)
    # RAS with forward axes: in LPS x and y run backwards; ctk stores them reversed, each voxel at ITK's point.
    write_nrrd(tmp_path / "ras.nrrd", v, "right-anterior-superior",
               [(VOXEL[0], 0, 0), (0, VOXEL[1], 0), (0, 0, VOXEL[2])], ORIGIN)
    back, layout = ctk.read_volume(tmp_path / "ras.nrrd")
    _, itk_point = nrrd_as_itk(tmp_path / "ras.nrrd")
    assert np.allclose(layout["voxel_mm"], VOXEL)
    for i, j, k in CHOSEN:
        lps = itk_point(i, j, k)
        index = np.rint((lps - np.array(layout["origin_mm"])) / np.array(layout["voxel_mm"])).astype(int)
        assert np.allclose(np.array(layout["origin_mm"]) + index * np.array(layout["voxel_mm"]), lps, atol=1e-9)
        assert back[index[2], index[1], index[0]] == v[k, j, i]
    # Files of earlier ctk builds said RAS for the holder frame: read as written, as before.
    write_nrrd(tmp_path / "old-ctk.nrrd", v, "right-anterior-superior",
               [(VOXEL[0], 0, 0), (0, VOXEL[1], 0), (0, 0, VOXEL[2])], ORIGIN,
               comment="# written by ctk (run x): holder frame, millimetres\n")
    back, layout = ctk.read_volume(tmp_path / "old-ctk.nrrd")
    assert np.array_equal(back, v) and np.allclose(layout["origin_mm"], ORIGIN)
