#!/bin/sh
# install_example.sh -- the library as flight software takes it: installed
# with `cmake --install`, found by find_package(conetrace) and by pkg-config,
# and examples/firmware built against the installed prefix and run -- on the
# host, and for Cortex-M4 (the library built on its own with the toolchain
# file, the program run under qemu mps2-an386), where its output must equal
# the host's byte for byte.
#
#   tests/install_example.sh <build-dir>
# Exit 0: pass; 1: fail; the Cortex-M part is skipped (and said so) without
# the cross tools.
set -u
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=$(cd "$1" && pwd)
W=$(mktemp -d /tmp/ct_install_XXXXXX)
trap 'rm -rf "$W"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
run() { "$@" >"$W/log" 2>&1 || { cat "$W/log"; fail "$*"; }; }

# 1. install the library from the project's build
run cmake --install "$BUILD" --prefix "$W/host"
for f in include/conetrace.h lib/libconetrace.a lib/cmake/conetrace/conetraceConfig.cmake \
         lib/cmake/conetrace/conetraceConfigVersion.cmake lib/pkgconfig/conetrace.pc; do
    [ -f "$W/host/$f" ] || fail "cmake --install did not install $f"
done
echo "installed: $(cd "$W/host" && find . -type f | sort | tr '\n' ' ')"

# 2. a terrain package as C source (the CLI of the same build)
mkdir -p "$W/pkg"
run "$BUILD/host_tools/conetrace" build "$ROOT/fixtures/jacksboro_fault_dem.tif" -o "$W/pkg/pkg.ctp" \
    --sectors 8 --reduce 8 --emit-c ct_example_pkg
PKG_C="$W/pkg/ct_example_pkg.c"

# 3. the example through find_package, on the host
run cmake -S "$ROOT/examples/firmware" -B "$W/ex_host" -DCMAKE_PREFIX_PATH="$W/host" -DEXAMPLE_PACKAGE_C="$PKG_C"
run cmake --build "$W/ex_host"
"$W/ex_host/geoloc_example" >"$W/out_host.txt" 2>&1 || { cat "$W/out_host.txt"; fail "the host example failed"; }
cat "$W/out_host.txt"
grep -q "^example: ok$" "$W/out_host.txt" || fail "the host example did not report ok"

# 4. the same program through pkg-config
if command -v pkg-config >/dev/null 2>&1; then
    FLAGS=$(PKG_CONFIG_PATH="$W/host/lib/pkgconfig" pkg-config --cflags --libs conetrace) || fail "pkg-config"
    run cc -std=c99 -O2 -I"$W/pkg" "$ROOT/examples/firmware/main.c" "$ROOT/examples/firmware/platform_host.c" "$PKG_C" \
        $FLAGS -o "$W/ex_pc"
    "$W/ex_pc" >"$W/out_pc.txt" 2>&1
    cmp -s "$W/out_pc.txt" "$W/out_host.txt" || fail "the pkg-config build printed something else"
    echo "pkg-config build: the same output ($FLAGS)"
else
    fail "pkg-config not found (scripts/deps.sh installs it)"
fi

# 5. Cortex-M4: the library alone with the toolchain file, installed, the
#    example built against it and run under qemu
PREFIX=${CT_ARM_PREFIX:-arm-none-eabi-}
QEMU=${CT_QEMU:-qemu-system-arm}
if ! command -v "${PREFIX}gcc" >/dev/null 2>&1 || ! command -v "$QEMU" >/dev/null 2>&1; then
    echo "Cortex-M4 part skipped: ${PREFIX}gcc or $QEMU not found (scripts/deps.sh installs them)"
    exit 0
fi
TC="$ROOT/cmake/arm-none-eabi.cmake"
run cmake -S "$ROOT/lib" -B "$W/lib_m4" -DCMAKE_TOOLCHAIN_FILE="$TC" -DCT_CPU=cortex-m4
run cmake --build "$W/lib_m4"
run cmake --install "$W/lib_m4" --prefix "$W/m4"
run cmake -S "$ROOT/examples/firmware" -B "$W/ex_m4" -DCMAKE_TOOLCHAIN_FILE="$TC" -DCMAKE_PREFIX_PATH="$W/m4" \
    -DEXAMPLE_PACKAGE_C="$PKG_C" -DEXAMPLE_PLATFORM=mps2 -DEXAMPLE_MPS2_DIR="$ROOT/tests/mcu"
run cmake --build "$W/ex_m4"
timeout 300 "$QEMU" -M mps2-an386 -nographic -monitor none -serial null \
    -semihosting-config enable=on,target=native -kernel "$W/ex_m4/geoloc_example.elf" >"$W/out_m4.txt" 2>&1
rc=$?
[ $rc -eq 0 ] || { cat "$W/out_m4.txt"; fail "the Cortex-M4 example exited with $rc under qemu"; }
cmp -s "$W/out_m4.txt" "$W/out_host.txt" || { diff "$W/out_host.txt" "$W/out_m4.txt"; fail "Cortex-M4 output differs from the host's"; }
echo "Cortex-M4 (qemu mps2-an386): the same output, byte for byte"
exit 0
