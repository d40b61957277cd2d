#!/bin/sh
# fuzz_host.sh -- build tests/fuzz/fuzz_host.cpp with clang's libFuzzer, ASan
# and UBSan over the host tools' file readers (rays and pixels CSVs, DEM
# rasters through OpenImageIO + libgeotiff, .cameramodel through libmrcal,
# the test kit's scene files) and run it.
#   tests/fuzz/fuzz_host.sh <build-dir> <runs> [max-seconds] [corpus-dir]
# The readers' sources (host_tools/) and lib/ are compiled here with the
# sanitizers; OpenImageIO, libtiff, libgeotiff and libmrcal are the system's
# (not instrumented for coverage; ASan still sees their heap).  Seeds:
# tests/fuzz/corpus_host/.  `make test` runs 100,000 inputs or 60 s from the
# seeds with a fixed seed (one process; the DEM reader makes it ~2,000 inputs
# per second); `make fuzz` runs 10^7 inputs (or FUZZ_HOST_SECONDS, default
# 3600) in fork mode with one worker per core (FUZZ_JOBS) and keeps its corpus in
# <build-dir>/fuzz_host_corpus.  Each input's file lives in
# $CT_FUZZ_TMPDIR (default /tmp) as ct_fuzz_host.<pid>.<ext>, removed after it.
# Exit 0: no finding; 1: a finding (the input saved in <build-dir>/fuzz_host/
# and printed); 77: clang's libFuzzer is not available.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=$(cd "$1" && pwd)
RUNS=${2:-20000}
SECS=${3:-0}
CORPUS=${4:-}
CC=${CT_FUZZ_CC:-clang}
CXX=${CT_FUZZ_CXX:-clang++}
OUT="$BUILD/fuzz_host"
command -v "$CXX" >/dev/null 2>&1 || { echo "fuzz_host: $CXX not found (scripts/deps.sh installs clang)"; exit 77; }
command -v "$CC" >/dev/null 2>&1 || { echo "fuzz_host: $CC not found (scripts/deps.sh installs clang)"; exit 77; }
mkdir -p "$OUT/obj"
. "$ROOT/tests/fuzz/common.sh"
fuzz_corpus "$ROOT"/tests/fuzz/corpus_host ct_fuzz_host

SAN="-g1 -O1 -fsanitize=address,undefined -fno-sanitize-recover=all"
H="$ROOT/host_tools"
INC="-I$ROOT/lib/include -I$H/core -I$H/io -I$H/dem_io -I$H/camera -I$ROOT/tests/kit -isystem /usr/include/geotiff"
# a libFuzzer check first (a missing runtime is a skip, not a failure)
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char *, unsigned long) { return 0; }' >"$OUT/probe.cpp"
if ! "$CXX" -fsanitize=fuzzer "$OUT/probe.cpp" -o "$OUT/probe" >"$OUT/build.log" 2>&1; then
    echo "fuzz_host: libFuzzer not available"; exit 77
fi
# objects (rebuilt when their source or a header is newer), two at a time
build_one() {  # source object compiler flags...
    src=$1; obj=$2; shift 2
    if [ ! -f "$obj" ] || [ -n "$(find "$ROOT/lib" "$H" "$ROOT/tests/kit" -newer "$obj" \( -name '*.h' -o -name '*.hpp' -o -name '*.c' -o -name '*.cpp' \) 2>/dev/null | head -n 1)" ]; then
        "$@" -c "$src" -o "$obj" || return 1
    fi
}
fail=0
pids=""
# build_one in the background, waiting for the pair once two run
build_bg() {
    build_one "$@" &
    pids="$pids $!"
    set -- $pids
    if [ $# -ge 2 ]; then
        for p in $pids; do wait "$p" || fail=1; done
        pids=""
    fi
}
for s in "$ROOT"/lib/src/*.c; do
    build_bg "$s" "$OUT/obj/lib_$(basename "$s" .c).o" "$CC" $SAN -fsanitize=fuzzer-no-link -std=c99 $INC
done
for s in core/terrain.cpp io/host_io.cpp dem_io/dem_io.cpp dem_io/dem_pixels.cpp dem_io/temp_output.cpp \
         camera/camera_host.cpp; do
    build_bg "$H/$s" "$OUT/obj/host_$(basename "$s" .cpp).o" "$CXX" $SAN -fsanitize=fuzzer-no-link -std=c++17 $INC
done
for p in $pids; do wait "$p" || fail=1; done
if [ $fail -ne 0 ] || ! "$CXX" $SAN -fsanitize=fuzzer -std=c++17 $INC "$ROOT/tests/fuzz/fuzz_host.cpp" "$OUT"/obj/*.o \
        -lOpenImageIO -lOpenImageIO_Util -lgeotiff -ltiff -lmrcal -lpthread -o "$OUT/fuzz_host" >>"$OUT/build.log" 2>&1; then
    cat "$OUT/build.log"; echo "fuzz_host: build failed"; exit 1
fi
cd "$OUT" || exit 1
fuzz_limits
# -timeout: one input over 20 s is a hang; -rss_limit_mb: a header may
# promise gigabytes the harness then declines to allocate (see dem())
rm -f "$OUT"/san.*
ASAN_OPTIONS=${ASAN_OPTIONS:-log_path=$OUT/san} UBSAN_OPTIONS=${UBSAN_OPTIONS:-log_path=$OUT/san:print_stacktrace=1} \
./fuzz_host $FORK -runs="$RUNS" $LIMIT -seed=1 -max_len=4096 -timeout=20 -rss_limit_mb=2048 \
    -print_final_stats=1 "$CORPUS" >"$OUT/run.log" 2>&1
rc=$?
fuzz_summary "$OUT/run.log"
if [ $rc -eq 0 ] && fuzz_forked_findings "$OUT/run.log"; then
    rc=1
fi
if [ $rc -ne 0 ]; then
    grep -a -v -E "^#[0-9]+ +(NEW|REDUCE|pulse)|NEW_FUNC" "$OUT/run.log" | tail -30
    grep -a "FINDING" "$OUT/run.log" | cut -c1-500
    cat "$OUT"/san.* 2>/dev/null | head -60
    echo "fuzz_host: FINDING (input saved in $OUT, see run.log)"
    exit 1
fi
echo "fuzz_host: ok"
exit 0
