#!/bin/sh
# fuzz.sh -- build tests/fuzz/fuzz_lib.c with clang's libFuzzer, ASan and
# UBSan over the flight library and run it.
#   tests/fuzz/fuzz.sh <build-dir> <runs> [max-seconds] [corpus-dir]
# The packages come from the MCU vectors the host build generates
# (<build-dir>/tests/mcu/ct_vectors.c).  `make test` runs 100,000 inputs from
# an empty corpus with a fixed seed (reproducible), one process; `make fuzz`
# runs long (10^7 inputs or FUZZ_SECONDS, default 2700) in libFuzzer's fork
# mode, one worker per core (FUZZ_JOBS), and keeps its corpus in
# <build-dir>/fuzz_corpus.
# Comparison tracing (-fsanitize-coverage=trace-cmp, part of
# -fsanitize=fuzzer) is left out: it took 2/3 of the time (30,000 inputs in
# 21 s against 7 s) and reached no more coverage (3,276 against 3,292
# edges after them; the harness builds valid packages itself, so there are
# no magic values to guess).
# Exit 0: no finding; 1: a finding (the crashing input is saved in
# <build-dir>/fuzz/ and printed); 77: clang's libFuzzer is not available.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=$(cd "$1" && pwd)
RUNS=${2:-100000}
SECS=${3:-0}
CORPUS=${4:-}
CC=${CT_FUZZ_CC:-clang}
OUT="$BUILD/fuzz"
VEC="$BUILD/tests/mcu/ct_vectors.c"
[ -f "$VEC" ] || { echo "fuzz: $VEC missing (build the project first)"; exit 1; }
command -v "$CC" >/dev/null 2>&1 || { echo "fuzz: $CC not found (scripts/deps.sh installs clang)"; exit 77; }
mkdir -p "$OUT"
. "$ROOT/tests/fuzz/common.sh"
fuzz_corpus "$ROOT"/tests/fuzz/corpus ct_fuzz
FLAGS="-g1 -O1 -std=c99 -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=all -fno-sanitize-coverage=trace-cmp"
if ! "$CC" $FLAGS -I"$ROOT/lib/include" -I"$ROOT/lib/src" -I"$ROOT/tests/mcu" \
        "$ROOT/tests/fuzz/fuzz_lib.c" "$VEC" "$ROOT"/lib/src/*.c -o "$OUT/fuzz_lib" 2>"$OUT/build.log"; then
    if grep -q "fuzzer" "$OUT/build.log" && ! grep -q "error:" "$OUT/build.log"; then
        echo "fuzz: libFuzzer not available"; exit 77
    fi
    cat "$OUT/build.log"; echo "fuzz: build failed"; exit 1
fi
cd "$OUT" || exit 1
fuzz_limits
./fuzz_lib $FORK -runs="$RUNS" $LIMIT -seed=1 -max_len=512 -len_control=0 -print_final_stats=1 "$CORPUS" >"$OUT/run.log" 2>&1
rc=$?
fuzz_summary "$OUT/run.log"
if [ $rc -eq 0 ] && fuzz_forked_findings "$OUT/run.log"; then
    rc=1
fi
if [ $rc -ne 0 ]; then
    tail -40 "$OUT/run.log"
    echo "fuzz: FINDING (input saved in $OUT, see run.log)"
    exit 1
fi
echo "fuzz: ok"
exit 0
