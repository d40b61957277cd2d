#!/bin/sh
# Install the Debian packages conetrace needs, if any is missing.
# Runs apt-get as root, or through sudo.  Idempotent and quiet when all present.
set -e
PKGS="cmake make ninja-build g++ gcc clang libclang-rt-14-dev valgrind
      libopenimageio-dev libgeotiff-dev libtiff-dev libpng-dev
      gcc-arm-none-eabi libnewlib-arm-none-eabi qemu-system-arm
      libembree-dev python3-numpy python3-mpmath python-matplotlib-data python3-matplotlib
      libmrcal-dev python3-opencv pkg-config gcovr libproj-dev proj-data
      libgdal-dev gdal-bin python3-gdal"
missing=""
for p in $PKGS; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
done
[ -z "$missing" ] && exit 0
echo "deps: installing:$missing"
if [ "$(id -u)" -eq 0 ]; then SUDO=""; elif command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
  echo "deps: need root or sudo to install:$missing" >&2; exit 1; fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
# shellcheck disable=SC2086
$SUDO apt-get install -y -qq --no-install-recommends $missing
