# bench_lib.sh - what the benchmark scripts share (sourced, not run):
# waiting for a quiet machine, reading KEY=VALUE fields, timing.
#   WAIT_BUDGET_S  seconds of waiting for quiet over the whole run (the caller sets it)
#   BENCH_NAME     the script's name for messages (the caller sets it)
# The caller may set QUIET_TICKS; by default a second counts as quiet when the
# machine's busy ticks in it stay at most 4 % of one CPU (at least 4 ticks).
WAIT_MS=0
WAIT_BUDGET_SPENT=0
# The benchmarks time loading and building: the structure cache (docs/scenes.md "Structure cache") is off,
# or every run after the first would map what the first built. bench_massive.sh turns it on for
# its second starts, in a directory of its own.
TESSERA_CACHE=off
export TESSERA_CACHE
: "${QUIET_TICKS:=$(($(getconf CLK_TCK 2>/dev/null || echo 100) * 4 / 100))}"
[ "$QUIET_TICKS" -lt 4 ] && QUIET_TICKS=4

now_ms() { echo $(($(date +%s%N) / 1000000)); }
busy_ticks() { awk '/^cpu /{print $2+$3+$4+$7+$8+$9}' /proc/stat; }
# kv LINE KEY: the value of KEY=VALUE in LINE (fields split on blanks)
kv() { printf '%s\n' "$1" | tr ' \t' '\n\n' | sed -n "s/^$2=//p" | head -n 1; }

# wait_quiet: up to 30 s for a quiet second, while the budget lasts
wait_quiet() {
    if [ $((WAIT_MS / 1000)) -ge "$WAIT_BUDGET_S" ]; then
        if [ "$WAIT_BUDGET_SPENT" = 0 ]; then
            echo "$BENCH_NAME: $WAIT_BUDGET_S s of waiting for quiet used up; runs start at once from now on" >&2
            WAIT_BUDGET_SPENT=1
        fi
        return 0
    fi
    w0=$(now_ms)
    i=0
    while [ $i -lt 30 ]; do
        qa=$(busy_ticks)
        sleep 1
        qb=$(busy_ticks)
        [ $((qb - qa)) -le "$QUIET_TICKS" ] && break
        i=$((i + 1))
    done
    WAIT_MS=$((WAIT_MS + $(now_ms) - w0))
}

# noise_status CPU_OTHER LIMIT: "clean" when the other programs' CPU share of a run (tessera
# bench's cpu_other) is known (>= 0) and at most LIMIT, else "noisy"
noise_status() {
    if awk -v o="$1" -v lim="$2" 'BEGIN { exit !(o >= 0 && o <= lim) }'; then echo clean; else echo noisy; fi
}

# bench_started: sets cpu_model (lscpu's name), start_s (now, seconds) and load_at_start (uptime's
# load averages), what a section's heading line reports
# shellcheck disable=SC2034 # the three are the caller's
bench_started() {
    cpu_model=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
    start_s=$(date +%s)
    load_at_start=$(uptime | sed 's/.*load average: //')
}

# median of the numbers on stdin (one per line)
median() { sort -g | awk '{ v[NR] = $1 } END { if (NR == 0) print 0; else if (NR % 2) print v[(NR + 1) / 2]; else print (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }

# build_peer DIR SRC LOG: the Embree harness from SRC (../shared/tools/peer) built in DIR
build_peer() {
    mkdir -p "$1"
    rm -f "$1/Makefile" "$1/embree_bench.c"
    cp "$2/Makefile" "$2/embree_bench.c" "$1/"
    env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -s -C "$1" embree_bench > "$3" 2>&1
}

# require_whole NAME=VALUE...: every VALUE a whole number, else a message and exit 2
require_whole() {
    for rw in "$@"; do
        case ${rw#*=} in
        '' | *[!0-9]*)
            echo "$BENCH_NAME: ${rw%%=*} must be a whole number, got '${rw#*=}'" >&2
            exit 2
            ;;
        esac
    done
}

# require_tessera_and_peer PEER_SRC: ./tessera built and the Embree harness's source there, else exit 1
require_tessera_and_peer() {
    if [ ! -x ./tessera ]; then
        echo "$BENCH_NAME: ./tessera not found; build it first (make tessera)" >&2
        exit 1
    fi
    if [ ! -f "$1/embree_bench.c" ]; then
        echo "$BENCH_NAME: the Embree peer harness is missing ($1/embree_bench.c)" >&2
        exit 1
    fi
}

# replace_section OUT HEADING SECTION TMP: write the file SECTION (which starts with the line
# HEADING) into the markdown file OUT in place of OUT's section under HEADING (up to the next
# "## " heading), else before "## The pipeline" (which bench_pipeline.sh keeps last), else at the
# end; a missing OUT becomes SECTION. TMP: a scratch path.
replace_section() {
    if [ -f "$1" ]; then
        awk -v heading="$2" -v section="$3" '
            function put() { while ((getline l < section) > 0) print l; done = 1 }
            $0 == heading { put(); skip = 1; next }
            skip && /^## / { skip = 0 }
            skip { next }
            /^## The pipeline$/ && !done { put() }
            { print }
            END { if (!done) put() }' "$1" > "$4"
        cp "$4" "$1"
    else
        cp "$3" "$1"
    fi
}
