#!/bin/sh
# make demo: the main job on the bundled real DEM (fixtures/jacksboro_fault_dem.tif,
# fixtures/README.md): package it, geolocate a grid of a wide-angle camera's
# pixels (fixtures/scenes/wide_opencv8: OPENCV8 lens, 1.8 km up, 45 deg down
# towards the south-east) with the effects a 10 cm tolerance calls for (here
# curvature and refraction: the true Earth), and draw what it sees:
# $OUT/footprint.png, the pixels in $OUT/pixels.csv.
set -eu
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${CT_DEMO_DIR:-$BUILD/demo}
exec "$BUILD/host_tools/conetrace" demo "$ROOT/fixtures/jacksboro_fault_dem.tif" \
    --camera "$ROOT/fixtures/scenes/wide_opencv8.cameramodel" --tolerance 0.1 -o "$OUT"
