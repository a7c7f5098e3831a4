"""The examples of examples/python run as a user runs them, so they cannot rot: each must finish,
draw its figure and print what it found."""
import os
import pathlib
import re
import subprocess
import sys

examples = pathlib.Path(__file__).resolve().parents[2] / "examples" / "python"


def run_example(name, *args):
    done = subprocess.run([sys.executable, str(examples / name), *args], capture_output=True, text=True, env=os.environ.copy())
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_the_pepper_example_finds_the_axis_column_and_draws_the_slices(tmp_path, real_data):
    out = run_example("pepper.py", "--data", str(real_data / "flexray-pepper-cone"), "--out", str(tmp_path),
                      "--effects", "detector_offset")
    u0 = float(re.search(r"'u0_px': ([0-9.]+)", out).group(1))
    assert abs(u0 - 119.2) < 0.3, out  # the scanner's own calibration: 119.13; conjugate rays 119.21
    assert (tmp_path / "pepper.png").stat().st_size > 10_000
    assert (tmp_path / "refined-geometry.json").exists()
    assert f"report page: {tmp_path / 'refine.html'}" in out
    for name in ("before", "after", "difference", "pattern"):
        assert (tmp_path / f"refine.{name}.png").stat().st_size > 1000, name
    assert (tmp_path / "refine.html").read_text().count("data:image/png;base64,") == 4


def test_the_walnut_example_reconstructs_ten_real_views(tmp_path, real_data):
    out = run_example("walnut.py", "--data", str(real_data / "walnut4-tubeV1-10views"), "--out", str(tmp_path), "--iterations", "6")
    inside, air = map(float, re.search(r"95th percentile ([-0-9.]+) /mm, air at the edge ([-0-9.]+)", out).groups())
    assert inside > 4 * abs(air) and inside > 0.01, out
    assert (tmp_path / "walnut.png").stat().st_size > 10_000
