#!/bin/sh
# coverage.sh -- line and branch coverage of lib/ by the test suite (gcov,
# gcovr).  A separate build in <dir> with the flight library instrumented
# (-O0 --coverage; everything else as usual), the suite run on it (the heavy
# sweeps at their default sizes; the benchmarks' and the cross tests' own
# builds do not count), then gcovr's table per file, the check that every
# branch never taken is listed in tests/coverage_exceptions.txt with its
# reason (scripts/coverage_check.py; exit 1 otherwise), and the summary.
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
# one gcovr run: the table (coverage.txt), every line and branch
# (coverage.json), the summary (printed last)
gcovr -r "$ROOT" --filter "$ROOT/lib/src/" --object-directory "$DIR/lib" \
    --exclude-unreachable-branches --exclude-throw-branches \
    --txt "$DIR/coverage.txt" --json "$DIR/coverage.json" --print-summary >"$DIR/coverage_summary.txt"
cat "$DIR/coverage.txt"
# every branch the suite never takes must be listed, with its reason, in
# tests/coverage_exceptions.txt (and every entry must still exist)
ok=0
/usr/bin/python3 "$ROOT/scripts/coverage_check.py" "$DIR/coverage.json" "$ROOT/tests/coverage_exceptions.txt" "$ROOT" || ok=1
cat "$DIR/coverage_summary.txt"
exit $ok
