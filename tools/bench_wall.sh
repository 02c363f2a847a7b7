#!/bin/sh
# bench_wall.sh - `tessera bench --wall` on the walls of configs/walls (by
# default wall_2x2, vm_2x2 and portrait_3x1) with the null and convert
# displays (and dump with WALL_DUMP=1, writing into a temporary directory),
# then writes a Markdown section "## Wall" into BENCHMARKS.md (replacing the
# one there, else inserting it before "## The pipeline") and prints it: the
# command, revision, machine, medians and the ratios against baselines
# measured in the same run (each output alone against the whole wall; each
# display against null). `make bench` and `make bench-wall` run it.
#
# Environment: WALL_CONFIGS (names in configs/walls, default "wall_2x2 vm_2x2
# portrait_3x1"), WALL_ROUNDS (default 5), WALL_FRAMES (24), WALL_THREADS
# (nproc), WALL_DUMP (0; 1 adds the dump display), WALL_SCALE (size scale, 1).
set -eu

cd "$(dirname "$0")/.."
CONFIGS=${WALL_CONFIGS:-"wall_2x2 vm_2x2 portrait_3x1"}
ROUNDS=${WALL_ROUNDS:-5}
FRAMES=${WALL_FRAMES:-24}
THREADS=${WALL_THREADS:-$(nproc)}
SCALE=${WALL_SCALE:-1}
TMP=${TMPDIR:-/tmp}
WORK=$(mktemp -d "$TMP/tessera-bench-wall.XXXXXX")
TESSERA=$WORK/tessera
cp ./tessera "$TESSERA"
DISPLAYS=null,convert,convert-tiles
DUMP_ARGS=
if [ "${WALL_DUMP:-0}" = 1 ]; then
    DISPLAYS=null,convert,convert-tiles,dump
    mkdir "$WORK/dump"
    DUMP_ARGS="--out $WORK/dump"
fi

field() { # line, key -> value
    echo "$1" | tr ' ' '\n' | sed -n "s/^$2=//p"
}

num() { # line, key, decimals -> the value rounded
    awk -v v="$(field "$1" "$2")" -v d="$3" 'BEGIN { printf "%.*f", d, v }'
}

ms() { # line -> "median (min-max)" in ms, one decimal
    echo "$(num "$1" median_ms 1) ($(num "$1" min_ms 1)-$(num "$1" max_ms 1))"
}

# The revision without running git: .git/HEAD and the ref it names.
revision() {
    head_ref=$(cat .git/HEAD 2>/dev/null || echo unknown)
    case $head_ref in
    "ref: "*)
        ref=${head_ref#ref: }
        if [ -f ".git/$ref" ]; then
            cut -c1-7 ".git/$ref"
        else
            sed -n "s| $ref\$||p" .git/packed-refs 2>/dev/null | cut -c1-7 | head -n 1
        fi
        ;;
    *) echo "$head_ref" | cut -c1-7 ;;
    esac
}

start=$(date +%s)
for w in $CONFIGS; do
    echo "bench_wall: $w ($DISPLAYS, $ROUNDS rounds of $FRAMES frames)" >&2
    # shellcheck disable=SC2086 # DUMP_ARGS is two words or none
    "$TESSERA" bench --wall "configs/walls/$w.json" --display "$DISPLAYS" $DUMP_ARGS --frames "$FRAMES" \
        --rounds "$ROUNDS" --threads "$THREADS" --size-scale "$SCALE" > "$WORK/$w.out" 2> "$WORK/$w.err" || {
        echo "bench_wall: $w failed:" >&2
        cat "$WORK/$w.err" >&2
        exit 1
    }
done
took=$(($(date +%s) - start))

first_display=${DISPLAYS%%,*}
{
echo "## Wall"
echo
echo "\`sh tools/bench_wall.sh\` at revision $(revision) (plus the working tree's changes, if any), $(date -u +%Y-%m-%d),"
echo "$(nproc) CPUs ($(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo | head -n 1)), $THREADS render threads; the run took $((took / 60)) min $((took % 60)) s."
echo "Per wall in configs/walls:"
echo
echo "\`\`\`sh"
echo "tessera bench --wall configs/walls/W.json --display $DISPLAYS${DUMP_ARGS:+ --out DIR} --frames $FRAMES --rounds $ROUNDS --threads $THREADS --size-scale $SCALE"
echo "\`\`\`"
echo
echo "Built-in scene, the camera orbiting (a turn in 2 s), fixed-rate time at 30 Hz: $FRAMES frames a run."
echo "*whole wall*: every output a channel of one pipeline (\`tessera run --wall\`); *alone*: each"
echo "output in a one-channel pipeline of its own, same window, size, display and frames. Each round runs"
echo "every (display, whole wall / output) combination once, alternating (reversed every other round);"
echo "each run waits for a quiet moment first (at most 300 s of waiting per wall), and a run during which"
echo "other programs took over 2 % CPU is repeated, up to 4 runs (if all are noisy, the least disturbed one"
echo "is kept). Frame ms = median over the rounds of each run's median loop step (display of frame f-1 on"
echo "thread 0 overlapping the rendering of frame f); *display ms* = thread 0's display stage per frame"
echo "and output."
echo
echo "### Whole wall against its outputs alone"
echo
echo "*alone, summed* = the outputs' frame times alone added up (a wall frame output by output); *summed / whole*"
echo "= median over the rounds of that sum / the whole wall's frame time in the same round (> 1: one pipeline"
echo "for all outputs is faster)."
echo
echo "| wall | display | outputs | Mpx a frame | whole wall ms (min-max) | frames/s | Mpx/s | alone, summed ms | summed / whole | display ms per output |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for w in $CONFIGS; do
    grep '^BENCH_WALL wall=' "$WORK/$w.out" | while read -r line; do
        echo "| $w | $(field "$line" display) | $(field "$line" outputs) |" \
            "$(awk -v p="$(field "$line" pixels)" 'BEGIN { printf "%.2f", p / 1e6 }') |" \
            "$(ms "$line") | $(num "$line" fps 2) |" \
            "$(num "$line" mpix_s 2) | $(num "$line" outputs_sum_ms 1) | **$(num "$line" sum_over_wall 3)** |" \
            "$(num "$line" display_ms_per_output 2) |"
    done
done
echo
echo "### Each output alone"
echo
echo "| wall | output | size | display | frame ms (min-max) | frames/s | Mpx/s | display ms |"
echo "|---|---|---|---|---:|---:|---:|---:|"
for w in $CONFIGS; do
    grep '^BENCH_WALL output=' "$WORK/$w.out" | while read -r line; do
        echo "| $w | $(field "$line" output) | $(field "$line" size) | $(field "$line" display) |" \
            "$(ms "$line") | $(num "$line" fps 2) |" \
            "$(num "$line" mpix_s 2) | $(num "$line" display_ms 2) |"
    done
done
echo
echo "### Handing frames to the outputs, against $first_display"
echo
echo "The whole wall's frame time with each display against $first_display, round by round (median of the"
echo "differences and of the ratios), and the display stage per frame and output: in the whole wall"
echo "(thread 0 hands every output its frame in turn) and alone. *convert* is the 8-bit sRGB XRGB8888"
echo "encoding a scan-out display does with a float frame (without the device's buffers), on thread 0"
echo "in the display stage: a cached float frame + a copy. *convert-tiles* is the same encoding done by"
echo "the render threads as each tile finishes, into a ring of four buffers: what the DRM display does"
echo "with its scan-out buffers (this machine has no DRM device, so these are cached buffers, not"
echo "write-combined scan-out memory; in the qemu guest virtio-gpu's dumb buffers are cached too)."
echo
echo "| wall | display | whole wall ms | cost ms a frame | ratio | display ms per output: whole / alone |"
echo "|---|---|---:|---:|---:|---:|"
for w in $CONFIGS; do
    grep '^BENCH_WALL_DISPLAY ' "$WORK/$w.out" | while read -r line; do
        echo "| $w | $(field "$line" display) | $(num "$line" wall_ms 1) | $(num "$line" cost_ms 1) |" \
            "**$(num "$line" cost_ratio 3)** | $(num "$line" display_ms_per_output 2) /" \
            "$(num "$line" alone_display_ms_per_output 2) |"
    done
done
echo
files=
for w in $CONFIGS; do files="$files $WORK/$w.out"; done
# shellcheck disable=SC2086 # a list of paths without spaces (mktemp)
noise=$(grep -h '^BENCH_WALL_NOISE ' $files | tr ' ' '\n' | awk -F= '
    { sum[$1] += $2 } END { printf "%d %d %d %.0f", sum["runs"], sum["repeated"], sum["noisy"], sum["waited_s"] }')
# shellcheck disable=SC2086 # four numbers, split on purpose
set -- $noise
echo "Noise: $1 measured runs; noisy runs thrown away and run again: $2; rounds kept although noisy in all 4"
echo "runs: $3; waiting for quiet moments before runs: $4 s. The raw output: \`$WORK/*.out\` (not kept in"
echo "the repository)."
echo
} > "$WORK/section.md"
cat "$WORK/section.md"
# into BENCHMARKS.md: in place of the old "## Wall" section, else before "## The pipeline"
awk -v section="$WORK/section.md" '
    function put() { while ((getline l < section) > 0) print l; done = 1 }
    /^## Wall$/ { put(); skip = 1; next }
    skip && /^## / { skip = 0 }
    skip { next }
    /^## The pipeline$/ && !done { put() }
    { print }
    END { if (!done) put() }' BENCHMARKS.md > "$WORK/BENCHMARKS.md"
cp "$WORK/BENCHMARKS.md" BENCHMARKS.md
echo "bench_wall: BENCHMARKS.md updated" >&2
