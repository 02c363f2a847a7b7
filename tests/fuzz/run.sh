#!/bin/sh
# run.sh - run the libFuzzer targets built by `make fuzz` (tests/fuzz/README.md).
# Usage: tests/fuzz/run.sh [SECONDS [TARGET...]]   (default 60 s, every target)
#        FUZZ_RUNS=N: stop a target after N executions instead (SECONDS stays a cap)
#        FUZZ_JOBS=N: N processes on each target at once (one per CPU), sharing its corpus
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

# the larger of two counts, either of which may be "?" or empty (not known)
larger() {
    case "$1" in '' | *[!0-9]*) echo "$2"; return ;; esac
    case "$2" in '' | *[!0-9]*) echo "$1"; return ;; esac
    if [ "$2" -gt "$1" ]; then echo "$2"; else echo "$1"; fi
}

# fuzz_job TARGET LOG RUNS: one libFuzzer process after another on TARGET (restarted
# after a stall) until the time is up or RUNS executions are done (RUNS empty: no
# limit); its log is LOG. Writes "EXECS STALLS EDGES FEATURES CORPUS" to LOG.sum
# and, when it found something, the result line to LOG.finding.
fuzz_job() {
    t=$1 log=$2 want=$3
    bin=$FZ/fuzz_$t seeds=tests/fuzz/corpus/$t work=$FZ/corpus/$t art=$FZ/artifacts/$t
    dict=""
    [ -f "tests/fuzz/$t.dict" ] && dict="-dict=tests/fuzz/$t.dict"
    execs=0 stalls=0 edges="" feats="" corpus=""
    # fuzz_watch_leaks (fuzz.h) writes the inputs before a leak it finds here
    suspects=$art/${log##*/}.suspects
    rm -rf "$suspects"
    mkdir -p "$suspects"
    : >"$log"
    rm -f "$log.finding"
    while :; do
        left=$((seconds - ($(date +%s) - start)))
        [ "$left" -gt 0 ] || break
        runs=""
        if [ -n "$want" ]; then
            [ "$execs" -lt "$want" ] || break
            runs="-runs=$((want - execs))"
        fi
        seg=$log.part
        # -close_fd_mask=2: the parsers' own stderr (cli_error) goes to /dev/null;
        # libFuzzer and the sanitizers keep a copy of stderr for their reports
        # shellcheck disable=SC2086
        FUZZ_SUSPECT_DIR=$suspects nice -n 10 "$bin" -max_total_time="$left" -timeout=1 -rss_limit_mb=2048 -malloc_limit_mb=2048 \
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
        if [ -n "$(ls "$suspects")" ]; then
            # a leak seen by the harness's own check: the input is the suspect that leaks alone
            artifact="none of the suspects in $suspects leaks alone"
            for suspect in "$suspects"/leak-suspect-*; do
                if ! "$bin" -runs=1 -detect_leaks=1 "$suspect" >/dev/null 2>&1; then
                    artifact=$art/leak-$(sha1sum <"$suspect" | cut -d' ' -f1)
                    cp "$suspect" "$artifact"
                    break
                fi
            done
        fi
        echo "FINDING (exit $rc: ${what:-see $log}) input: ${artifact:-none} log: $log" >"$log.finding"
        break
    done
    rm -f "$log.part"
    rmdir "$suspects" 2>/dev/null # kept when it holds suspects
    echo "$execs $stalls ${edges:-?} ${feats:-?} ${corpus:-?}" >"$log.sum"
}

# FUZZ_JOBS=N runs N processes on each target at once (default 1), sharing its corpus
# directory (libFuzzer reloads it, so each sees what the others found); each has its own
# log (T.log for one job, T.1.log ... T.N.log for more) and 1/N of FUZZ_RUNS. The row
# sums their executions; edges, features and corpus are the largest any job reached.
jobs=${FUZZ_JOBS:-1}
case "$jobs" in '' | *[!0-9]* | 0) echo "fuzz: FUZZ_JOBS must be a positive number, got '$jobs'" >&2; exit 2 ;; esac

failed=""
printf '%-16s %12s %8s %8s %8s %8s  %s\n' target executions exec/s edges features corpus result
for t in $targets; do
    mkdir -p "$FZ/corpus/$t" "$FZ/artifacts/$t" "$FZ/logs"
    [ -x "$FZ/fuzz_$t" ] || { echo "fuzz: $FZ/fuzz_$t is missing" >&2; failed="$failed $t"; continue; }
    start=$(date +%s)
    logs=""
    if [ "$jobs" -eq 1 ]; then
        logs=$FZ/logs/$t.log
        (fuzz_job "$t" "$logs" "${FUZZ_RUNS:-}")
    else
        # background jobs ignore SIGINT in sh: stop them (the whole group) when we are stopped
        trap 'trap - INT TERM; kill 0; exit 130' INT TERM
        for j in $(seq "$jobs"); do
            want=""
            # the first jobs take the remainder, so the runs add up to FUZZ_RUNS
            [ -n "${FUZZ_RUNS:-}" ] && want=$((FUZZ_RUNS / jobs + (j <= FUZZ_RUNS % jobs ? 1 : 0)))
            fuzz_job "$t" "$FZ/logs/$t.$j.log" "$want" &
            logs="$logs $FZ/logs/$t.$j.log"
        done
        wait
        trap - INT TERM
    fi
    execs=0 stalls=0 edges="" feats="" corpus="" result=""
    for l in $logs; do
        n=0 s=0 e="" f="" c=""
        [ -f "$l.sum" ] && read -r n s e f c <"$l.sum"
        execs=$((execs + n)) stalls=$((stalls + s))
        edges=$(larger "$edges" "$e") feats=$(larger "$feats" "$f") corpus=$(larger "$corpus" "$c")
        [ -f "$l.finding" ] && [ -z "$result" ] && result=$(cat "$l.finding")
        rm -f "$l.sum" "$l.finding"
    done
    [ -n "$result" ] && failed="$failed $t"
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
