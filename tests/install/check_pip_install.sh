#!/bin/sh
# `pip install .` into a virtual environment of Debian's python3, offline (Debian's setuptools and
# numpy through --system-site-packages; the build tree reused through CTK_BUILD_DIR): then
# `import ctk` works from anywhere without PYTHONPATH, is the installed copy, names the build's
# version, and reads an EXR through the image codec the wheel put beside the module.
# Usage: check_pip_install.sh BUILD SOURCE
set -eu
build=$(cd "$1" && pwd)
source=$(cd "$2" && pwd)
work=$PWD/pip-check
rm -rf "$work"
mkdir -p "$work"
python=/usr/bin/python3
"$python" -m venv --system-site-packages "$work/env"
(cd "$source" && CTK_BUILD_DIR="$build" "$work/env/bin/pip" install --no-build-isolation --no-index . > "$work/pip.log" 2>&1) ||
  { cat "$work/pip.log"; echo "FAIL: pip install ."; exit 1; }
"$build/tools/ctk" simulate --out "$work/exr" --views 2 --cols 16 --rows 16 --pitch 24 --output line-integrals > /dev/null
cd "$work"
built=$(PYTHONPATH="$build/python" "$python" -c "import ctk; print(ctk.__version__)")
env -u PYTHONPATH -u CTK_IMAGE_CODEC "$work/env/bin/python" - "$work" "$built" <<'PY'
import sys
import ctk
work, built = sys.argv[1], sys.argv[2]
assert ctk.__file__.startswith(work + "/env/"), ctk.__file__
assert ctk.__version__ == built and "+" in built, (ctk.__version__, built)
image = ctk.read_image(work + "/exr/projections/proj_0001.exr")
assert image.shape == (16, 16), image.shape
codec = [line.split()[-1] for line in open("/proc/self/maps") if "libctk_image_codec_oiio" in line]
assert codec and all(p.startswith(work + "/env/") for p in codec), codec
print("pip-installed ctk " + ctk.__version__ + " at " + ctk.__file__ + ", codec " + codec[0])
PY
echo "pip install: 1 passed, 0 failed"
