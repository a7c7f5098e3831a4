#!/bin/sh
# ctk installed as a lab installs it: `cmake --install` into a prefix, then a project of its own
# (tests/install/consumer) finds it with find_package(ctk), builds against it and runs; and the
# Debian package CPack makes installs (into a root of its own, with a dpkg database of its own, so
# the machine's is untouched) and its `ctk --version` runs.  Usage: check_install.sh BUILD SOURCE
set -eu
build=$1
source=$2
work=$PWD/install-check
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
test -f "$work/prefix/lib/cmake/ctk/ctkConfig.cmake"
cmake -S "$source/tests/install/consumer" -B "$work/consumer" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release \
  > "$work/configure.log"
cmake --build "$work/consumer" -j 2 > "$work/build.log"
"$work/consumer/ctk_consumer"
(cd "$build" && cpack -G DEB -B "$work/package" > "$work/cpack.log")
deb=$(ls "$work"/package/ctk_*.deb)
depends=$(dpkg-deb -f "$deb" Depends)
echo "package $(basename "$deb"), depends on: $depends"
case "$depends" in *libopenimageio*) ;; *) echo "FAIL: the package does not name its run-time libraries"; exit 1 ;; esac
mkdir -p "$work/root" "$work/dpkg/updates" "$work/dpkg/info"
touch "$work/dpkg/status" "$work/dpkg/available"
dpkg --instdir="$work/root" --admindir="$work/dpkg" --log=/dev/null --force-depends --force-not-root --force-script-chrootless \
  -i "$deb" > "$work/dpkg.log" 2>&1
"$work/root/usr/bin/ctk" --version
# EXR goes through the OpenImageIO module the package puts in /usr/lib/ctk.
"$work/root/usr/bin/ctk" simulate --out "$work/exr" --views 2 --cols 16 --rows 16 --pitch 24 --output line-integrals > /dev/null
test -s "$work/exr/projections/proj_0001.exr"
test -f "$work/root/usr/lib/ctk/libctk_image_codec_oiio.so"
# The Python module where Debian's python3 looks without PYTHONPATH: under /usr (the package) in
# lib/python3/dist-packages, under the default prefix /usr/local in lib/python3.X/dist-packages.
python=/usr/bin/python3
if [ -x "$python" ] && ls "$build"/python/ctk/_ctk*.so > /dev/null 2>&1; then
  site=$("$python" -c 'import sys; print("/usr/local/lib/python%d.%d/dist-packages" % sys.version_info[:2])')
  "$python" -c "import sys; sys.exit(0 if '$site' in sys.path and '/usr/lib/python3/dist-packages' in sys.path else 1)" ||
    { echo "FAIL: $site or /usr/lib/python3/dist-packages is not on $python's default path"; exit 1; }
  ls "$work"/root/usr/lib/python3/dist-packages/ctk/_ctk*.so > /dev/null ||
    { echo "FAIL: the package does not put the module in /usr/lib/python3/dist-packages"; exit 1; }
  DESTDIR="$work/stage" cmake --install "$build" --prefix /usr/local > "$work/install-local.log"
  ls "$work/stage$site"/ctk/_ctk*.so > /dev/null ||
    { echo "FAIL: cmake --install --prefix /usr/local does not put the module in $site"; exit 1; }
  # Imported from there (the staged copy standing for the installed one) it is the build's module.
  PYTHONPATH="$work/stage$site" "$python" -c "import ctk, sys; assert ctk.__file__.startswith('$work/stage'), ctk.__file__; print('python module: ' + ctk.__version__)"
fi
echo "installed: 1 passed, 0 failed"
