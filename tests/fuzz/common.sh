# common.sh -- what fuzz.sh and fuzz_host.sh share (sourced; POSIX sh).

# fuzz_corpus SEEDS PREFIX: $CORPUS made absolute (the fuzzer runs in its
# build directory) -- a temporary directory /tmp/PREFIX_XXXXXX, removed on
# exit, when the caller gave none -- and seeded with the files of SEEDS
# (inputs worth keeping, earlier findings among them).
fuzz_corpus() {
    if [ -z "$CORPUS" ]; then
        CORPUS=$(mktemp -d "/tmp/$2_XXXXXX")
        trap 'rm -rf "$CORPUS"' EXIT
    fi
    mkdir -p "$CORPUS"
    CORPUS=$(cd "$CORPUS" && pwd)
    cp "$1"/* "$CORPUS"/ 2>/dev/null || true
}

# fuzz_limits: $LIMIT (-max_total_time when $SECS > 0) and $FORK (a long
# run, $RUNS over 100,000: one worker per core, FUZZ_JOBS to choose; the
# parent counts every worker's inputs).
fuzz_limits() {
    LIMIT=""
    [ "$SECS" -gt 0 ] && LIMIT="-max_total_time=$SECS"
    FORK=""
    if [ "$RUNS" -gt 100000 ]; then
        FORK="-fork=${FUZZ_JOBS:-$(nproc 2>/dev/null || echo 1)}"
    fi
}

# fuzz_summary LOG: the inputs run, the corpus added to, the workers'
# crash count.
fuzz_summary() {
    grep -E "^(stat::number_of_executed_units|stat::new_units_added)|^#[0-9]+.*DONE|Done [0-9]+ runs|fuzzed for [0-9]+ iterations" "$1"
    grep -E "oom/timeout/crash" "$1" | tail -n 1
}

# fuzz_forked_findings LOG: 1 when fork mode's workers counted an OOM, a
# timeout or a crash (the parent goes on past them and exits 0: a finding
# all the same, its input saved as oom-*, timeout-* or crash-*)
fuzz_forked_findings() {
    grep -a -E "oom/timeout/crash: ([1-9]|0/[1-9]|0/0/[1-9])" "$1" >/dev/null
}
