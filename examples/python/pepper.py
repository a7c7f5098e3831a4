"""A real circular scan of a pepper (CWI FleX-ray) from Python: imported from its numbers, the
markerless loop run on it (which finds where the rotation axis really projects), and a figure of
the central slice reconstructed (FDK) with the nominal and with the refined geometry.

    /usr/bin/python3 examples/python/pepper.py [--data ../shared/data/real/flexray-pepper-cone] [--out pepper-out]
                                               [--effects detector_offset ...]

(with PYTHONPATH=build/python in a build tree, or after `cmake --install`)."""
import argparse
import logging
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import ctk  # noqa: E402

here = pathlib.Path(__file__).resolve().parent
parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--data", type=pathlib.Path, default=here.parents[1] / ".." / "shared" / "data" / "real" / "flexray-pepper-cone")
parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("pepper-out"))
parser.add_argument("--effects", nargs="*", default=None, help="candidates of the loop (default: every one)")
args = parser.parse_args()
logging.basicConfig(level=logging.INFO, format="%(message)s")
args.out.mkdir(parents=True, exist_ok=True)

# The scanner's numbers (scan settings): 225 views 1.6 deg apart, 239 x 190 pixels of 0.5984 mm;
# the principal point is taken at the detector centre, which is what the loop corrects.
views = 225
matrices = ctk.circular_matrices([0.7 + 1.6 * k for k in range(views)], detector_shape=(190, 239), pixel_mm=(0.5984, 0.5984),
                                 sod=1001.305645, sdd=1098.0)
scan = ctk.import_scan(args.out / "scan.json", matrices, [args.data / f"scan_{k:05d}.tif" for k in range(views)],
                       detector_shape=(190, 239), pixel_mm=(0.5984, 0.5984), flat=[args.data / "io000000.tif"],
                       dark=[args.data / "di000000.tif"])
print(f"imported {scan['projections']['count']} views into {args.out / 'scan.json'}")

# With pictures=, the same pictures and HTML page as `ctk refine` (slices, difference, detector pattern).
result = ctk.refine(args.out / "scan.json", effects=args.effects, pictures=args.out / "refine")
print(result.brief)
print(f"report page: {result.page}")
for effect in result.accepted:
    print(f"accepted {effect['name']}: {effect['parameters']} +- {effect['uncertainty']}")
ctk.write_geometry(result.geometry, args.out / "refined-geometry.json")

high = float(np.percentile(result.slice_before, 99.8))
fig, axes = plt.subplots(1, 2, figsize=(10, 5))
for ax, image, name in zip(axes, (result.slice_before, result.slice_after), ("nominal geometry", "refined geometry")):
    ax.imshow(image, cmap="gray", vmin=0, vmax=high, origin="lower")
    ax.set_title(name)
    ax.axis("off")
fig.suptitle("Pepper, central slice (FDK): " + (", ".join(e["name"] for e in result.accepted) or "nothing") + " found by the loop")
fig.savefig(args.out / "pepper.png", dpi=100, bbox_inches="tight")
print(f"figure: {args.out / 'pepper.png'}")
