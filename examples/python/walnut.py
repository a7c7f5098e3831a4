"""Ten real projections of a walnut (CWI FleX-ray, ASTRA cone_vec geometry) reconstructed by
WLS-CG from Python: vectors to 3x4 matrices, counts to line integrals with numpy, the projector
as an operator, and a figure of the central slices.

    /usr/bin/python3 examples/python/walnut.py [--data ../shared/data/real/walnut4-tubeV1-10views] [--out walnut-out]

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
parser.add_argument("--data", type=pathlib.Path, default=here.parents[1] / ".." / "shared" / "data" / "real" / "walnut4-tubeV1-10views")
parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("walnut-out"))
parser.add_argument("--iterations", type=int, default=20)
args = parser.parse_args()
logging.basicConfig(level=logging.INFO, format="%(message)s")
args.out.mkdir(parents=True, exist_ok=True)

# Geometry row 1200 - k describes file k (the dataset's own pairing); the vectors describe the
# stored image transposed and flipped: img = transpose(flipud(raw)), 972 rows x 768 columns.
files = [6 + 110 * m for m in range(10)]
vectors = ctk.read_cone_vec(args.data / "scan_geom_corrected.geom")[[1200 - k for k in files]]
detector_shape = (972, 768)
matrices = ctk.matrices_from_cone_vec(vectors, detector_shape, pixel_mm=(0.1496, 0.1496))


def stored_as_described(raw: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(np.transpose(np.flipud(raw)))


dark = stored_as_described(ctk.read_image(args.data / "di000000.tif"))
flat = stored_as_described(0.5 * (ctk.read_image(args.data / "io000000.tif") + ctk.read_image(args.data / "io000001.tif")))
counts = np.stack([stored_as_described(ctk.read_image(args.data / f"scan_{k:06d}.tif")) for k in files])
transmission = np.clip((counts - dark) / (flat - dark), 1e-3, None)
line_integrals = (-np.log(transmission)).astype(np.float32)
weights = (transmission * (flat - dark) / np.mean(flat - dark)).astype(np.float32)  # Poisson: W ~ detected counts

A = ctk.Projector(matrices, volume_shape=(96, 96, 96), voxel_mm=0.45, detector_shape=detector_shape)
result = ctk.wls_cg(A, line_integrals, weights=weights, iterations=args.iterations, lam=2.0, regulariser="gradient")
x = result.x
print(f"{len(files)} views, volume {A.volume_shape}, {result.stop_reason}; "
      f"cost {result.iterations[0]['cost']:.4g} -> {result.cost:.4g}")

# The shell and kernel attenuate; the air around the walnut does not.
middle = x[x.shape[0] // 2]
inside, outside = float(np.percentile(middle, 95)), float(np.median(middle[:, :8]))
print(f"central axial slice: 95th percentile {inside:.4f} /mm, air at the edge {outside:.4f} /mm")

fig, axes = plt.subplots(1, 3, figsize=(12, 4))
for ax, image, name in zip(axes, (x[x.shape[0] // 2], x[:, x.shape[1] // 2], x[:, :, x.shape[2] // 2]),
                           ("axial (z)", "coronal (y)", "sagittal (x)")):
    ax.imshow(image, cmap="gray", vmin=0, vmax=np.percentile(x, 99.5), origin="lower")
    ax.set_title(name)
    ax.axis("off")
fig.suptitle(f"Walnut, {len(files)} real views, WLS-CG {args.iterations} iterations (ctk from Python)")
fig.savefig(args.out / "walnut.png", dpi=100, bbox_inches="tight")
print(f"figure: {args.out / 'walnut.png'}")
