#!/bin/sh
# clang_build.sh -- compile every flight-library source with clang:
# -std=c99 -ffreestanding, the project's warning set and -Werror, for the
# host and (when clang has the Arm backend) for thumbv6m / thumbv7em.
#
#   clang_build.sh <out-dir> <include-dir> <src-dir> "<warnings>" <sources...>
set -u
OUT=${1:?out dir}
INC=${2:?include dir}
SRC=${3:?src dir}
WARN=${4:?warnings}
shift 4
case " $WARN " in *" -Werror "*) ;; *) WARN="$WARN -Werror" ;; esac
CLANG=${CT_CLANG:-clang}
command -v "$CLANG" >/dev/null 2>&1 || { echo "SKIPPED: $CLANG not found"; exit 77; }
[ $# -gt 0 ] || { echo "FAIL: no sources given"; exit 1; }
mkdir -p "$OUT"
"$CLANG" --version | head -n 1
fail=0
n=0
done_targets=""
for target in host thumbv6m-none-eabi thumbv7em-none-eabi; do
    if [ "$target" = host ]; then TFLAGS=""; else
        TFLAGS="--target=$target -mfloat-abi=soft"
        # skip cross targets only if this clang has no Arm backend at all
        echo 'int x;' | "$CLANG" $TFLAGS -x c -c -o /dev/null - 2>/dev/null || {
            echo "note: $CLANG cannot target $target; host only"; continue; }
    fi
    done_targets="$done_targets $target"
    for src in "$@"; do
        obj="$OUT/$target-$(basename "$src" .c).o"
        # shellcheck disable=SC2086
        if "$CLANG" $TFLAGS -std=c99 -ffreestanding -O2 $WARN -I"$INC" -I"$SRC" -c "$src" -o "$obj"; then
            n=$((n + 1))
        else
            echo "FAIL: clang ($target) $src"
            fail=1
        fi
    done
done
if [ $fail -ne 0 ]; then echo "lib_clang_build: FAIL"; exit 1; fi
echo "lib_clang_build: ok ($n compilations for$done_targets; -std=c99 -ffreestanding $WARN)"
