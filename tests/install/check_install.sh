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
echo "installed: 1 passed, 0 failed"
