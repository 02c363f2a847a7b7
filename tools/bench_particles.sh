#!/bin/sh
# bench_particles.sh - particles as spheres: tessera against the Embree peer
# harness's sphere points (RTC_GEOMETRY_TYPE_SPHERE_POINT, what
# ../shared/tools/peer/embree_bench.c makes of a PLY without faces), on the
# same points, radius and camera. Prints a markdown section ("## Particles")
# on stdout, keeps it in $WORK/particles_section.md (WORK is printed on
# stderr) and puts it into BENCHMARKS.md in place of its old section, else
# before "## Ambient occlusion" (BENCH_PARTICLES_OUT names another file; "-"
# for none). `make bench` runs it; `make bench-particles` alone.
#
# The workload is the same ray for ray: both programs give a point set
# without a radius 0.001 x its box diagonal (engine/geometry/particles, the peer's
# rule), tessera bench frames the set by the peer's rule and its camera is
# handed to the peer, and the script checks that both hit the same number of
# primary rays (within 0.1 %). The shading is the peer's eye-light shade.
# Per point set, thread count (1, 2) and round, each run its own process
# after a quiet second, alternating A B A B: tessera, Embree p8, Embree p16,
# Embree single rays. A run during which other programs used more than 0.05
# CPU is repeated, up to BENCH_PARTICLES_ATTEMPTS attempts. Figures: primary
# Mrays/s of the median frame, medians over the rounds, ratio tessera /
# Embree (> 1: tessera faster); build seconds (tessera: its tree, including
# putting the particles in the tree's order; Embree: rtcCommitScene, high
# quality) and bytes a particle (tessera: positions + tree; Embree: its own
# memory monitor's peak).
#
# Environment: BENCH_PARTICLES_SETS (file names in $TESSERA_SHARED/data/points;
# a missing one is skipped; default the 2 M Lennard-Jones particles and the
# 342 k lion scan), BENCH_PARTICLES_ROUNDS (3), BENCH_PARTICLES_FRAMES (10),
# BENCH_PARTICLES_SIZE (1920x1080), BENCH_PARTICLES_ATTEMPTS (3),
# BENCH_MAX_WAIT (seconds of waiting for quiet per whole run, 300), TMPDIR,
# TESSERA_SHARED (../shared). Needs ./tessera and libembree-dev
# (sh tools/deps.sh --bench).
set -eu

cd "$(dirname "$0")/.."
BENCH_NAME=bench_particles
# shellcheck source=tools/bench_lib.sh
. tools/bench_lib.sh
SHARED=${TESSERA_SHARED:-../shared}
DATA=$SHARED/data/points
PEER_SRC=$SHARED/tools/peer
TMP=${TMPDIR:-/tmp}
PEER_DIR=$TMP/tessera-peer
SETS=${BENCH_PARTICLES_SETS:-lj_melt_2048k.ply lion_takanawa_342k.ply}
OUT=${BENCH_PARTICLES_OUT:-BENCHMARKS.md}
ROUNDS=${BENCH_PARTICLES_ROUNDS:-3}
FRAMES=${BENCH_PARTICLES_FRAMES:-10}
SIZE=${BENCH_PARTICLES_SIZE:-1920x1080}
MAX_ATTEMPTS=${BENCH_PARTICLES_ATTEMPTS:-3}
WAIT_BUDGET_S=${BENCH_MAX_WAIT:-300}
THREADS="1 2"
NOISE_LIMIT=0.05

require_whole "BENCH_PARTICLES_ROUNDS=$ROUNDS" "BENCH_PARTICLES_FRAMES=$FRAMES" \
    "BENCH_PARTICLES_ATTEMPTS=$MAX_ATTEMPTS" "BENCH_MAX_WAIT=$WAIT_BUDGET_S"
require_tessera_and_peer "$PEER_SRC"

WORK=$(mktemp -d "$TMP/tessera-bench-particles.XXXXXX")
LOG=$WORK/runs.log
: > "$LOG"
echo "bench_particles: work directory $WORK" >&2
cp ./tessera "$WORK/tessera"
TESSERA=$WORK/tessera
if ! build_peer "$PEER_DIR" "$PEER_SRC" "$WORK/peer_build.log"; then
    echo "bench_particles: building the Embree harness failed (sh tools/deps.sh --bench installs libembree-dev):" >&2
    cat "$WORK/peer_build.log" >&2
    exit 1
fi
EMBREE=$PEER_DIR/embree_bench

# run ENGINE SET THREADS MODE COMMAND...: one measurement (repeated while noisy), logged as
#   engine set threads mode status mrays build_s bytes_per_point hits cpu_other
run() {
    r_engine=$1 r_set=$2 r_threads=$3 r_mode=$4
    shift 4
    attempt=1
    while :; do
        wait_quiet
        if ! "$@" > "$WORK/run.out" 2> "$WORK/run.err"; then
            echo "bench_particles: this command failed:" >&2
            echo "  $*" >&2
            cat "$WORK/run.err" >&2
            exit 1
        fi
        if [ "$r_engine" = tessera ]; then
            line=$(grep '^BENCH ' "$WORK/run.out" | tail -n 1)
            ms=$(kv "$line" frame_ms_median)
            build=$(kv "$line" build_s)
            bytes=$(kv "$line" bytes_per_point)
            hits=$(kv "$line" hits)
            other=$(kv "$line" cpu_other)
        else
            line=$(grep '^RESULT ' "$WORK/run.out" | tail -n 1)
            ms=$(kv "$line" median_ms)
            build=$(kv "$line" build_s)
            peak=$(sed -n 's/.*(peak \([0-9.]*\) MiB).*/\1/p' "$WORK/run.out" | head -n 1)
            count=$(kv "$line" spheres)
            bytes=$(awk -v p="${peak:-0}" -v n="$count" 'BEGIN { printf "%.2f", (n > 0 ? p * 1048576 / n : 0) }')
            hits=$(sed -n 's/^checksum *hits \([0-9]*\) .*/\1/p' "$WORK/run.out")
            other=$(kv "$line" cpu_other)
        fi
        w=${SIZE%x*} h=${SIZE#*x}
        mrays=$(awk -v w="$w" -v h="$h" -v ms="$ms" 'BEGIN { printf "%.3f", w * h / (ms / 1000) / 1e6 }')
        if awk -v o="$other" -v lim="$NOISE_LIMIT" 'BEGIN { exit !(o >= 0 && o <= lim) }'; then
            status=clean
        else
            status=noisy
        fi
        echo "bench_particles: $r_engine $r_set ${r_threads}T $r_mode: $ms ms/frame, $mrays Mrays/s, build $build s," \
            "$hits hits ($status, cpu_other $other)" >&2
        if [ "$status" = clean ] || [ "$attempt" -ge "$MAX_ATTEMPTS" ]; then
            printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$r_engine" "$r_set" "$r_threads" "$r_mode" "$status" \
                "$mrays" "$build" "$bytes" "$hits" "$other" >> "$LOG"
            return 0
        fi
        attempt=$((attempt + 1))
    done
}

cpu_model=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
start_s=$(date +%s)
load_at_start=$(uptime | sed 's/.*load average: //')
for set in $SETS; do
    f=$DATA/$set
    [ -f "$f" ] || { echo "bench_particles: $f not found: skipped" >&2; continue; }
    "$TESSERA" bench --scene "$f" --size "$SIZE" --frames 1 --warmup 0 --threads 1 > "$WORK/probe.out" \
        2> "$WORK/probe.err"
    camera=$(sed -n 's/^tessera: camera //p' "$WORK/probe.err" | head -n 1)
    [ -n "$camera" ] || { echo "bench_particles: no camera from tessera" >&2; exit 1; }
    for t in $THREADS; do
        r=1
        while [ $r -le "$ROUNDS" ]; do
            # shellcheck disable=SC2086 # $camera is several options
            run tessera "$set" "$t" packets "$TESSERA" bench --scene "$f" --size "$SIZE" --frames "$FRAMES" --threads "$t"
            for mode in p8 p16 single; do
                # shellcheck disable=SC2086
                run embree "$set" "$t" "$mode" "$EMBREE" -r "$SIZE" -f "$FRAMES" -t "$t" -m "$mode" $camera "$f"
            done
            r=$((r + 1))
        done
    done
done
total_s=$(($(date +%s) - start_s))

# ---- the section
SECTION=$WORK/particles_section.md
awk -F '\t' -v size="$SIZE" -v rounds="$ROUNDS" -v frames="$FRAMES" -v cpu="${cpu_model:-unknown CPU}" \
    -v cpus="$(nproc)" -v load="$load_at_start" -v total_s="$total_s" -v date="$(date -u '+%Y-%m-%d %H:%M UTC')" \
    -v rev="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)" '
function median(key, col,    n, i, j, tmp, v) {
    n = cnt[key]
    for (i = 1; i <= n; i++) v[i] = val[key, col, i]
    for (i = 2; i <= n; i++) for (j = i; j > 1 && v[j - 1] > v[j]; j--) { tmp = v[j]; v[j] = v[j - 1]; v[j - 1] = tmp }
    return n % 2 ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2
}
{
    key = $2 SUBSEP $3 SUBSEP $1 SUBSEP $4
    cnt[key]++
    for (c = 6; c <= 9; c++) val[key, c, cnt[key]] = $c
    if ($5 != "clean") noisy++
    runs++
    if (!($2 in seen_set)) { seen_set[$2] = 1; sets[++ns] = $2 }
    if (!($3 in seen_t)) { seen_t[$3] = 1; threads[++nt] = $3 }
}
END {
    printf "## Particles\n\n"
    printf "%s, revision %s; %d CPUs, %s (lscpu); load average at start %s. `sh tools/bench_particles.sh`:\n", date, rev, cpus, cpu, load
    printf "%s, one primary ray a pixel, the peer'"'"'s eye-light shade, each point a sphere of radius 0.001 x the set'"'"'s\n", size
    printf "box diagonal in both programs, the same camera (hits checked equal); %d rounds of A B A B runs (tessera,\n", rounds
    printf "Embree p8, p16, single rays), %d timed frames each; Mrays/s of the median frame, medians over the rounds;\n", frames
    printf "ratio = tessera / Embree (> 1: tessera faster). Build: tessera'"'"'s tree (with putting the particles in its\n"
    printf "order) against rtcCommitScene at high quality. Bytes a particle: tessera'"'"'s positions, attributes (the\n"
    printf "lion'"'"'s red, green, blue: 12 bytes) and tree (bench'"'"'s bytes_per_point), Embree'"'"'s memory monitor peak /\n"
    printf "particles (its copy of the points as float4 and its tree). %d of %d kept runs were noisy; the whole run took %d s.\n\n", noisy + 0, runs + 0, total_s
    printf "| points | threads | tessera Mrays/s | Embree p8 | Embree p16 | Embree single | tessera / best Embree | build s: tessera | Embree | bytes a particle: tessera | Embree |\n"
    printf "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    for (i = 1; i <= ns; i++) for (j = 1; j <= nt; j++) {
        s = sets[i]; t = threads[j]
        kt = s SUBSEP t SUBSEP "tessera" SUBSEP "packets"
        k8 = s SUBSEP t SUBSEP "embree" SUBSEP "p8"; k16 = s SUBSEP t SUBSEP "embree" SUBSEP "p16"
        k1 = s SUBSEP t SUBSEP "embree" SUBSEP "single"
        if (!cnt[kt] || !cnt[k8] || !cnt[k16] || !cnt[k1]) continue
        a = median(kt, 6); b = median(k8, 6); c = median(k16, 6); d = median(k1, 6)
        best = b; if (c > best) best = c; if (d > best) best = d
        ht = median(kt, 9); he = median(k8, 9)
        check = he > 0 ? (ht - he) / he : 1; if (check < 0) check = -check
        mismatch = (check > 0.001) ? " (HITS DIFFER: " ht " vs " he ")" : ""
        rows++
        if (a >= best) met++
        printf "| %s%s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %.1f |\n", s, mismatch, t, a, b, c, d, a / best, \
            median(kt, 7), median(k8, 7), median(kt, 8), median(k8, 8)
    }
    printf "\ntessera >= 1.0x the best Embree mode on %d of %d rows.\n", met + 0, rows + 0
}' "$LOG" > "$SECTION"
cat "$SECTION"
echo "bench_particles: section written to $SECTION (runs in $LOG)" >&2

# ---- into BENCHMARKS.md
[ "$OUT" = "-" ] && exit 0
[ -f "$OUT" ] || : > "$OUT"
awk -v section="$SECTION" '
BEGIN { while ((getline l < section) > 0) text = text l "\n" }
/^## Particles$/ { skipping = 1; if (!done) { printf "%s\n", text; done = 1 }; next }
skipping && /^## / { skipping = 0 }
skipping { next }
/^## Ambient occlusion$/ && !done { printf "%s\n", text; done = 1 }
{ print }
END { if (!done) printf "\n%s", text }
' "$OUT" > "$WORK/out.md" && cp "$WORK/out.md" "$OUT"
echo "bench_particles: $OUT updated" >&2
