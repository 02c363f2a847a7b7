#!/bin/sh
# bench_remote.sh - the remote view's benchmark, the "## Remote view" section
# of BENCHMARKS.md (make bench-remote): build/bench-remote drives a kiosk
# (tessera run --remote 0, the built-in scene, a 640x360 wall and a 1280x720 view,
# display null, threads = CPUs) from one headless Chromium page and measures
# the latency from an input event in the page to the first frame showing its
# effect (p50/p95 over BENCH_REMOTE_EVENTS single drag steps, default 100),
# the frames per second the page shows and the JPEG bytes a frame (over
# BENCH_REMOTE_SECONDS, default 5, camera still), at quality 80 / 4:2:0 (the
# default) and then at the other knob settings with BENCH_REMOTE_KNOB_EVENTS
# (30) events each. Prints the section and writes it into BENCHMARKS.md
# (BENCH_REMOTE_OUT names another file; "-" for none).
set -eu
cd "$(dirname "$0")/.."
BENCH_NAME=bench_remote
. tools/bench_lib.sh
OUT=${BENCH_REMOTE_OUT:-BENCHMARKS.md}
EVENTS=${BENCH_REMOTE_EVENTS:-100}
KNOB_EVENTS=${BENCH_REMOTE_KNOB_EVENTS:-30}
SECONDS_STILL=${BENCH_REMOTE_SECONDS:-5}
[ -x ./tessera ] && [ -x build/bench-remote ] || { echo "bench_remote: run make bench-remote" >&2; exit 1; }
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessera-bench-remote.XXXXXX")
cp ./tessera build/bench-remote "$WORK/"
load_before=$(cat /proc/loadavg)
date_utc=$(date -u '+%Y-%m-%d %H:%M UTC')
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
: > "$WORK/lines"
for setting in "80 420 $EVENTS" "50 420 $KNOB_EVENTS" "95 420 $KNOB_EVENTS" "80 444 $KNOB_EVENTS" "95 444 $KNOB_EVENTS"; do
    # shellcheck disable=SC2086
    set -- $setting
    echo "bench_remote: quality $1, $2, $3 events" >&2
    "$WORK/bench-remote" "$WORK/tessera" "$1" "$2" "$3" "$SECONDS_STILL" >> "$WORK/lines"
done
load_after=$(cat /proc/loadavg)
SECTION=$WORK/section.md
{
    echo "## Remote view"
    echo
    echo "$date_utc, revision $revision; $(nproc) CPUs, ${cpu:-unknown CPU} (lscpu); load average before $load_before, after $load_after. \`make bench-remote\` (\`tools/bench_remote.sh\`)."
    echo
    echo "The kiosk (\`tessera run --remote 0 --display null --size 640x360\`: a small wall, so the view is most of the work; the built-in scene, $(nproc) render threads) with a"
    echo "1280x720 remote view, watched by one headless Chromium page on the same machine (so the browser's decoding shares"
    echo "the CPUs with the renderer). *Latency*: from the page handling a pointer event of a drag to the page having drawn the"
    echo "first frame whose camera is newer (one drag step at a time). *fps* and *KB a frame*: what the page showed over"
    echo "$SECONDS_STILL s with the camera still; *wall fps*: the kiosk's own frames per second over the whole run (the wall and"
    echo "the view render together)."
    echo
    echo "| JPEG quality | subsampling | events | latency p50 ms | p95 ms | max ms | page fps | KB a frame | wall fps |"
    echo "|---:|---|---:|---:|---:|---:|---:|---:|---:|"
    while read -r line; do
        printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s |\n' "$(kv "$line" quality)" "$(kv "$line" subsampling)" \
            "$(kv "$line" events)" "$(kv "$line" p50_ms)" "$(kv "$line" p95_ms)" "$(kv "$line" max_ms)" \
            "$(kv "$line" fps)" "$(kv "$line" kb_per_frame)" "$(kv "$line" wall_fps)"
    done < "$WORK/lines"
    echo
} > "$SECTION"
cat "$SECTION"
[ "$OUT" = "-" ] || replace_section "$OUT" "## Remote view" "$SECTION" "$WORK/out.md"
rm -rf "$WORK"
