#!/bin/sh
# bench_m4.sh -- instructions per ray on Cortex-M4, per method and ray family
# (bench/m4/bench_m4.c under qemu mps2-an386 with -icount), over the fixture
# package at N = 24, r = 3 and ct_bench's ray families (100 per family);
# then instructions per pixel of ct_geolocate (directional) for 64 pixels of
# an oblique camera over that package: straight, curvature + refraction on
# the sphere, and on the true Earth, exact and with its map fitted per call
# (mean, min-max, per pixel in a batch,
# and the per-call set-up).  Each ray's and pixel's status, steps (and hit)
# must equal the host's, else exit status 1.  Run by `make bench`.
#
#   scripts/bench_m4.sh <build-dir> [rays-per-family]
# Environment: CT_M4_OPT (default -Os, as the flight builds of make cross).
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
. "$ROOT/scripts/m4_common.sh"
BUILD=${1:-$ROOT/build}
N=${2:-100}
if ! m4_tools; then
    echo "bench_m4: ${PREFIX}gcc or $QEMU not found (scripts/deps.sh installs them); skipped"
    exit 0
fi
GEN="$BUILD/bench/ct_gen_m4_data"
[ -x "$GEN" ] || { echo "bench_m4: $GEN missing (build the project first)" >&2; exit 1; }
OUT="$BUILD/bench/m4"
mkdir -p "$OUT"
"$GEN" "$OUT/bench_m4_data.c" "$N" || { echo "bench_m4: ct_gen_m4_data failed" >&2; exit 1; }
m4_link "$OUT/bench_m4.elf" "$ROOT/bench/m4/bench_m4.c" "$OUT/bench_m4_data.c" ||
    { echo "bench_m4: Cortex-M4 build failed" >&2; exit 1; }
printf "bench_m4: %s build, %s rays per family\n" "$OPT" "$N"
m4_run 600 "$OUT/bench_m4.elf"
