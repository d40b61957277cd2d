#!/bin/sh
# make demo: package the bundled real DEM (fixtures/jacksboro_fault_dem.tif)
# and trace a handful of rays with every method.
set -eu
BUILD=${1:-build}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
exec "$BUILD/host_tools/conetrace" demo "$ROOT/fixtures/jacksboro_fault_dem.tif" --sectors 24 --reduce 1
