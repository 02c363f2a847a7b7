#!/bin/sh
# report_remote.sh - the remote view's JPEG frames, speed against error: the
# "## Remote view" section of REPORT.md (make report-remote). For each scene
# (the built-in one; the shared dragon when present) a 1280x720 frame as the
# remote view's follow channel renders it (tessera render, linear EXR) is
# compressed at each JPEG quality with each chroma subsampling
# (build/report_img jpeg: remote/jpeg.h, TurboJPEG): bytes a frame and the
# median encode time against the mean LDR-FLIP (and PSNR) of the decoded
# frame against the lossless 8-bit one. With gnuplot (sh tools/deps.sh
# --report) also as curves, report/remote_jpeg_bytes.png and
# report/remote_jpeg_time.png beside REPORT.md.
# Prints the section, and puts it into REPORT.md in place of its old section,
# else at the end (REPORT_REMOTE_OUT names another file; "-" for none).
# Environment: TESSERA_SHARED (../shared), TMPDIR, REPORT_REMOTE_RUNS (9:
# encodes timed per point, median), REPORT_REMOTE_QUALITIES ("30 50 60 70 80
# 90 95"). Needs ./tessera and build/report_img.
set -eu

cd "$(dirname "$0")/.."
. tools/bench_lib.sh # replace_section
SHARED=${TESSERA_SHARED:-../shared}
OUT=${REPORT_REMOTE_OUT:-REPORT.md}
RUNS=${REPORT_REMOTE_RUNS:-9}
QUALITIES=${REPORT_REMOTE_QUALITIES:-30 50 60 70 80 90 95}
SIZE=1280x720
[ -x ./tessera ] || { echo "report_remote: ./tessera not found (make tessera)" >&2; exit 1; }
[ -x build/report_img ] || { echo "report_remote: build/report_img not found (make build/report_img)" >&2; exit 1; }
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessera-report-remote.XXXXXX")
echo "report_remote: work directory $WORK" >&2
cp ./tessera build/report_img "$WORK/" # copies: a rebuild during the run changes nothing measured

SCENES="default"
dragon=$SHARED/data/meshes/stanford_dragon_vrip.ply
[ -f "$dragon" ] && SCENES="$SCENES dragon"
scene_arg() { if [ "$1" = default ]; then echo default; else echo "$dragon"; fi; }

load_before=$(cat /proc/loadavg)
date_utc=$(date -u '+%Y-%m-%d %H:%M UTC')
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
for s in $SCENES; do
    "$WORK/tessera" render --scene "$(scene_arg "$s")" --size $SIZE --threads 2 --out "$WORK/$s.exr" > /dev/null 2>&1 ||
        { echo "report_remote: rendering $s failed" >&2; exit 1; }
    # shellcheck disable=SC2086
    "$WORK/report_img" jpeg "$WORK/$s.exr" "$RUNS" $QUALITIES > "$WORK/$s.tsv" ||
        { echo "report_remote: report_img jpeg on $s failed" >&2; exit 1; }
done
load_after=$(cat /proc/loadavg)

SECTION=$WORK/section.md
{
    echo "## Remote view: JPEG quality and chroma subsampling"
    echo
    echo "$date_utc, revision $revision; $(nproc) CPUs, ${cpu:-unknown CPU} (lscpu); load average before $load_before, after $load_after. \`sh tools/report_remote.sh\` (\`make report-remote\`)."
    echo
    echo "The remote view sends each viewer JPEG frames (\`remote/jpeg.h\`, TurboJPEG, fast DCT). A $SIZE frame of each scene"
    echo "(\`tessera render --size $SIZE\`, the follow channel's default size) is encoded at each quality and chroma subsampling;"
    echo "*encode* is the median of $RUNS encodes on one thread; the error is the decoded frame's against the lossless 8-bit"
    echo "frame (what the page would show without compression): mean LDR-FLIP (\`metrics/flip.h\`, 67 pixels per degree) and PSNR"
    echo "over the 8-bit codes. The float-to-8-bit conversion before encoding (the remote display's \`show()\`) is timed too."
    echo "Even quality 100 at 4:4:4 leaves a FLIP floor (codes off by one from the colour conversion's rounding, which FLIP's"
    echo "power curve weighs up), so compare FLIP between points, not against 0."
    echo
    for s in $SCENES; do
        convert=$(sed -n 's/^# convert_ms //p' "$WORK/$s.tsv")
        echo "**$s** (convert to 8-bit sRGB: $convert ms a frame)"
        echo
        echo "| subsampling | quality | KB a frame | encode ms | mean FLIP | PSNR dB |"
        echo "|---|---:|---:|---:|---:|---:|"
        grep -v '^#' "$WORK/$s.tsv" | awk -F '\t' '{ printf "| %s | %d | %.1f | %.2f | %.4f | %.2f |\n", $1, $2, $3 / 1024, $4, $5, $6 }'
        echo
    done
} > "$SECTION"

PLOTS=""
if command -v gnuplot > /dev/null 2>&1; then
    for s in $SCENES; do
        for sub in 444 422 420; do
            awk -F '\t' -v subsampling="$sub" '$1 == subsampling { print $3 / 1024, $4, $5 }' "$WORK/$s.tsv" > "$WORK/$s-$sub.dat"
        done
    done
    plot_cmd() { # column of x, x label, file
        first=1
        printf 'set terminal pngcairo size 900,560 font "sans,11"; set output "%s"; set xlabel "%s"; set ylabel "mean FLIP"; set key top right; set grid; plot ' "$WORK/$3" "$2"
        for s in $SCENES; do
            for sub in 444 422 420; do
                [ $first = 1 ] || printf ', '
                first=0
                printf '"%s" using %s:3 with linespoints title "%s %s"' "$WORK/$s-$sub.dat" "$1" "$s" "$sub"
            done
        done
        echo
    }
    if plot_cmd 1 "KB a frame" remote_jpeg_bytes.png | gnuplot && plot_cmd 2 "encode ms" remote_jpeg_time.png | gnuplot; then
        PLOTS="remote_jpeg_bytes.png remote_jpeg_time.png"
        {
            echo "![mean FLIP against KB a frame](report/remote_jpeg_bytes.png)"
            echo
            echo "![mean FLIP against encode time](report/remote_jpeg_time.png)"
            echo
        } >> "$SECTION"
    fi
fi
cat "$SECTION"
[ "$OUT" = "-" ] && exit 0
if [ -n "$PLOTS" ]; then
    mkdir -p "$(dirname "$OUT")/report"
    for p in $PLOTS; do cp "$WORK/$p" "$(dirname "$OUT")/report/$p"; done
fi
replace_section "$OUT" "$(head -n 1 "$SECTION")" "$SECTION" "$WORK/out.md"
rm -rf "$WORK"
echo "report_remote: $OUT updated" >&2
