#!/bin/sh
# report.sh - the speed-against-error report (issue 13): writes REPORT.md and
# report/*.png (gnuplot) with one section per quality knob, each a curve of
# frame time against error (mean FLIP and RMSE, `tessera compare`) on named
# scenes against a converged reference. `make report` runs it after
# `tools/deps.sh --report` and building ./tessera, build/report_img,
# build/gen-assembly (the transparency and ao knobs' assembly) and
# build-unrobust/tessera (make unrobust: the robustness knob's fast mode).
#
# The knobs: antialiasing (samples per pixel), render_scale (render at a
# fraction of the size, upscale), governor (the frame-budget governor along a
# path), robustness (the robust intersection kernels), transparency
# (renderer.transparency.min_transmittance and max_layers at opacity 0.3) and
# ao (the ao renderer's rays per hit, filter and accumulated frames). The
# transparency and ao knobs add a generated 10,000-part assembly of their own
# and measure against a reference of their own (lib.sh,
# report_knob_reference: the same pixel-centre rays with the knob's limits
# removed), not the scenes' jittered means.
#
# A knob is one file, tools/report/knob_NAME.sh, defining knob_NAME (called
# with the scene labels; it writes $WORK/section_NAME.md and its pictures into
# $WORK/plots/), and one word in KNOBS below. lib.sh has what they share.
#
# Environment (defaults in brackets):
#   REPORT_SIZE        image size [1920x1080]
#   REPORT_RUNS        timed runs per point, median taken [3]
#   REPORT_FRAMES      frames per timed run [4]
#   REPORT_THREADS     render threads [2]
#   REPORT_KNOBS       the knobs to run, a subset of KNOBS [all]
#   REPORT_ROBUST_SMALL 1: the robustness knob runs `tessera robust --small` [0]
#   REPORT_BUDGET_MS   the governor knob's frame budget in ms (`--budget-ms`) [40]
#   REPORT_REF_K, REPORT_REF_RENDERS  reference: RENDERS renders of jittered:K averaged [16, 4]
#   REPORT_CACHE       where references are kept between runs [/tmp/report-cache]
#   REPORT_OUT         where REPORT.md and report/ go [the repository root]
#   REPORT_KEEP        1: keep the work directory after a good run [0]
#   TESSERA_SHARED     the shared data (meshes) [../shared]; scenes missing there are skipped
#   GNUPLOT            the gnuplot program [gnuplot]
# shellcheck disable=SC2034,SC2154
# (SC2034, SC2154: the per-scene SCENE_ARG_x, SCENE_NOTE_x are read back through eval)
set -eu

cd "$(dirname "$0")/../.."
ROOT=$(pwd)
. tools/report/lib.sh

# the knobs, in report order (tools/report/knob_NAME.sh each)
KNOBS="antialiasing render_scale governor robustness transparency ao"

SIZE=${REPORT_SIZE:-1920x1080}
RUNS=${REPORT_RUNS:-3}
FRAMES=${REPORT_FRAMES:-4}
THREADS=${REPORT_THREADS:-2}
BUDGET_MS=${REPORT_BUDGET_MS:-40}
REFERENCE_K=${REPORT_REF_K:-16}
REFERENCE_RENDERS=${REPORT_REF_RENDERS:-4}
CACHE=${REPORT_CACHE:-/tmp/report-cache}
OUT=${REPORT_OUT:-$ROOT}
SHARED=${TESSERA_SHARED:-../shared}
GNUPLOT=${GNUPLOT:-gnuplot}
RUN_KNOBS=${REPORT_KNOBS:-$KNOBS}
CROP_AT_1080=256 # crop edge in pixels at 1080 rows (scaled with the image height)

# ---- check everything before measuring anything ----
WORK=""
case $SIZE in
    *[!0-9x]* | x* | *x | *x*x*) report_fail "REPORT_SIZE '$SIZE': expected WxH, e.g. 1920x1080" ;;
    *x*) ;;
    *) report_fail "REPORT_SIZE '$SIZE': expected WxH, e.g. 1920x1080" ;;
esac
for v in RUNS FRAMES THREADS REFERENCE_K REFERENCE_RENDERS; do
    eval "val=\$$v"
    case $val in
        '' | *[!0-9]* | 0) report_fail "REPORT_$v '$val': expected a whole number >= 1" ;;
    esac
done
case $BUDGET_MS in
    '' | *[!0-9.]* | *.*.* | .*) report_fail "REPORT_BUDGET_MS '$BUDGET_MS': expected milliseconds > 0, e.g. 40 or 33.3" ;;
esac
awk -v b="$BUDGET_MS" 'BEGIN { exit !(b > 0) }' || report_fail "REPORT_BUDGET_MS '$BUDGET_MS': expected milliseconds > 0"
[ $((REFERENCE_RENDERS % 2)) -eq 0 ] || report_fail "REPORT_REF_RENDERS $REFERENCE_RENDERS: expected an even number (the halves check convergence)"
command -v "$GNUPLOT" > /dev/null 2>&1 ||
    report_fail "gnuplot not found ('$GNUPLOT'): install Debian gnuplot-nox (sh tools/deps.sh --report, as root)"
if "$GNUPLOT" -e 'set terminal' 2>&1 | grep -q pngcairo; then
    GNUPLOT_TERM="pngcairo font 'sans,11'"
elif "$GNUPLOT" -e 'set terminal' 2>&1 | grep -q ' png '; then
    GNUPLOT_TERM=png
else
    report_fail "$GNUPLOT has neither the pngcairo nor the png terminal (Debian gnuplot-nox has both)"
fi
[ -x ./tessera ] || report_fail "./tessera not built: run 'make tessera' (or make report)"
[ -x build/report_img ] || report_fail "build/report_img not built: run 'make build/report_img' (or make report)"
for k in $RUN_KNOBS; do
    case " $KNOBS " in
        *" $k "*) ;;
        *) report_fail "REPORT_KNOBS: unknown knob '$k' (known: $KNOBS)" ;;
    esac
    [ -f "tools/report/knob_$k.sh" ] || report_fail "tools/report/knob_$k.sh missing"
    # shellcheck source=tools/report/knob_antialiasing.sh
    . "tools/report/knob_$k.sh"
done
for tool in awk sed sort sha256sum mktemp; do
    command -v "$tool" > /dev/null 2>&1 || report_fail "'$tool' not found"
done

WORK=$(mktemp -d /tmp/report-run.XXXXXX)
: > "$WORK/report.log"
# copies, so a rebuild during the run changes nothing measured
TESSERA=$WORK/tessera
REPORT_IMG=$WORK/report_img
cp ./tessera "$TESSERA"
cp build/report_img "$REPORT_IMG"

# ---- scenes: the built-in one always, the shared meshes when present ----
SCENES="default"
SCENE_ARG_default=default
SCENE_NOTE_default="the built-in default scene (\`--scene default\`: 9218 triangles, 7 spheres, 2 lights), its own camera"
SKIPPED=""
dragon=$SHARED/data/meshes/stanford_dragon_vrip.ply
if [ -f "$dragon" ]; then
    SCENES="$SCENES dragon"
    SCENE_ARG_dragon=$dragon
    SCENE_NOTE_dragon="the Stanford dragon (\`$dragon\`, 871,414 triangles, framed by tessera's rule for a mesh file)"
else
    SKIPPED="$SKIPPED dragon ($dragon not found)"
fi

# ---- measure ----
load_before=$(cat /proc/loadavg)
start=$(date +%s)
date_utc=$(date -u '+%Y-%m-%d %H:%M UTC')
echo "report: $SIZE, $RUNS runs x $FRAMES frames, $THREADS threads; scenes: $SCENES; knobs: $RUN_KNOBS; work in $WORK" >&2
for scene in $SCENES; do
    report_reference "$scene"
done
for k in $RUN_KNOBS; do
    # shellcheck disable=SC2086
    "knob_$k" $SCENES
    [ -f "$WORK/section_$k.md" ] || report_fail "knob $k wrote no section"
done
load_after=$(cat /proc/loadavg)
took=$(($(date +%s) - start))

# ---- write ----
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ "$revision" != unknown ] && ! git diff --quiet HEAD 2>/dev/null; then
    revision="$revision (plus uncommitted changes)"
fi
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
[ -n "$cpu" ] || cpu=$(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo | head -n 1)
isa=$(sed -n 's/.*(\([a-z0-9]*\) kernels).*/\1/p' "$WORK/report.log" | head -n 1)
report=$WORK/REPORT.md
{
    echo "# Speed against error"
    echo
    echo "Written by \`make report\` (\`tools/report/report.sh\`): for each quality knob, frame time against"
    echo "error (mean FLIP and RMSE, \`tessera compare\`) against a converged reference."
    echo
    echo "- date: $date_utc; tessera revision $revision; kernels ${isa:-?}"
    echo "- machine: $(nproc) CPUs, ${cpu:-unknown CPU} (lscpu); $THREADS render threads"
    echo "- load average (/proc/loadavg) before: $load_before; after: $load_after"
    if awk -v l="${load_before%% *}" 'BEGIN { exit !(l > 0.5) }'; then
        echo "- **the machine was busy** before the run (1-minute load ${load_before%% *} on $(nproc) CPUs): the frame"
        echo "  times are not a quiet machine's; the errors do not depend on load"
    fi
    echo "- image size $SIZE; $RUNS timed runs per point of $FRAMES frames each (median of the runs)"
    if [ "$SIZE" != 1920x1080 ]; then
        echo "- **reduced size**: the issue's numbers are at 1920x1080 (\`make report\` with no REPORT_SIZE)"
    fi
    echo "- the whole run took $((took / 60)) min $((took % 60)) s"
    echo
    echo "## Scenes and references"
    echo
    for scene in $SCENES; do
        eval "note=\$SCENE_NOTE_$scene"
        report_reference "$scene"
        echo "- **$scene**: $note."
        echo "  Reference: the mean of $REFERENCE_RENDERS renders of jittered:$REFERENCE_K ($REFERENCE_K×$REFERENCE_K strata, seeds"
        echo "  1..$REFERENCE_RENDERS; the curves use seed 0), so $((REFERENCE_RENDERS * REFERENCE_K * REFERENCE_K)) rays per pixel, averaged in double"
        echo "  (\`build/report_img mean\`), kept as linear EXR in $CACHE (key: scene, size, recipe and the"
        echo "  sources of engine/, app/, wall/); made in $REF_SECONDS s. Its two halves"
        echo "  ($((REFERENCE_RENDERS / 2 * REFERENCE_K * REFERENCE_K)) rays per pixel each) against each other: \`$REF_HALVES\`."
    done
    if [ -n "$SKIPPED" ]; then
        echo "- skipped:$SKIPPED (TESSERA_SHARED=$SHARED)"
    fi
    echo
    for k in $RUN_KNOBS; do
        cat "$WORK/section_$k.md"
        echo
    done
} > "$report"

mkdir -p "$OUT/report"
rm -f "$OUT"/report/*.png "$OUT"/report/*.tsv
cp "$WORK"/plots/*.png "$WORK"/plots/*.tsv "$OUT/report/"
mv "$report" "$OUT/REPORT.md"
echo "report: wrote $OUT/REPORT.md and $(ls "$OUT"/report | wc -l) files in $OUT/report/ in $((took / 60)) min $((took % 60)) s" >&2
if [ "${REPORT_KEEP:-0}" = 1 ]; then
    echo "report: work files kept in $WORK" >&2
else
    rm -rf "$WORK"
fi
