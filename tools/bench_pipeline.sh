#!/bin/sh
# bench_pipeline.sh - the pipeline benchmarks: `tessera bench --scaling` (the
# same animation at 1..N threads, fraction of linear speed-up) and `tessera
# bench --path` (camera transactions at 30 Hz, frame times), plus a control
# measured in the same run: two independent 1-thread processes at once, which
# shows how much two busy cores slow each other down on this machine without
# any pipeline. Rewrites the "## The pipeline" section at the end of
# BENCHMARKS.md (everything from that heading on); `make bench` runs it after
# tools/bench.sh, `make bench-pipeline` alone.
#
# Environment: PIPE_ROUNDS (default 9), PIPE_SIZE (1280x720), TESSERA_SHARED (../shared).
set -eu

cd "$(dirname "$0")/.."
SHARED=${TESSERA_SHARED:-../shared}
DRAGON=$SHARED/data/meshes/stanford_dragon_vrip.ply
ROUNDS=${PIPE_ROUNDS:-9}
SIZE=${PIPE_SIZE:-1280x720}
THREADS=$(nproc)
OUT=BENCHMARKS.md
TMP=${TMPDIR:-/tmp}
WORK=$(mktemp -d "$TMP/tessera-bench-pipeline.XXXXXX")
TESSERA=$WORK/tessera
cp ./tessera "$TESSERA"
LOG=$WORK/pipeline.log

run() { # label, then the command; its SCALING / BENCH_PATH lines go to the log
    label=$1
    shift
    echo "bench_pipeline: $label" >&2
    "$@" 2>/dev/null | sed -n "s/^\(# .*\|SCALING .*\|BENCH_PATH .*\)$/$label \1/p" >> "$LOG"
}

field() { # line, key -> value
    echo "$1" | tr ' ' '\n' | sed -n "s/^$2=//p"
}

run default-convert "$TESSERA" bench --scaling --size "$SIZE" --threads "$THREADS" --rounds "$ROUNDS"
run default-null "$TESSERA" bench --scaling --size "$SIZE" --threads "$THREADS" --rounds "$ROUNDS" --display null
if [ -f "$DRAGON" ]; then
    run dragon-convert "$TESSERA" bench --scaling --scene "$DRAGON" --size "$SIZE" --threads "$THREADS" \
        --rounds "$ROUNDS"
fi
# control: the 1-thread run alone, then two of it at once (separate processes, nothing shared)
run control-alone "$TESSERA" bench --scaling --size "$SIZE" --threads 1 --rounds "$ROUNDS"
# (each copy is the other's "other program": --keep-noisy, or every run would be repeated)
"$TESSERA" bench --scaling --size "$SIZE" --threads 1 --rounds "$ROUNDS" --keep-noisy 2>/dev/null |
    sed -n 's/^SCALING /control-pair-a SCALING /p' > "$WORK/pair_a" &
pair_pid=$!
run control-pair-b "$TESSERA" bench --scaling --size "$SIZE" --threads 1 --rounds "$ROUNDS" --keep-noisy
wait "$pair_pid"
cat "$WORK/pair_a" >> "$LOG"
for t in $(seq 1 "$THREADS"); do
    run "path-$t" "$TESSERA" bench --path configs/paths/orbit.json --rate 30 --size "$SIZE" --threads "$t"
done

revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
section=$WORK/section.md
{
    echo "## The pipeline"
    echo
    echo "\`sh tools/bench_pipeline.sh\` (\`make bench-pipeline\`) at revision $revision, $(date -u +%Y-%m-%d),"
    echo "$THREADS CPUs ($(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo | head -n 1)), $SIZE, $ROUNDS rounds per row."
    echo
    echo "### Scaling: the same 48-frame orbit (fixed-rate time) at 1..$THREADS threads"
    echo
    echo "\`tessera bench --scaling --size $SIZE --threads $THREADS --rounds $ROUNDS [--display null] [--scene dragon]\`:"
    echo "median wall time of pipeline_run over the rounds (runs during which other programs took"
    echo "over 2 % CPU are repeated), fraction of linear = (T1 / TN) / N. *display* is thread 0's"
    echo "display stage per frame (\`convert\`: 8-bit sRGB XRGB8888 encoding, the work of a scan-out"
    echo "display); *barrier* is the share of all threads' time spent at the frame barrier (idle at"
    echo "the end of a frame, plus the serial section)."
    echo
    echo "| scene, display | threads | median s | min-max s | frames/s | speed-up | fraction of linear | display ms | barrier |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|"
    grep -E '^(default|dragon)-[a-z]+ SCALING' "$LOG" | while read -r label _ rest; do
        line="$rest"
        echo "| $label | $(field "$line" threads) | $(field "$line" median_s) | $(field "$line" min_s)-$(field "$line" max_s) |" \
            "$(field "$line" frames_per_s) | $(field "$line" speedup) | **$(field "$line" fraction_of_linear)** |" \
            "$(field "$line" display_ms_per_frame) | $(field "$line" barrier_share) |"
    done
    echo
    alone=$(sed -n 's/^control-alone SCALING .*median_s=\([0-9.]*\).*/\1/p' "$LOG")
    pa=$(sed -n 's/^control-pair-a SCALING .*median_s=\([0-9.]*\).*/\1/p' "$LOG")
    pb=$(sed -n 's/^control-pair-b SCALING .*median_s=\([0-9.]*\).*/\1/p' "$LOG")
    echo "Control, same run: the 1-thread default/convert row alone took $alone s; two copies at once,"
    echo "as separate processes sharing nothing, took $pa s and $pb s, i.e. a ceiling of"
    echo "$(awk -v a="$alone" -v x="$pa" -v y="$pb" 'BEGIN { printf "%.3f", a / ((x + y) / 2) }') for the fraction of linear on this machine without any pipeline."
    echo
    echo "### Camera transactions along a path"
    echo
    echo "\`tessera bench --path configs/paths/orbit.json --rate 30 --size $SIZE --threads T\`: a thread"
    echo "queues one camera transaction per 1/30 s of the 8 s orbit (241 in all) while the pipeline"
    echo "renders as fast as it can (display null, real time)."
    echo
    echo "| threads | transactions | frames | median frame ms | worst frame ms | median fps |"
    echo "|---:|---:|---:|---:|---:|---:|"
    grep -E '^path-[0-9]+ BENCH_PATH' "$LOG" | while read -r _ _ rest; do
        line="$rest"
        echo "| $(field "$line" threads) | $(field "$line" transactions) | $(field "$line" frames) |" \
            "$(field "$line" median_frame_ms) | $(field "$line" worst_frame_ms) | $(field "$line" median_fps) |"
    done
    echo
    echo "The raw lines: \`$LOG\` (not kept in the repository)."
} > "$section"

if [ -f "$OUT" ]; then
    # everything before the old section, without its trailing blank lines
    awk '/^## The pipeline$/ { exit } /^$/ { blank++; next } { while (blank) { print ""; blank-- } print }' \
        "$OUT" > "$WORK/head.md"
    echo >> "$WORK/head.md"
else
    : > "$WORK/head.md"
fi
cat "$WORK/head.md" "$section" > "$OUT"
echo "bench_pipeline: wrote the pipeline section of $OUT" >&2
