"""Shared fixtures of the Python tests: the ctk command (for comparisons with the command line),
the real data folder, and a small random problem."""
import os
import pathlib
import subprocess

import numpy as np
import pytest

import ctk


@pytest.fixture(scope="session")
def ctk_command() -> str:
    return os.environ["CTK_COMMAND"]


@pytest.fixture(scope="session")
def real_data() -> pathlib.Path:
    return pathlib.Path(os.environ["CTK_REAL_DATA"])


def orbit_matrices(views: int, detector_shape=(40, 56), sod=300.0, sdd=600.0, tilt_deg=0.0) -> np.ndarray:
    """Views of a circle about the holder's z axis (tilted out of plane by tilt_deg), principal
    point at the detector centre, 1 mm pixels."""
    rows, cols = detector_shape
    K = np.array([[sdd, 0, (cols - 1) / 2], [0, sdd, (rows - 1) / 2], [0, 0, 1.0]])
    out = []
    t = np.radians(tilt_deg)
    for a in np.linspace(0, 2 * np.pi, views, endpoint=False):
        beam = np.array([np.cos(a) * np.cos(t), np.sin(a) * np.cos(t), np.sin(t)])  # from the source to the holder
        z = beam
        x = np.cross([0, 0, 1.0], z)
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        R = np.vstack([x, y, z])
        out.append(K @ np.hstack([R, np.array([[0], [0], [sod]])]))
    return np.array(out)


@pytest.fixture
def small_projector() -> ctk.Projector:
    return ctk.Projector(orbit_matrices(24, tilt_deg=20), (18, 20, 22), voxel_mm=1.5, detector_shape=(40, 56))


def run(command, cwd=None) -> str:
    """Runs a command, failing the test with its output when it fails."""
    done = subprocess.run(command, cwd=cwd, capture_output=True, text=True)
    assert done.returncode == 0, f"{command} failed:\n{done.stdout}\n{done.stderr}"
    return done.stdout
