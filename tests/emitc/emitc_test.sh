#!/bin/sh
# emitc_test.sh -- the package emitted as C (conetrace build --emit-c) linked
# into a small program for the host and for Cortex-M4 (qemu, mps2-an386):
#   emitc_test.sh <host program> <package.ctp> <emitted dir> <root> <lib sources...>
# Checks: the host program's line says PASS and names the package file's
# size and CRC; the Cortex-M4 build prints the very same line.
set -u
HOSTPROG=$1 PKG=$2 DIR=$3 ROOT=$4
shift 4
PREFIX=${CT_ARM_PREFIX:-arm-none-eabi-}
QEMU=${CT_QEMU:-qemu-system-arm}
line=$("$HOSTPROG") || { echo "FAIL: host program: $line"; exit 1; }
echo "host:        $line"
size=$(printf '%08x' "$(wc -c <"$PKG")")
crc=$(od -An -tx1 -j12 -N4 "$PKG" | awk '{print $4 $3 $2 $1}')
case "$line" in
*"size 0x$size crc 0x$crc "*PASS) ;;
*) echo "FAIL: expected size 0x$size crc 0x$crc and PASS"; exit 1 ;;
esac
if ! command -v "${PREFIX}gcc" >/dev/null 2>&1 || ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "SKIPPED: ${PREFIX}gcc or $QEMU not found (the Cortex-M4 half)"; exit 77
fi
M="$ROOT/tests/mcu"
FLAGS="-mcpu=cortex-m4 -mthumb -mfloat-abi=soft -std=c99 -ffreestanding -Os -Wall -Wextra -Werror"
"${PREFIX}gcc" $FLAGS -I"$ROOT/lib/include" -I"$ROOT/lib/src" -I"$M" -I"$DIR" \
    -nostdlib -nostartfiles -T"$M/mps2.ld" -Wl,--gc-sections \
    "$M/startup.c" "$ROOT/tests/emitc/emitc_main.c" "$DIR/terrain_pkg.c" "$@" -lgcc \
    -o "$DIR/emitc_m4.elf" || { echo "FAIL: Cortex-M4 build"; exit 1; }
"${PREFIX}size" "$DIR/emitc_m4.elf"
arm=$(timeout 300 "$QEMU" -M mps2-an386 -nographic -monitor none -serial null \
    -semihosting-config enable=on,target=native -kernel "$DIR/emitc_m4.elf" 2>&1)
rc=$?
echo "cortex-m4:   $arm"
[ $rc -eq 0 ] || { echo "FAIL: qemu exit status $rc"; exit 1; }
[ "$arm" = "$line" ] || { echo "FAIL: the Cortex-M4 line differs from the host's"; exit 1; }
echo "emitc: host and Cortex-M4 agree"
