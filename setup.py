"""`pip install .`: the ctk Python module built by the project's own CMake (pyproject.toml).

The extension and the image codec module it loads on first use are built by CMake for the
interpreter running pip, then put into the wheel beside the package's Python files, so the
installed package finds its codec where the library looks first (beside the module).
"""

import os
import re
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = Path(__file__).resolve().parent


def project_version() -> str:
    text = (SOURCE / "CMakeLists.txt").read_text()
    match = re.search(r"project\(ctk VERSION ([0-9.]+)", text)
    if not match:
        raise RuntimeError("CMakeLists.txt: no `project(ctk VERSION ...)` line")
    return match.group(1)


class CMakeBuild(build_ext):
    """Configures (unless CTK_BUILD_DIR names a configured tree) and builds the `_ctk` target."""

    def build_extension(self, ext: Extension) -> None:
        tree = os.environ.get("CTK_BUILD_DIR")
        build = Path(tree).resolve() if tree else Path(self.build_temp).resolve() / "cmake"
        if not tree:
            build.mkdir(parents=True, exist_ok=True)
            subprocess.run(
                ["cmake", "-S", str(SOURCE), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release", "-DCTK_BUILD_TESTS=OFF",
                 f"-DPython3_EXECUTABLE={sys.executable}"],
                check=True)
        jobs = str(os.cpu_count() or 1)
        subprocess.run(["cmake", "--build", str(build), "--target", "_ctk", "-j", jobs], check=True)
        built = sorted((build / "python" / "ctk").glob("_ctk*.so"))
        codec = sorted(build.rglob("libctk_image_codec_oiio.so"))
        if not built or not codec:
            raise RuntimeError(f"{build}: the build made no python/ctk/_ctk*.so or libctk_image_codec_oiio.so")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        self.copy_file(str(built[0]), str(target))
        self.copy_file(str(codec[0]), str(target.parent / codec[0].name))


# setuptools' scratch folders inside the git-ignored build area, not beside the sources.
scratch = SOURCE / "build" / "setuptools"
scratch.mkdir(parents=True, exist_ok=True)
setup(
    version=project_version(),
    ext_modules=[Extension("ctk._ctk", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    options={"build": {"build_base": str(scratch)}, "egg_info": {"egg_base": str(scratch)}},
)
