#!/bin/sh
# run.sh - run the libFuzzer targets built by `make fuzz` (tests/fuzz/README.md).
# Usage: tests/fuzz/run.sh [SECONDS [TARGET...]]   (default 60 s, every target)
#        FUZZ_RUNS=N: stop a target after N executions instead (SECONDS stays a cap)
# From the top directory. Each target runs alone, under nice, from its seed
# corpus tests/fuzz/corpus/TARGET (read only) and what earlier runs found
# (build-fuzz/corpus/TARGET, where new inputs go). Any crash, sanitizer report,
# leak, input slower than 1 s or allocation over 2 GiB ends that target's run,
# keeps the input in build-fuzz/artifacts/TARGET/ and fails the script.
#
# libFuzzer's -timeout is wall-clock time: on a loaded machine a process can be
# starved for a second in the middle of a fast input. So a timeout input is run
# again alone three times; if it never takes a second there it is reported as a
# stall (not a finding), removed, and the target goes on for the time or runs
# left. A timeout that reproduces fails as any other finding.
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

# the value of libFuzzer's final "stat::NAME:" line in log $1
final_stat() { sed -n "s/^stat::$2: *//p" "$1" | tail -n 1; }
# the last "NAME: N" of libFuzzer's status lines in log $1
last() { grep -o "$2: [0-9]*" "$1" | tail -n 1 | cut -d' ' -f2; }

# whether input $2 of target binary $1 takes over a second when run alone
timeout_reproduces() {
    for _ in 1 2 3; do
        "$1" -timeout=1 -rss_limit_mb=2048 -malloc_limit_mb=2048 -runs=1 "$2" >/dev/null 2>&1 || return 0
    done
    return 1
}

failed=""
printf '%-16s %12s %8s %8s %8s %8s  %s\n' target executions exec/s edges features corpus result
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
    start=$(date +%s)
    execs=0 stalls=0 result="" edges="" feats="" corpus=""
    : >"$log"
    while :; do
        left=$((seconds - ($(date +%s) - start)))
        [ "$left" -gt 0 ] || break
        runs=""
        if [ -n "${FUZZ_RUNS:-}" ]; then
            [ "$execs" -lt "$FUZZ_RUNS" ] || break
            runs="-runs=$((FUZZ_RUNS - execs))"
        fi
        seg=$log.part
        # -close_fd_mask=2: the parsers' own stderr (cli_error) goes to /dev/null;
        # libFuzzer and the sanitizers keep a copy of stderr for their reports
        # shellcheck disable=SC2086
        nice -n 10 "$bin" -max_total_time="$left" -timeout=1 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
            -detect_leaks=1 -print_final_stats=1 -close_fd_mask=2 -artifact_prefix="$art/" $runs $dict \
            "$work" "$seeds" >"$seg" 2>&1
        rc=$?
        cat "$seg" >>"$log"
        n=$(final_stat "$seg" number_of_executed_units)
        execs=$((execs + ${n:-0}))
        e=$(last "$seg" cov) f=$(last "$seg" ft) c=$(last "$seg" corp)
        edges=${e:-$edges} feats=${f:-$feats} corpus=${c:-$corpus}
        [ "$rc" -eq 0 ] && break
        artifact=$(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$seg" | tail -n 1)
        case "${artifact##*/}" in
        timeout-*)
            if ! timeout_reproduces "$bin" "$artifact"; then
                stalls=$((stalls + 1))
                echo "fuzz: $t: timeout did not reproduce alone (a stalled machine: $(cut -d' ' -f1-3 /proc/loadavg)); going on" >>"$log"
                rm -f "$artifact"
                continue
            fi ;;
        esac
        what=$(grep -o -m 1 -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer): [a-z-]+|runtime error|fuzz: FINDING' "$seg")
        result="FINDING (exit $rc: ${what:-see $log}) input: ${artifact:-none} log: $log"
        failed="$failed $t"
        break
    done
    rm -f "$log.part"
    elapsed=$(($(date +%s) - start))
    rate=$((execs / (elapsed > 0 ? elapsed : 1)))
    if [ -z "$result" ]; then
        result="ok, no findings"
        [ "$stalls" -gt 0 ] && result="$result ($stalls stalls: timeouts that did not reproduce)"
    fi
    printf '%-16s %12s %8s %8s %8s %8s  %s\n' "$t" "$execs" "$rate" "${edges:-?}" "${feats:-?}" "${corpus:-?}" \
        "$result"
done
if [ -n "$failed" ]; then
    echo "fuzz: FAILED:$failed (reproduce: $FZ/fuzz_TARGET INPUT; README: tests/fuzz/README.md)"
    exit 1
fi
echo "fuzz: every target ran with no findings"
