#!/bin/sh
# bench.sh - the `make bench` driver: tessera against the Intel Embree 3 peer
# harness (../shared/tools/peer) on the shared meshes (../shared/data/meshes),
# same camera, same image, same machine, same minutes; writes BENCHMARKS.md.
#
# For each round, mesh and thread count (1, 2) it runs, alternately,
#   tessera, embree single, tessera --single-rays, tessera, embree p8, tessera, embree p16   (primary rays)
#   tessera --shadows, embree p8 --shadows, tessera --shadows, embree p16 --shadows
# each as its own process after a quiet second; a run during which other
# programs used more than 0.05 CPU (cpu_other, which both programs measure from
# /proc/stat) is logged as noisy and repeated, up to 4 attempts. Only clean
# runs enter the medians (a configuration with none falls back to its noisy
# runs, marked). Every attempt is logged to $TMPDIR/tessera-bench/run.XXXXXX/runs.log;
# ./tessera is copied there first, so a rebuild during the run does not change
# what is measured.
#
# The Embree harness is built from ../shared/tools/peer in $TMPDIR/tessera-peer,
# outside the repository (it needs libembree-dev: `sh tools/deps.sh --bench`).
#
# Usage (after `make tessera`; `make bench` does both):
#   sh tools/bench.sh                  BENCH_ROUNDS rounds (default 3), BENCH_FRAMES (20) frames per run
#   BENCH_QUICK=1 sh tools/bench.sh    smoke run: 1 round, 2 frames per run (cpu_other is coarse then)
#   sh tools/bench.sh --summarize DIR  rewrite BENCHMARKS.md from an earlier run's DIR (its runs.log)
# Environment: BENCH_ROUNDS, BENCH_FRAMES, BENCH_QUICK, BENCH_MAX_WAIT (seconds of waiting for
# quiet per whole run, default 600), TMPDIR, TESSERA_SHARED (default ../shared).
set -eu
# build times are measured: the structure cache (docs/scenes.md "Structure cache") stays off
TESSERA_CACHE=off
export TESSERA_CACHE

cd "$(dirname "$0")/.."
SHARED=${TESSERA_SHARED:-../shared}
DATA=$SHARED/data/meshes
PEER_SRC=$SHARED/tools/peer
TMP=${TMPDIR:-/tmp}
PEER_DIR=$TMP/tessera-peer
OUT=BENCHMARKS.md
MESHES="stanford_bunny.obj stanford_dragon_vrip.ply ctbunny_iso900_4M.ply"
SIZE=1920x1080
THREADS="1 2"
MAX_ATTEMPTS=4
NOISE_LIMIT=0.05 # CPUs other programs may use during a run's timed frames
# Total seconds a run may spend waiting for quiet seconds: on a busy machine the
# waits, not the measurements, would otherwise set the runtime.
WAIT_BUDGET_S=${BENCH_MAX_WAIT:-600}

ROUNDS=${BENCH_ROUNDS:-3}
# Timed frames per run: enough that the timed part of a fast run lasts about a
# second, since cpu_other comes from /proc/stat's 1/100 s ticks (with 5 frames
# of 30 ms, one tick is already 0.07 CPU of "noise").
FRAMES=${BENCH_FRAMES:-20}
QUICK=${BENCH_QUICK:-0}
if [ "$QUICK" = 1 ]; then
    ROUNDS=1
    FRAMES=2
fi

now_ms() { echo $(($(date +%s%N) / 1000000)); }
min_s() { echo "$(($1 / 60)) min $(($1 % 60)) s"; }
busy_ticks() { awk '/^cpu /{print $2+$3+$4+$7+$8+$9}' /proc/stat; }

# wait_quiet: up to 60 s for a second with < 0.04 CPU used, as run_bench.sh does,
# while the run's waiting budget lasts
wait_quiet() {
    if [ $((WAIT_MS / 1000)) -ge "$WAIT_BUDGET_S" ]; then
        if [ "$WAIT_BUDGET_SPENT" = 0 ]; then
            echo "bench: $WAIT_BUDGET_S s of waiting for quiet used up; from now on runs start at once" \
                "(noisy ones are still rejected)" >&2
            WAIT_BUDGET_SPENT=1
        fi
        return 0
    fi
    w0=$(now_ms)
    i=0
    while [ $i -lt 60 ]; do
        a=$(busy_ticks)
        sleep 1
        b=$(busy_ticks)
        if [ $((b - a)) -le "$QUIET_TICKS" ]; then
            WAIT_MS=$((WAIT_MS + $(now_ms) - w0))
            return 0
        fi
        i=$((i + 1))
    done
    WAIT_MS=$((WAIT_MS + $(now_ms) - w0))
    echo "bench: no quiet second in 60 s; running anyway" >&2
}

# run TAG ENGINE MESH THREADS MODE COMMAND...: one measurement, repeated while noisy.
# Log line: tag, clean|noisy, engine, mesh, threads, mode, command, result fields (tabs between).
run() {
    run_tag=$1 run_engine=$2 run_mesh=$3 run_threads=$4 run_mode=$5
    shift 5
    attempt=1
    while :; do
        wait_quiet
        r0=$(now_ms)
        if ! "$@" > "$WORK/run.out" 2> "$WORK/run.err"; then
            echo "bench: this command failed:" >&2
            echo "  $*" >&2
            cat "$WORK/run.err" >&2
            exit 1
        fi
        if [ "$run_engine" = tessera ]; then
            line=$(grep '^BENCH ' "$WORK/run.out" | tail -n 1)
        else # the RESULT line, plus Embree's memory, hit rate and version from its report
            line="$(grep '^RESULT ' "$WORK/run.out" | tail -n 1)"
            line="$line $(sed -n 's/^build .* embree mem \([0-9.]*\) MiB.*/mem_mib=\1/p' "$WORK/run.out")"
            line="$line $(sed -n 's/^rays .*(hit rate \([0-9.]*\)).*/hit_rate=\1/p' "$WORK/run.out")"
            line="$line $(sed -n 's/^embree *\([0-9.]*\) .*/embree_version=\1/p' "$WORK/run.out")"
        fi
        other=$(printf '%s\n' "$line" | sed -n 's/.*cpu_other=\([-0-9.]*\).*/\1/p')
        if [ -z "$other" ]; then
            echo "bench: no result line from: $*" >&2
            cat "$WORK/run.out" "$WORK/run.err" >&2
            exit 1
        fi
        if awk -v o="$other" -v lim="$NOISE_LIMIT" 'BEGIN { exit !(o >= 0 && o <= lim) }'; then
            status=clean
        else
            status=noisy
        fi
        r1=$(now_ms)
        RUN_MS=$((RUN_MS + r1 - r0))
        [ "$status" = noisy ] && REJECTED_MS=$((REJECTED_MS + r1 - r0))
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$run_tag" "$status" "$run_engine" "$run_mesh" "$run_threads" \
            "$run_mode" "$*" "$line" >> "$LOG"
        printf 'bench: %-7s %-8s %-26s %sT %-6s %s (cpu_other %s)\n' "$run_tag" "$run_engine" "$run_mesh" \
            "$run_threads" "$run_mode" "$status" "$other" >&2
        [ "$status" = clean ] && return 0
        [ "$attempt" -ge "$MAX_ATTEMPTS" ] && return 0
        attempt=$((attempt + 1))
    done
}

# meta NAME...: the variables as shell assignments, for --summarize
meta() {
    for name in "$@"; do
        value=""
        eval "value=\${$name}"
        printf "%s='%s'\n" "$name" "$(printf '%s' "$value" | sed "s/'/'\\\\''/g")"
    done
}

# measure: build the peer, run the matrix into $WORK/runs.log, record $WORK/meta
measure() {
    for v in "BENCH_ROUNDS=$ROUNDS" "BENCH_FRAMES=$FRAMES" "BENCH_MAX_WAIT=$WAIT_BUDGET_S"; do
        case ${v#*=} in
        '' | *[!0-9]*)
            echo "bench: ${v%%=*} must be a whole number, got '${v#*=}'" >&2
            exit 2
            ;;
        0)
            [ "${v%%=*}" = BENCH_MAX_WAIT ] && continue
            echo "bench: ${v%%=*} must be a whole number >= 1, got '${v#*=}'" >&2
            exit 2
            ;;
        esac
    done
    if [ ! -d "$SHARED/data" ]; then
        echo "bench: $SHARED/data not found (the shared meshes live beside the repository); nothing to measure" >&2
        exit 0
    fi
    found=""
    for m in $MESHES; do
        if [ -f "$DATA/$m" ]; then found="$found $m"; else echo "bench: $DATA/$m not found; skipped" >&2; fi
    done
    if [ -z "$found" ]; then
        echo "bench: no meshes in $DATA; nothing to measure" >&2
        exit 0
    fi
    if [ ! -x ./tessera ]; then
        echo "bench: ./tessera not found; build it first (make tessera, or make bench)" >&2
        exit 1
    fi
    if [ ! -f "$PEER_SRC/embree_bench.c" ] || [ ! -f "$PEER_SRC/Makefile" ]; then
        echo "bench: the Embree peer harness is missing ($PEER_SRC/embree_bench.c, Makefile)" >&2
        exit 1
    fi

    start_s=$(date +%s)
    run_date=$(date -u '+%Y-%m-%d %H:%M UTC')
    mkdir -p "$TMP/tessera-bench" "$PEER_DIR"
    WORK=$(mktemp -d "$TMP/tessera-bench/run.XXXXXX")
    LOG=$WORK/runs.log
    : > "$LOG"
    # the binary measured: a snapshot, since others may rebuild ./tessera meanwhile
    cp ./tessera "$WORK/tessera"
    TESSERA=$WORK/tessera
    revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
    if [ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ]; then
        revision="$revision plus uncommitted changes"
    fi

    # the peer harness, built outside the repository (copies replace the
    # previous ones: the shared files are read-only); the sub-make must not
    # inherit `make bench`'s variables (CFLAGS=..., WERROR=1)
    rm -f "$PEER_DIR/Makefile" "$PEER_DIR/embree_bench.c"
    cp "$PEER_SRC/Makefile" "$PEER_SRC/embree_bench.c" "$PEER_DIR/"
    if ! env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -s -C "$PEER_DIR" embree_bench > "$WORK/peer_build.log" 2>&1
    then
        echo "bench: building the Embree harness in $PEER_DIR failed" \
            "(is libembree-dev installed? sh tools/deps.sh --bench):" >&2
        cat "$WORK/peer_build.log" >&2
        exit 1
    fi
    EMBREE=$PEER_DIR/embree_bench

    TICKS_PER_S=$(getconf CLK_TCK 2>/dev/null || echo 100)
    QUIET_TICKS=$((TICKS_PER_S * 4 / 100))
    WAIT_MS=0 RUN_MS=0 REJECTED_MS=0 # waiting for quiet, in runs, in runs then rejected
    WAIT_BUDGET_SPENT=0

    # rounds outermost, so that each configuration's repeats spread over the run
    echo "bench: $ROUNDS round(s), $FRAMES frames per run, meshes:$found; log: $LOG" >&2
    r=1
    while [ $r -le "$ROUNDS" ]; do
        echo "bench: round $r of $ROUNDS" >&2
        for m in $found; do
            f=$DATA/$m
            for t in $THREADS; do
                for mode in single p8 p16; do
                    run primary tessera "$m" "$t" - "$TESSERA" bench --scene "$f" --size $SIZE --threads "$t" \
                        --frames "$FRAMES"
                    run primary embree "$m" "$t" "$mode" "$EMBREE" -r $SIZE -f "$FRAMES" -t "$t" -m "$mode" "$f"
                    if [ "$mode" = single ]; then # tessera's single-ray path beside Embree's single mode
                        run single tessera "$m" "$t" - "$TESSERA" bench --scene "$f" --size $SIZE --threads "$t" \
                            --frames "$FRAMES" --single-rays
                    fi
                done
                for mode in p8 p16; do
                    run shadows tessera "$m" "$t" - "$TESSERA" bench --scene "$f" --size $SIZE --threads "$t" \
                        --frames "$FRAMES" --shadows
                    run shadows embree "$m" "$t" "$mode" "$EMBREE" -r $SIZE -f "$FRAMES" -t "$t" -m "$mode" \
                        --shadows "$f"
                done
            done
        done
        r=$((r + 1))
    done
    total_s=$(($(date +%s) - start_s))

    cpu_model=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
    cpu_flags=$(lscpu 2>/dev/null | sed -n 's/^Flags: *//p' | head -n 1)
    simd=""
    for flag in sse4_2 avx2 fma avx512f; do
        case " $cpu_flags " in *" $flag "*) simd="$simd $flag" ;; esac
    done
    cpus=$(nproc)
    kernel=$(uname -r)
    cc_version=$(cc --version 2>/dev/null | head -n 1)
    meta ROUNDS FRAMES QUICK SIZE DATA PEER_SRC PEER_DIR EMBREE TESSERA NOISE_LIMIT MAX_ATTEMPTS WAIT_BUDGET_S \
        WAIT_BUDGET_SPENT run_date total_s WAIT_MS RUN_MS REJECTED_MS revision cpus cpu_model simd kernel \
        cc_version > "$WORK/meta"
}

if [ "${1:-}" = --summarize ]; then
    if [ ! -f "${2:-}/meta" ] || [ ! -f "${2:-}/runs.log" ]; then
        echo "bench: --summarize needs the directory of an earlier run (with meta and runs.log)" >&2
        exit 2
    fi
    WORK=$2
elif [ $# -gt 0 ]; then
    echo "bench: unknown argument '$1' (usage: sh tools/bench.sh [--summarize DIR])" >&2
    exit 2
else
    measure
fi
LOG=$WORK/runs.log
# shellcheck disable=SC1091 # written by measure
. "$WORK/meta"

# ---- BENCHMARKS.md
cat > "$WORK/summary.awk" << 'EOF'
# Reads runs.log; prints the result sections of BENCHMARKS.md.
function median(a, n,    i, j, v, b) { # a[1..n]; sorted copy in b
    for (i = 1; i <= n; i++) b[i] = a[i]
    for (i = 2; i <= n; i++) { v = b[i]; for (j = i - 1; j >= 1 && b[j] > v; j--) b[j + 1] = b[j]; b[j + 1] = v }
    return n % 2 ? b[(n + 1) / 2] : (b[n / 2] + b[n / 2 + 1]) / 2
}
function spread(a, n,    i, lo, hi, m) {
    lo = hi = a[1]
    for (i = 2; i <= n; i++) { if (a[i] < lo) lo = a[i]; if (a[i] > hi) hi = a[i] }
    m = median(a, n)
    return m > 0 ? 100 * (hi - lo) / m : 0
}
# median of field f over the runs of group g that count (its clean ones, else all of them)
function gmed(g, f,    i, n, a) {
    n = 0
    for (i = 1; i <= cnt[g]; i++) if (run_ok[g, i]) a[++n] = val[g, i, f]
    return n ? median(a, n) : ""
}
function gspread(g, f,    i, n, a) {
    n = 0
    for (i = 1; i <= cnt[g]; i++) if (run_ok[g, i]) a[++n] = val[g, i, f]
    return n ? spread(a, n) : 0
}
function gn(g,    i, n) { n = 0; for (i = 1; i <= cnt[g]; i++) if (run_ok[g, i]) n++; return n }
function mark(g) { return noisy_only[g] ? "†" : "" }
function fmt(v, d) { return v == "" ? "–" : sprintf("%." d "f", v) }
function ratio(a, b) { return a == "" || b == "" || b == 0 ? "–" : sprintf("%.2f", a / b) }
function num(x) { return x == "" ? "" : x + 0 } # fields are strings: compare them as numbers

BEGIN { FS = "\t" }
{
    tag = $1; status = $2; engine = $3; mesh = $4; thr = $5; mode = $6
    g = tag SUBSEP mesh SUBSEP thr SUBSEP engine SUBSEP mode
    i = ++cnt[g]
    clean[g, i] = status == "clean"
    if (status == "clean") nclean[g]++
    attempts++; if (status != "clean") { rejected++; rej_eng[engine]++; rej_other[rejected] = 0 }
    nf = split($8, kv, " ")
    delete r
    for (k = 2; k <= nf; k++) { p = index(kv[k], "="); if (p) r[substr(kv[k], 1, p - 1)] = substr(kv[k], p + 1) }
    if (status != "clean") rej_other[rejected] = r["cpu_other"] + 0
    if (engine == "tessera") {
        val[g, i, "prim"] = num(r["prim_mrays"]); val[g, i, "total"] = num(r["total_mrays"])
        val[g, i, "build"] = num(r["build_s"]); val[g, i, "bpt"] = num(r["bytes_per_tri"])
        val[g, i, "hit"] = num(r["hit_rate"]); tris[mesh] = r["triangles"]
        if (r["isa"] != "") isa = r["isa"]
    } else { # per-run figure from the median frame, as tessera's (see BENCHMARKS.md)
        split(r["res"], wh, "x")
        prim = wh[1] * wh[2] / (r["median_ms"] * 1000)
        val[g, i, "prim"] = prim
        val[g, i, "total"] = r["prim_mrays"] > 0 ? prim * r["total_mrays"] / r["prim_mrays"] : prim
        val[g, i, "build"] = num(r["build_s"]); val[g, i, "hit"] = num(r["hit_rate"])
        val[g, i, "bpt"] = r["tris"] > 0 ? r["mem_mib"] * 1048576 / r["tris"] : ""
        tris[mesh] = r["tris"]; if (r["embree_version"] != "") embree_version = r["embree_version"]
    }
    if (!(mesh in seen_mesh)) { seen_mesh[mesh] = 1; meshes[++nmeshes] = mesh }
}
END {
    for (g in cnt) {
        noisy_only[g] = !nclean[g]
        for (i = 1; i <= cnt[g]; i++) run_ok[g, i] = nclean[g] ? clean[g, i] : 1
    }
    split("single p8 p16", all_modes, " ")
    split("p8 p16", shadow_modes, " ")
    for (t = 1; t <= 2; t++) {
        printf "### Primary rays, %d thread%s\n\n", t, (t > 1 ? "s" : "")
        print "| mesh | triangles | tessera prim Mrays/s (median, spread, n) | best Embree mode: median | tessera / Embree-best | build s: tessera / Embree | bytes/tri: tessera / Embree | hit rate: tessera / Embree |"
        print "|---|---:|---:|---:|---:|---:|---:|---:|"
        for (k = 1; k <= nmeshes; k++) {
            m = meshes[k]
            tg = "primary" SUBSEP m SUBSEP t SUBSEP "tessera" SUBSEP "-"
            if (!(tg in cnt)) continue
            best = ""; best_mode = ""; ebuild_n = 0; delete eb
            for (j = 1; j <= 3; j++) {
                eg = "primary" SUBSEP m SUBSEP t SUBSEP "embree" SUBSEP all_modes[j]
                if (!(eg in cnt)) continue
                v = gmed(eg, "prim")
                if (v != "" && (best == "" || v > best)) { best = v; best_mode = all_modes[j]; bg = eg }
                for (i = 1; i <= cnt[eg]; i++) if (run_ok[eg, i]) eb[++ebuild_n] = val[eg, i, "build"]
            }
            tp = gmed(tg, "prim")
            if (best != "" && tp != "") { rows++; if (tp / best >= 1.0) met++ }
            printf "| %s | %s | %s%s (%.0f%%, n=%d) | %s%s: %s | **%s** | %s / %s | %s / %s | %s / %s |\n", m, tris[m],
                fmt(tp, 2), mark(tg), gspread(tg, "prim"), gn(tg), best_mode, best_mode != "" ? mark(bg) : "",
                fmt(best, 2), ratio(tp, best), fmt(gmed(tg, "build"), 3),
                ebuild_n ? fmt(median(eb, ebuild_n), 3) : "–", fmt(gmed(tg, "bpt"), 1),
                best_mode != "" ? fmt(gmed(bg, "bpt"), 1) : "–", fmt(gmed(tg, "hit"), 4),
                best_mode != "" ? fmt(gmed(bg, "hit"), 3) : "–"
        }
        print ""
    }
    print "### Embree, every mode: primary Mrays/s (median, spread, n)\n"
    print "| mesh | threads | single | p8 | p16 |"
    print "|---|---:|---:|---:|---:|"
    for (k = 1; k <= nmeshes; k++) for (t = 1; t <= 2; t++) {
        m = meshes[k]; line = sprintf("| %s | %d", m, t); any = 0
        for (j = 1; j <= 3; j++) {
            eg = "primary" SUBSEP m SUBSEP t SUBSEP "embree" SUBSEP all_modes[j]
            if (eg in cnt) { any = 1; line = line sprintf(" | %s%s (%.0f%%, n=%d)", fmt(gmed(eg, "prim"), 2), mark(eg), gspread(eg, "prim"), gn(eg)) }
            else line = line " | –"
        }
        if (any) print line " |"
    }
    print ""
    print "### Single rays: tessera --single-rays against Embree single (rtcIntersect1): primary Mrays/s (median, spread, n)\n"
    print "| mesh | threads | tessera --single-rays | Embree single | tessera / Embree | tessera packets / tessera single rays |"
    print "|---|---:|---:|---:|---:|---:|"
    for (k = 1; k <= nmeshes; k++) for (t = 1; t <= 2; t++) {
        m = meshes[k]
        sg = "single" SUBSEP m SUBSEP t SUBSEP "tessera" SUBSEP "-"
        eg = "primary" SUBSEP m SUBSEP t SUBSEP "embree" SUBSEP "single"
        tg = "primary" SUBSEP m SUBSEP t SUBSEP "tessera" SUBSEP "-"
        if (!(sg in cnt) || !(eg in cnt)) continue
        ts = gmed(sg, "prim"); es = gmed(eg, "prim")
        printf "| %s | %d | %s%s (%.0f%%, n=%d) | %s%s (%.0f%%, n=%d) | **%s** | %s |\n", m, t, fmt(ts, 2), mark(sg),
            gspread(sg, "prim"), gn(sg), fmt(es, 2), mark(eg), gspread(eg, "prim"), gn(eg), ratio(ts, es),
            (tg in cnt) ? ratio(gmed(tg, "prim"), ts) : "–"
    }
    print ""
    print "### One shadow ray per hit: Mrays/s, primary / total (median; spread of primary, n)\n"
    print "| mesh | threads | tessera | best Embree mode (p8, p16): primary / total | tessera / Embree-best (frame rate) |"
    print "|---|---:|---:|---:|---:|"
    for (k = 1; k <= nmeshes; k++) for (t = 1; t <= 2; t++) {
        m = meshes[k]
        tg = "shadows" SUBSEP m SUBSEP t SUBSEP "tessera" SUBSEP "-"
        if (!(tg in cnt)) continue
        best = ""; best_mode = ""
        for (j = 1; j <= 2; j++) {
            eg = "shadows" SUBSEP m SUBSEP t SUBSEP "embree" SUBSEP shadow_modes[j]
            if (!(eg in cnt)) continue
            v = gmed(eg, "prim")
            if (v != "" && (best == "" || v > best)) { best = v; best_mode = shadow_modes[j]; bg = eg }
        }
        tp = gmed(tg, "prim")
        printf "| %s | %d | %s / %s%s (%.0f%%, n=%d) | %s%s: %s / %s | **%s** |\n", m, t, fmt(tp, 2),
            fmt(gmed(tg, "total"), 2), mark(tg), gspread(tg, "prim"), gn(tg), best_mode,
            best_mode != "" ? mark(bg) : "", fmt(best, 2), best_mode != "" ? fmt(gmed(bg, "total"), 2) : "–",
            ratio(tp, best)
    }
    print ""
    print "### Noise\n"
    printf "%d attempts, %d rejected as noisy (tessera %d, Embree %d)", attempts, rejected + 0, rej_eng["tessera"] + 0, rej_eng["embree"] + 0
    if (rejected) printf "; their median cpu_other was %.2f CPUs", median(rej_other, rejected)
    print "."
    n_noisy_only = 0
    for (g in noisy_only) if (noisy_only[g]) n_noisy_only++
    if (n_noisy_only) printf "%d configuration(s) had no clean run at all; their figures come from noisy runs and are marked †.\n", n_noisy_only
    print ""
    # the summary for the header, read back by bench.sh
    if (isa == "") isa = "-"
    if (embree_version == "") embree_version = "-"
    printf "SUMMARY met=%d rows=%d isa=%s embree=%s\n", met + 0, rows + 0, isa, embree_version > summary
}
EOF
awk -v summary="$WORK/summary.txt" -f "$WORK/summary.awk" "$LOG" > "$WORK/tables.md"
read -r _ met_kv rows_kv isa_kv embree_kv < "$WORK/summary.txt"
met=${met_kv#met=}
rows=${rows_kv#rows=}
isa=${isa_kv#isa=}
embree_version=${embree_kv#embree=}
[ "$isa" = - ] && isa="not reported (the BENCH line has no isa= field)"

{
    echo "# Benchmarks: tessera against Embree"
    echo
    echo "Written by \`make bench\` (\`tools/bench.sh\`). **The target is a ratio tessera / Embree-best"
    echo ">= 1.0 on every mesh** (primary rays at 1920x1080, at 1 and 2 threads): tessera must trace at"
    echo "least as fast as the best of Embree's single-ray and 8- and 16-wide packet modes on the same"
    echo "machine. In this run $met of $rows rows meet it."
    echo
    echo "Speed against error (frame time against image error for each quality knob: antialiasing,"
    echo "and the knobs later issues add) is measured apart: REPORT.md, written by \`make report\`."
    echo
    echo "- date: $run_date; $ROUNDS round(s), $FRAMES timed frames per run$(
        [ "$QUICK" = 1 ] && echo ' (BENCH_QUICK=1 smoke run)')"
    echo "- the whole run took $(min_s "$total_s"): $(min_s $((RUN_MS / 1000))) in the measured programs"
    echo "  (of which $(min_s $((REJECTED_MS / 1000))) in runs then rejected as noisy),"
    echo "  $(min_s $((WAIT_MS / 1000))) waiting for quiet seconds$(
        [ "${WAIT_BUDGET_SPENT:-0}" = 1 ] && echo " (the budget of $WAIT_BUDGET_S s ran out: later runs started at once)")"
    echo "- machine: $cpus CPUs, ${cpu_model:-unknown CPU} (lscpu), SIMD flags:${simd:- none of sse4_2/avx2/avx512f};"
    echo "  kernel $kernel"
    echo "- tessera: revision $revision; kernels ISA $isa; built by \`make tessera\`"
    echo "  ($cc_version, -O2, generic x86-64)"
    echo "- Embree $embree_version (Debian libembree-dev), through \`embree_bench\` from \`$PEER_SRC\`,"
    echo "  built in \`$PEER_DIR\` with its own Makefile (\`cc -O3 -march=native\`)"
    echo
    echo "## How"
    echo
    echo "Commands (from the repository root; M = each mesh present in \`$DATA\`, T = 1 and 2):"
    echo
    echo '```sh'
    echo "./tessera bench --scene $DATA/M --size $SIZE --threads T --frames $FRAMES [--shadows | --single-rays]"
    echo "$EMBREE -r $SIZE -f $FRAMES -t T -m single|p8|p16 [--shadows] $DATA/M"
    echo '```'
    echo
    echo "(\`./tessera\` is run as a copy taken at the start, \`$TESSERA\`.)"
    echo
    echo "Per round, mesh and thread count, in this order, each its own process: tessera, Embree"
    echo "single, tessera --single-rays, tessera, Embree p8, tessera, Embree p16; then tessera --shadows,"
    echo "Embree p8 --shadows, tessera --shadows, Embree p16 --shadows. So tessera has 3 primary, 1"
    echo "single-ray and 2 shadow runs per round and each Embree mode one. Both programs frame a mesh by the same rule (the peer's), render"
    echo "1 untimed warm-up frame and then the timed frames, and shade the same image (|dot(Ng, dir)|;"
    echo "the hit rate columns check that they see the same picture)."
    echo
    echo "- **Mrays/s of a run** = primary rays per frame (W x H) / the median frame time. tessera"
    echo "  prints it (\`prim_mrays\`, median of per-frame rates); for Embree it is computed from"
    echo "  \`median_ms\` of its RESULT line (its own \`prim_mrays\` is a mean over the frames; both are in"
    echo "  the log). Total = primary + shadow rays, likewise. The tables give the median over the runs"
    echo "  and spread = (max - min) / median; differences under ~10% are noise on this kind of machine."
    echo "- **build s**: tessera's \`accel_build\` with T threads; Embree's \`rtcCommitScene\` with T"
    echo "  threads (median over all its modes' runs). Loading the file is not included in either."
    echo "- **bytes/tri**: tessera = (mesh arrays + acceleration structure) / triangles (\`tessera bench"
    echo "  --help\`); Embree = all memory its memory monitor saw (its copies of the vertex and index"
    echo "  buffers + BVH) / triangles."
    echo "- **Noise**: before each run the driver waits for a second in which the machine used < 0.04"
    echo "  CPU; a run during which other programs used more than $NOISE_LIMIT CPU (\`cpu_other\`, from"
    echo "  /proc/stat minus the program's own CPU time) is rejected and repeated, up to $MAX_ATTEMPTS attempts."
    echo "  Waiting for quiet seconds is capped at ${WAIT_BUDGET_S:-600} s per whole run (BENCH_MAX_WAIT)."
    echo
    echo "## Results"
    echo
    cat "$WORK/tables.md"
    echo "Every attempt, with its command and result line, was logged to \`$LOG\` (not kept in the"
    echo "repository; \`sh tools/bench.sh --summarize $WORK\` rewrites this file from it)."
} > "$WORK/BENCHMARKS.md"
# the file's head (title, How, Results) is this script's; the other scripts' sections that
# follow it in the old file (Wall, Particles, ... The pipeline) stay as they were
if [ -f "$OUT" ]; then
    awk '/^## / && $0 != "## How" && $0 != "## Results" { keep = 1 } keep' "$OUT" >> "$WORK/BENCHMARKS.md"
fi
mv "$WORK/BENCHMARKS.md" "$OUT"
echo "bench: wrote $OUT ($met of $rows rows at ratio >= 1.0; $(min_s "$total_s"))" >&2
