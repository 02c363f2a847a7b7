#!/bin/sh
# run.sh - run the libFuzzer targets built by `make fuzz` (tests/fuzz/README.md).
# Usage: tests/fuzz/run.sh [SECONDS [TARGET...]]   (default 60 s, every target)
# From the top directory. Each target runs alone, under nice, from its seed
# corpus tests/fuzz/corpus/TARGET (read only) and what earlier runs found
# (build-fuzz/corpus/TARGET, where new inputs go). Any crash, sanitizer report,
# leak, input slower than 1 s or allocation over 2 GiB ends that target's run,
# keeps the input in build-fuzz/artifacts/TARGET/ and fails the script.
set -u

seconds=${1:-60}
[ $# -gt 0 ] && shift
FZ=build-fuzz
targets="$*"
if [ -z "$targets" ]; then
    for bin in "$FZ"/fuzz_*; do
        [ -x "$bin" ] && targets="$targets ${bin#"$FZ"/fuzz_}"
    done
fi
[ -n "$targets" ] || { echo "fuzz: no targets in $FZ (run make fuzz)" >&2; exit 2; }

# UBSan is fatal by the build (-fno-sanitize-recover=all); stacks for its reports
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=0"
export LSAN_OPTIONS="suppressions=tests/fuzz/lsan.supp:print_suppressions=0"
export TESSERA_LOG=error # parsers' warnings (a skipped optional mesh) are not findings

failed=""
printf '%-16s %12s %10s %8s %8s %8s  %s\n' target executions exec/s edges features corpus result
for t in $targets; do
    bin=$FZ/fuzz_$t
    seeds=tests/fuzz/corpus/$t
    work=$FZ/corpus/$t
    art=$FZ/artifacts/$t
    log=$FZ/logs/$t.log
    mkdir -p "$work" "$art" "$FZ/logs"
    [ -x "$bin" ] || { echo "fuzz: $bin is missing" >&2; failed="$failed $t"; continue; }
    dict=""
    [ -f "tests/fuzz/$t.dict" ] && dict="-dict=tests/fuzz/$t.dict"
    # -close_fd_mask=2: the parsers' own stderr (cli_error) goes to /dev/null;
    # libFuzzer and the sanitizers keep a copy of stderr for their reports
    # shellcheck disable=SC2086
    nice -n 10 "$bin" -max_total_time="$seconds" -timeout=1 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
        -detect_leaks=1 -print_final_stats=1 -close_fd_mask=2 -artifact_prefix="$art/" $dict \
        "$work" "$seeds" >"$log" 2>&1
    rc=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
    edges=$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    feats=$(grep -o 'ft: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    corpus=$(grep -o 'corp: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)
    if [ "$rc" -eq 0 ]; then
        result="ok, no findings"
    else
        what=$(grep -o -m 1 -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer): [a-z-]+|runtime error|fuzz: FINDING' "$log")
        artifact=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log" | tail -n 1)
        result="FINDING (exit $rc: ${what:-see $log}) input: ${artifact:-none} log: $log"
        failed="$failed $t"
    fi
    printf '%-16s %12s %10s %8s %8s %8s  %s\n' "$t" "${execs:-?}" "${rate:-?}" "${edges:-?}" "${feats:-?}" \
        "${corpus:-?}" "$result"
done
if [ -n "$failed" ]; then
    echo "fuzz: FAILED:$failed (reproduce: $FZ/fuzz_TARGET INPUT; README: tests/fuzz/README.md)"
    exit 1
fi
echo "fuzz: all targets ran ${seconds} s with no findings"
