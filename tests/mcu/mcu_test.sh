#!/bin/sh
# mcu_test.sh -- driver of the MCU / flight-rule CTest tests (tests/mcu).
#
#   mcu_test.sh build            <cpu> <dir> [config.cmake] [vectors.c]
#   mcu_test.sh symbols          <cpu> <dir>
#   mcu_test.sh symbols-selftest <cpu> <dir>
#   mcu_test.sh stack            <cpu> <dir>
#   mcu_test.sh stack-selftest   <cpu> <dir>
#   mcu_test.sh qemu             <cpu> <dir>
#
# <cpu> is cortex-m0 or cortex-m4, <dir> the cross sub-build directory.
# Exit 77 (CTest SKIP_RETURN_CODE) with a reason when a tool is missing.
set -u
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
ACTION=${1:?action}
CPU=${2:?cpu}
DIR=${3:?build dir}
PREFIX=${CT_ARM_PREFIX:-arm-none-eabi-}
QEMU=${CT_QEMU:-qemu-system-arm}
TIMEOUT=${CT_QEMU_TIMEOUT:-300}

skip() {
    echo "SKIPPED: $*"
    exit 77
}

need_arm() {
    for t in gcc nm objdump size ar; do
        command -v "${PREFIX}$t" >/dev/null 2>&1 || skip "${PREFIX}$t not found (install gcc-arm-none-eabi; scripts/deps.sh)"
    done
}

need_python() {
    if [ -x /usr/bin/python3 ]; then PY=/usr/bin/python3
    elif command -v python3 >/dev/null 2>&1; then PY=$(command -v python3)
    else skip "python3 not found"; fi
}

need_built() {
    [ -f "$DIR/libconetrace.a" ] || { echo "FAIL: $DIR/libconetrace.a missing: mcu_build_* did not build"; exit 1; }
}

case "$CPU" in
cortex-m0) MACHINE=mps2-an385 ;; # Cortex-M3 board: runs the ARMv6-M code
cortex-m4) MACHINE=mps2-an386 ;;
*) echo "unknown cpu $CPU"; exit 2 ;;
esac

case "$ACTION" in
build)
    need_arm
    CONFIG=${4:-}
    VECTORS=${5:-}
    command -v cmake >/dev/null 2>&1 || skip "cmake not found"
    if [ -n "$VECTORS" ] && [ ! -f "$VECTORS" ]; then
        echo "FAIL: $VECTORS missing: build the host project first (target mcu_vectors)"; exit 1
    fi
    set -- -S "$HERE/cross" -B "$DIR" -DCMAKE_TOOLCHAIN_FILE="$ROOT/cmake/arm-none-eabi.cmake" -DCT_MCU_CPU="$CPU"
    [ -n "$CONFIG" ] && set -- "$@" -DCT_MCU_CONFIG="$CONFIG"
    [ -n "$VECTORS" ] && set -- "$@" -DCT_MCU_VECTORS="$VECTORS"
    cmake "$@" >"$DIR.configure.log" 2>&1 || { cat "$DIR.configure.log"; echo "FAIL: configure of the $CPU sub-build"; exit 1; }
    cmake --build "$DIR" || { echo "FAIL: $CPU cross build (flight flags, -Werror)"; exit 1; }
    echo "conetrace $CPU (-std=c99 -ffreestanding -Os, soft-float): library section sizes in bytes"
    "${PREFIX}size" -t "$DIR/libconetrace.a"
    ;;
symbols)
    need_arm; need_python; need_built
    exec "$PY" "$HERE/check_symbols.py" --nm "${PREFIX}nm" --objdump "${PREFIX}objdump" \
        --image "$DIR/stack_image.elf" "$DIR/libconetrace.a"
    ;;
symbols-selftest)
    need_arm; need_python; need_built
    exec "$PY" "$HERE/check_symbols.py" --nm "${PREFIX}nm" --objdump "${PREFIX}objdump" \
        --expect heap,stdio,float,testhook "$DIR/libbad_flight.a"
    ;;
stack)
    need_arm; need_python; need_built
    exec "$PY" "$HERE/stack_report.py" --cpu "$CPU" --header "$ROOT/lib/include/conetrace.h" \
        --ci "$DIR/CMakeFiles/conetrace_mcu.dir" --lib "$DIR/libconetrace.a" --elf "$DIR/stack_image.elf" \
        --objdump "${PREFIX}objdump"
    ;;
stack-selftest)
    need_arm; need_python; need_built
    exec "$PY" "$HERE/stack_report.py" --cpu "$CPU" --roots ct_bad_fib,ct_bad_dynamic,ct_bad_indirect,ct_bad_fine \
        --ci "$DIR/CMakeFiles/bad_stack.dir" --lib "$DIR/libbad_stack.a" --objdump "${PREFIX}objdump" \
        --expect recursion,dynamic,indirect
    ;;
qemu)
    need_arm
    command -v "$QEMU" >/dev/null 2>&1 || skip "$QEMU not found (install qemu-system-arm)"
    ELF="$DIR/mcu_test.elf"
    [ -f "$ELF" ] || { echo "FAIL: $ELF missing (no vectors given to the $CPU sub-build?)"; exit 1; }
    LOG="$DIR/qemu.log"
    echo "$QEMU -M $MACHINE -nographic -monitor none -serial null -semihosting-config enable=on,target=native -kernel $ELF"
    if command -v timeout >/dev/null 2>&1; then T="timeout $TIMEOUT"; else T=""; fi
    $T "$QEMU" -M "$MACHINE" -nographic -monitor none -serial null \
        -semihosting-config enable=on,target=native -kernel "$ELF" >"$LOG" 2>&1
    rc=$?
    cat "$LOG"
    if [ $rc -eq 124 ]; then echo "FAIL: qemu timed out after ${TIMEOUT}s"; exit 1; fi
    if [ $rc -ne 0 ]; then echo "FAIL: qemu exit status $rc (semihosting SYS_EXIT reported failure or a fault)"; exit 1; fi
    grep -q "^mcu_vectors\[$CPU\]: PASS" "$LOG" || { echo "FAIL: no PASS summary from the target"; exit 1; }
    if grep -q MISMATCH "$LOG"; then echo "FAIL: mismatches reported"; exit 1; fi
    # the stack used on the target must stay within the static bound
    need_python
    "$PY" "$HERE/stack_report.py" --cpu "$CPU" --header "$ROOT/lib/include/conetrace.h" \
        --ci "$DIR/CMakeFiles/conetrace_mcu.dir" --lib "$DIR/libconetrace.a" --elf "$DIR/stack_image.elf" \
        --objdump "${PREFIX}objdump" --check-measured "$LOG" >"$DIR/stack_measured.log" 2>&1
    rc=$?
    grep -v '^ \|^worst-case' "$DIR/stack_measured.log"
    [ $rc -eq 0 ] || { echo "FAIL: measured stack use above the static worst case"; exit 1; }
    echo "mcu_qemu $CPU on $MACHINE: ok"
    ;;
*)
    echo "unknown action $ACTION"; exit 2 ;;
esac
