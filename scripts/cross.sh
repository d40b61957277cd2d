#!/bin/sh
# cross.sh -- cross-build the flight library for Cortex-M0 and Cortex-M4 with
# arm-none-eabi-gcc (-std=c99 -ffreestanding -Os, soft-float, the project's
# warning set, -Werror) and print, per CPU: .text/.data/.bss, the
# forbidden-symbol check and the worst-case stack of every public function.
# The same checks run under CTest as mcu_* tests (tests/mcu); this needs no
# host build and no ctest.
#
#   scripts/cross.sh <build-dir>          (make cross: build/cross)
#
# Exit status: 0 when every CPU builds and passes both checks.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
OUT=${1:-$ROOT/build/cross}
PREFIX=${CT_ARM_PREFIX:-arm-none-eabi-}
for t in gcc nm objdump size; do
    command -v "${PREFIX}$t" >/dev/null 2>&1 || {
        echo "cross.sh: ${PREFIX}$t not found (install gcc-arm-none-eabi: scripts/deps.sh)" >&2; exit 1; }
done
command -v cmake >/dev/null 2>&1 || { echo "cross.sh: cmake not found" >&2; exit 1; }
if [ -x /usr/bin/python3 ]; then PY=/usr/bin/python3; else PY=python3; fi
command -v "$PY" >/dev/null 2>&1 || { echo "cross.sh: python3 not found" >&2; exit 1; }
mkdir -p "$OUT"
OUT=$(cd "$OUT" && pwd)

status=0
SUMMARY=""
for cpu in cortex-m0 cortex-m4; do
    dir="$OUT/$cpu"
    echo "==== $cpu ===================================================================="
    if ! cmake -S "$ROOT/tests/mcu/cross" -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/arm-none-eabi.cmake" \
            -DCT_MCU_CPU="$cpu" >"$dir.configure.log" 2>&1; then
        cat "$dir.configure.log"; echo "cross.sh: $cpu: configure FAILED"; status=1; continue
    fi
    if ! cmake --build "$dir" --target conetrace_mcu stack_image >"$dir.build.log" 2>&1; then
        cat "$dir.build.log"; echo "cross.sh: $cpu: build FAILED"; status=1; continue
    fi
    grep -i 'warning' "$dir.build.log" || true
    echo "-- section sizes (bytes), arm-none-eabi-size:"
    "${PREFIX}size" -t "$dir/libconetrace.a"
    echo "-- forbidden symbols:"
    "$PY" "$ROOT/tests/mcu/check_symbols.py" --nm "${PREFIX}nm" --objdump "${PREFIX}objdump" \
        --image "$dir/stack_image.elf" "$dir/libconetrace.a" || { status=1; SUMMARY="$SUMMARY $cpu:symbols"; }
    echo "-- stack:"
    "$PY" "$ROOT/tests/mcu/stack_report.py" --cpu "$cpu" --header "$ROOT/lib/include/conetrace.h" \
        --ci "$dir/CMakeFiles/conetrace_mcu.dir" --lib "$dir/libconetrace.a" --elf "$dir/stack_image.elf" \
        --objdump "${PREFIX}objdump" || { status=1; SUMMARY="$SUMMARY $cpu:stack"; }
done
if [ $status -eq 0 ]; then
    echo "cross.sh: ok (cortex-m0, cortex-m4)"
else
    echo "cross.sh: FAILED${SUMMARY}"
fi
exit $status
