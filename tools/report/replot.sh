#!/bin/sh
# replot.sh - redraw one section's plots of REPORT.md from its measurements
# in report/KNOB.tsv, measuring nothing (after a change to the plotting in
# tools/report/lib.sh or the knob's series):
#
#   sh tools/report/replot.sh KNOB SIZE RUNS THREADS
#   sh tools/report/replot.sh crop MONTAGE A_CAPTION B_CAPTION A_NAME B_NAME
#       ('|' in a caption breaks the line)
#
# KNOB: antialiasing, render_scale, transparency or ao; SIZE, RUNS, THREADS:
# what the section was measured with (its text in REPORT.md says), for the x
# axis's label. Writes report/KNOB_flip.png and report/KNOB_rmse.png.
#
# crop: captions a crop montage that report_crops made before it captioned
# them (report/*_crop_*.png of an older run), in place: above, "reference"
# and the captions; below, the FLIP maps of A_NAME and B_NAME. A montage
# already captioned is refused.
# shellcheck shell=sh disable=SC1090,SC2034
set -eu
usage() { echo "usage: sh tools/report/replot.sh KNOB SIZE RUNS THREADS | crop MONTAGE A_CAPTION B_CAPTION A_NAME B_NAME" >&2; exit 2; }
[ $# -ge 1 ] || usage
[ "$1" != crop ] || [ $# -eq 6 ] || usage
[ "$1" = crop ] || [ $# -eq 4 ] || usage
cd "$(dirname "$0")/../.."
GNUPLOT=${GNUPLOT:-gnuplot}
command -v "$GNUPLOT" > /dev/null 2>&1 || { echo "replot.sh: no gnuplot (sh tools/deps.sh --report)" >&2; exit 1; }
if "$GNUPLOT" -e 'set terminal' 2>&1 | grep -q pngcairo; then
    GNUPLOT_TERM="pngcairo font 'sans,11'"
else
    GNUPLOT_TERM=png
fi
WORK=$(mktemp -d)
trap '[ -n "${KEEP_WORK:-}" ] || rm -rf "$WORK"' EXIT
. tools/report/lib.sh
if [ "$1" = crop ]; then
    # width and height: big-endian at bytes 16 and 20 of a PNG
    w=$(od -An -tu1 -j16 -N4 "$2" | awk '{ print $1 * 16777216 + $2 * 65536 + $3 * 256 + $4 }')
    h=$(od -An -tu1 -j20 -N4 "$2" | awk '{ print $1 * 16777216 + $2 * 65536 + $3 * 256 + $4 }')
    cell=$(((w - 8) / 3))
    if [ $((3 * cell + 8)) -ne "$w" ] || [ $((2 * cell + 4)) -ne "$h" ]; then
        echo "replot.sh: $2 ($w x $h) is not a bare 3 x 2 montage (captioned already?)" >&2
        exit 1
    fi
    cp "$2" "$WORK/bare.png"
    mkdir -p "$WORK/plots"
    report_caption_montage "$WORK/bare.png" "$WORK/captioned.png" "$cell" reference "$3" "$4" \
        "FLIP maps:|black 0, pale yellow 1" "FLIP map of|$5" "FLIP map of|$6"
    cp "$WORK/captioned.png" "$2"
    echo "captioned $2"
    exit 0
fi
KNOB=$1 SIZE=$2 RUNS=$3 THREADS=$4
case $KNOB in
    antialiasing) plots=aa_plots ;;
    render_scale) plots=rs_plots ;;
    transparency) plots=tr_plots ;;
    ao) plots=ao_plots ;;
    *) echo "replot.sh: no plots for knob '$KNOB'" >&2; exit 2 ;;
esac
[ -f "report/$KNOB.tsv" ] || { echo "replot.sh: report/$KNOB.tsv missing" >&2; exit 1; }
. "tools/report/knob_$KNOB.sh"
cp "report/$KNOB.tsv" "$WORK/"
$plots
cp "$WORK/plots/${KNOB}_flip.png" "$WORK/plots/${KNOB}_rmse.png" report/
echo "wrote report/${KNOB}_flip.png report/${KNOB}_rmse.png"
