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
BUILD=${1:-$ROOT/build}
N=${2:-100}
PREFIX=${CT_ARM_PREFIX:-arm-none-eabi-}
QEMU=${CT_QEMU:-qemu-system-arm}
OPT=${CT_M4_OPT:--Os}
if ! command -v "${PREFIX}gcc" >/dev/null 2>&1 || ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "bench_m4: ${PREFIX}gcc or $QEMU not found (scripts/deps.sh installs them); skipped"
    exit 0
fi
GEN="$BUILD/bench/ct_gen_m4_data"
[ -x "$GEN" ] || { echo "bench_m4: $GEN missing (build the project first)" >&2; exit 1; }
OUT="$BUILD/bench/m4"
mkdir -p "$OUT"
"$GEN" "$OUT/bench_m4_data.c" "$N" || { echo "bench_m4: ct_gen_m4_data failed" >&2; exit 1; }
M="$ROOT/tests/mcu"
FLAGS="-mcpu=cortex-m4 -mthumb -mfloat-abi=soft -std=c99 -ffreestanding $OPT -Wall -Wextra -Werror -fno-builtin -fno-tree-loop-distribute-patterns"
"${PREFIX}gcc" $FLAGS -I"$ROOT/lib/include" -I"$ROOT/lib/src" -I"$M" -I"$ROOT/bench/m4" \
    -nostdlib -nostartfiles -T"$M/mps2.ld" -Wl,--gc-sections \
    "$M/startup.c" "$ROOT/bench/m4/bench_m4.c" "$OUT/bench_m4_data.c" "$ROOT"/lib/src/*.c -lgcc \
    -o "$OUT/bench_m4.elf" || { echo "bench_m4: Cortex-M4 build failed" >&2; exit 1; }
printf "bench_m4: %s build, %s rays per family\n" "$OPT" "$N"
timeout 600 "$QEMU" -M mps2-an386 -icount shift=0 -nographic -monitor none -serial null \
    -semihosting-config enable=on,target=native -kernel "$OUT/bench_m4.elf"
