"""Ten real views of a walnut (CWI FleX-ray, the dataset's calibrated cone_vec geometry):
the edge-preserving Huber penalty against the quadratic gradient penalty, at equal noise.

Both penalties run in the same solver (OS-SQS, Poisson weights, non-negative) over a range of
weights. For each reconstruction: the noise, the standard deviation in eight cubes of air at the
volume's corners (outside the nut), and the sharpness, the mean gradient magnitude over the
steepest 1 % of the voxels inside the nut (its shell's and kernel's faces). A lighter weight
gives more noise and sharper faces, so each penalty traces a curve of sharpness against noise;
the comparison reads the Huber curve at the noise of each quadratic reconstruction (linear in the
logarithm of the noise between the Huber points around it). The Huber delta follows the rule of
the simulated benchmarks, a quarter of the smallest contrast to keep: here the nut against the
air, the median of the nut's voxels in the lightest quadratic reconstruction.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/walnut_penalties.py --ctk build/tools/ctk \
        [--data ../shared/data/real/walnut4-tubeV1-10views] [--out benchmarks/results] [--pictures docs/real-data]

Writes <out>/walnut_penalties-<cpu>.json and, with --pictures, the slices side by side at equal
noise (walnut-penalties.png) and the two curves (walnut-penalties-curves.png)."""
import argparse
import json
import pathlib
import subprocess
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import ctk  # noqa: E402
from diagnosis_population import cpu_name, cpu_slug  # noqa: E402

FILES = [6 + 110 * m for m in range(10)]  # file k pairs with geometry row 1200 - k
SHAPE, VOXEL_MM = (128, 128, 128), 0.35
WEIGHTS = [2.0, 8.0, 32.0, 128.0, 512.0, 2048.0]


def import_walnut(ctk_command, data, folder):
    scan = folder / "scan.json"
    subprocess.run([ctk_command, "import", "cone-vec", "--out", str(scan), "--vectors", str(data / "scan_geom_corrected.geom"),
                    "--vector-rows", *[str(1200 - k) for k in FILES],
                    "--files", *[str(data / f"scan_{k:06d}.tif") for k in FILES],
                    "--flat", str(data / "io000000.tif"), str(data / "io000001.tif"), "--dark", str(data / "di000000.tif"),
                    "--detector", "768", "972", "--orientation", "transpose-flipud", "--bin", "2"],
                   check=True, stdout=subprocess.DEVNULL)
    return scan


def gradient_magnitude(x):
    gz, gy, gx = np.gradient(x.astype(np.float64), VOXEL_MM)
    return np.sqrt(gx * gx + gy * gy + gz * gz)


def air_cubes(shape, side=12, margin=4):
    """Eight cubes of side voxels at the corners, `margin` voxels in from the faces."""
    cubes = []
    for z in (margin, shape[0] - margin - side):
        for y in (margin, shape[1] - margin - side):
            for x in (margin, shape[2] - margin - side):
                cubes.append((slice(z, z + side), slice(y, y + side), slice(x, x + side)))
    return cubes


def figures(x, nut, cubes):
    noise = float(np.mean([np.std(x[c]) for c in cubes]))
    g = gradient_magnitude(x)[nut]
    steepest = g[g >= np.percentile(g, 99)]
    return noise, float(np.mean(steepest))


def huber_at_noise(noise, huber_points):
    """Huber's sharpness at `noise`, linear in log noise between its points (None outside them)."""
    pts = sorted(huber_points)
    for (n0, s0), (n1, s1) in zip(pts, pts[1:]):
        if n0 <= noise <= n1:
            f = (np.log(noise) - np.log(n0)) / (np.log(n1) - np.log(n0))
            return s0 + f * (s1 - s0)
    return None


def main():
    a = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    a.add_argument("--ctk", default="build/tools/ctk")
    a.add_argument("--data", type=pathlib.Path,
                   default=pathlib.Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "real" / "walnut4-tubeV1-10views")
    a.add_argument("--epochs", type=int, default=20)
    a.add_argument("--out", type=pathlib.Path, default=pathlib.Path("benchmarks/results"))
    a.add_argument("--pictures", type=pathlib.Path)
    args = a.parse_args()

    with tempfile.TemporaryDirectory() as tmp:
        m = ctk.load_measurements(import_walnut(args.ctk, args.data, pathlib.Path(tmp)))
    A = m.projector(SHAPE, VOXEL_MM)
    solve = lambda lam, delta: ctk.os_sqs(A, m.line_integrals, weights=m.weights, epochs=args.epochs, subsets=2, lambda_=lam,
                                          regulariser="gradient", huber_delta=delta).x

    lightest = solve(WEIGHTS[0], 0.0)
    nut = lightest > 0.5 * np.percentile(lightest, 99)  # the shell and the kernel
    delta = 0.25 * float(np.median(lightest[nut]))
    cubes = air_cubes(SHAPE)
    runs = {"quadratic": [], "huber": []}
    volumes = {}
    for name, d in (("quadratic", 0.0), ("huber", delta)):
        for lam in WEIGHTS:
            x = lightest if (name == "quadratic" and lam == WEIGHTS[0]) else solve(lam, d)
            noise, sharpness = figures(x, nut, cubes)
            runs[name].append({"lambda": lam, "noise_per_mm": noise, "sharpness_per_mm2": sharpness})
            volumes[(name, lam)] = x
            print(f"{name:9s} lambda {lam:7.0f}: noise {noise:.5f} /mm, sharpness {sharpness:.5f} /mm^2", flush=True)

    huber_points = [(r["noise_per_mm"], r["sharpness_per_mm2"]) for r in runs["huber"]]
    at_equal_noise = []
    for r in runs["quadratic"]:
        h = huber_at_noise(r["noise_per_mm"], huber_points)
        if h is not None:
            at_equal_noise.append({"lambda": r["lambda"], "noise_per_mm": r["noise_per_mm"], "quadratic_sharpness": r["sharpness_per_mm2"],
                                   "huber_sharpness": h, "ratio": h / r["sharpness_per_mm2"]})
            print(f"at the noise of quadratic lambda {r['lambda']:.0f} ({r['noise_per_mm']:.5f}): sharpness Huber {h:.5f}, "
                  f"quadratic {r['sharpness_per_mm2']:.5f}, ratio {h / r['sharpness_per_mm2']:.3f}")

    cpu = cpu_name()
    result = {"cpu": cpu, "data": "walnut4-tubeV1-10views (10 real views, binned 2 x 2)", "volume": list(SHAPE),
              "voxel_mm": VOXEL_MM, "solver": f"OS-SQS, {args.epochs} epochs, 2 subsets, Poisson weights, non-negative",
              "huber_delta_per_mm": delta, "nut_voxels": int(nut.sum()), "runs": runs, "at_equal_noise": at_equal_noise}
    args.out.mkdir(parents=True, exist_ok=True)
    file = args.out / f"walnut_penalties-{cpu_slug()}.json"
    file.write_text(json.dumps(result, indent=1) + "\n")
    print(f"written: {file}")

    if args.pictures:
        args.pictures.mkdir(parents=True, exist_ok=True)
        # Side by side at equal noise: the quadratic weight in the middle of the matched range and
        # the Huber weight whose noise is nearest to it.
        q = at_equal_noise[len(at_equal_noise) // 2] if at_equal_noise else runs["quadratic"][2]
        h = min(runs["huber"], key=lambda r: abs(np.log(r["noise_per_mm"] / q["noise_per_mm"])))
        xq, xh = volumes[("quadratic", q["lambda"])], volumes[("huber", h["lambda"])]
        top = float(np.percentile(xq[nut], 99.5))
        fig, axes = plt.subplots(2, 2, figsize=(9, 9))
        for row, (x, title) in enumerate(((xq, f"quadratic, lambda {q['lambda']:.0f}, noise {q['noise_per_mm']:.4f}"),
                                          (xh, f"Huber, lambda {h['lambda']:.0f}, noise {h['noise_per_mm']:.4f}"))):
            for col, (image, plane) in enumerate(((x[SHAPE[0] // 2], "axial"), (x[:, SHAPE[1] // 2], "coronal"))):
                ax = axes[row][col]
                ax.imshow(image, cmap="gray", vmin=0, vmax=top, origin="lower")
                ax.set_title(f"{title}\n{plane}", fontsize=9)
                ax.axis("off")
        fig.suptitle("Walnut, 10 real views: quadratic against Huber penalty at equal noise in the air")
        fig.savefig(args.pictures / "walnut-penalties.png", dpi=90, bbox_inches="tight")
        fig, ax = plt.subplots(figsize=(6, 4))
        for name, marker in (("quadratic", "o-"), ("huber", "s-")):
            ax.plot([r["noise_per_mm"] for r in runs[name]], [r["sharpness_per_mm2"] for r in runs[name]], marker, label=name)
        ax.set_xscale("log")
        ax.set_xlabel("noise in the air (1/mm, std)")
        ax.set_ylabel("sharpness (mean of the steepest 1 % of |grad|, 1/mm^2)")
        ax.legend()
        ax.grid(alpha=0.3)
        fig.savefig(args.pictures / "walnut-penalties-curves.png", dpi=90, bbox_inches="tight")
        print(f"pictures: {args.pictures / 'walnut-penalties.png'}, walnut-penalties-curves.png")


if __name__ == "__main__":
    main()
