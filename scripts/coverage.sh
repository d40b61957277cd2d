#!/bin/sh
# coverage.sh -- line and branch coverage of lib/ by the test suite (gcov,
# gcovr).  A separate build in <dir> with the flight library instrumented
# (-O0 --coverage; everything else as usual), the suite run on it (the heavy
# sweeps at their default sizes; the benchmarks' and the cross tests' own
# builds do not count), then gcovr's table per file and its summary.
#   scripts/coverage.sh <dir>
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
DIR=$(mkdir -p "$1" && cd "$1" && pwd)  # absolute: the suite runs from inside it
command -v gcovr >/dev/null 2>&1 || { echo "coverage: gcovr not found (scripts/deps.sh installs it)"; exit 1; }
cmake -S "$ROOT" -B "$DIR" -DCMAKE_BUILD_TYPE=Release -DCT_COVERAGE=ON >/dev/null
cmake --build "$DIR" -j"$(nproc 2>/dev/null || echo 2)" >/dev/null
find "$DIR" -name '*.gcda' -delete
# the suite, except what does not run the host library: cross builds, qemu,
# the clang/fuzz builds (their own compilations), the install test
(cd "$DIR" && ctest -j"$(nproc 2>/dev/null || echo 2)" -E 'mcu_|lib_clang|fuzz_|install_example|_san$' \
    --output-on-failure >"$DIR/coverage_ctest.log" 2>&1) || { tail -30 "$DIR/coverage_ctest.log"; echo "coverage: a test failed"; exit 1; }
cd "$DIR"
gcovr -r "$ROOT" --filter "$ROOT/lib/src/" --object-directory "$DIR/lib" --txt --print-summary \
    --exclude-unreachable-branches --exclude-throw-branches
