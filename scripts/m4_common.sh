# m4_common.sh -- sourced by bench_m4.sh and profile_m4.sh (ROOT set): the
# Cortex-M4 cross compiler and qemu, and the flight build of lib/ with a
# bench's main for qemu's mps2-an386.
#   CT_ARM_PREFIX  the cross compiler's prefix (arm-none-eabi-)
#   CT_QEMU        qemu-system-arm
#   CT_M4_OPT      the optimisation (-Os, as the flight builds of make cross)
PREFIX=${CT_ARM_PREFIX:-arm-none-eabi-}
QEMU=${CT_QEMU:-qemu-system-arm}
OPT=${CT_M4_OPT:--Os}
M4_FLAGS="-mcpu=cortex-m4 -mthumb -mfloat-abi=soft -std=c99 -ffreestanding $OPT -Wall -Wextra -Werror -fno-builtin -fno-tree-loop-distribute-patterns"

# 0 when both tools are there
m4_tools() {
    command -v "${PREFIX}gcc" >/dev/null 2>&1 && command -v "$QEMU" >/dev/null 2>&1
}

# m4_link ELF MAIN DATA [compiler flags...]: startup, MAIN, the baked DATA
# and every lib/src file, linked for mps2-an386
m4_link() {
    m4_elf=$1
    m4_main=$2
    m4_data=$3
    shift 3
    "${PREFIX}gcc" $M4_FLAGS "$@" -I"$ROOT/lib/include" -I"$ROOT/lib/src" -I"$ROOT/tests/mcu" -I"$ROOT/bench/m4" \
        -nostdlib -nostartfiles -T"$ROOT/tests/mcu/mps2.ld" -Wl,--gc-sections \
        "$ROOT/tests/mcu/startup.c" "$m4_main" "$m4_data" "$ROOT"/lib/src/*.c -lgcc -o "$m4_elf"
}

# m4_run SECONDS ELF [qemu options...]: run it with -icount (one instruction
# per virtual tick), its semihosting output on stdout
m4_run() {
    m4_t=$1
    m4_elf=$2
    shift 2
    timeout "$m4_t" "$QEMU" -M mps2-an386 -icount shift=0 -nographic -monitor none -serial null \
        -semihosting-config enable=on,target=native -kernel "$m4_elf" "$@"
}
