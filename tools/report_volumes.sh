#!/bin/sh
# report_volumes.sh - volumes' speed against error, the "## Volumes" section
# of REPORT.md (make report-volumes): on the shared MRI and CT volumes
# (../shared/data/volumes; a missing one is skipped),
#   iso-surfaces: the three root methods (linear interpolation per cell, a
#     few regula-falsi steps, exact with the cubic's extrema isolated), their
#     Mrays/s (tessera bench, 1920x1080, 2 threads, median of the frames)
#     against their error: each method's hit distance against the exact
#     one's along the same rays (tessera trace, 480x270 rays of the scene's
#     camera), in cells (|dt| |d| / smallest spacing), mean and max, and the
#     rays where one hits and the other does not;
#   direct volume rendering: step 2, 1, 0.5, 0.25 voxels, pre-integration off
#     and on, frame time (tessera bench, 1920x1080, 2 threads) against mean
#     FLIP (tessera compare) of a 960x540 picture against the step-1/64
#     picture without pre-integration.
# With gnuplot (sh tools/deps.sh --report) both as curves too,
# report/volumes_iso.png and report/volumes_dvr.png beside REPORT.md.
# Prints the section, keeps it in $WORK/volumes_section.md and puts it into
# REPORT.md in place of its old section, else at the end (REPORT_VOLUMES_OUT
# names another file; "-" for none). Environment: TESSERA_SHARED (../shared),
# TMPDIR, REPORT_VOLUMES_FRAMES (3). Needs ./tessera and python3.
set -eu

cd "$(dirname "$0")/.."
. tools/bench_lib.sh # replace_section
SHARED=${TESSERA_SHARED:-../shared}
DATA=$SHARED/data/volumes
OUT=${REPORT_VOLUMES_OUT:-REPORT.md}
FRAMES=${REPORT_VOLUMES_FRAMES:-3}
[ -x ./tessera ] || { echo "report_volumes: ./tessera not found (make tessera)" >&2; exit 1; }
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessera-report-volumes.XXXXXX")
echo "report_volumes: work directory $WORK" >&2
DATA_ABS=$(cd "$DATA" 2>/dev/null && pwd) || { echo "report_volumes: $DATA missing" >&2; exit 1; }

kv() { printf '%s\n' "$1" | tr ' \t' '\n\n' | sed -n "s/^$2=//p" | head -n 1; }

# name|header|iso value|transfer (JSON)|camera eye|look_at|up|smallest spacing
# (the CT's values are Hounsfield units + 1024: ct-bone over the range it was
# made for, [-1000, 2000] HU; its automatic range, the data's [-2000, 2648],
# would put the air on the opacity ramp, a haze nothing can skip)
VOLUMES='mri|colin27_ch2better_301x370x316_uint8.txt|40|"mri-soft"|260,-200,150|0,-18,0|0,0,1|0.5
ct|ctbunny_sub2_256x256x181_uint16.txt|900|{"map": "ct-bone", "range": [24, 3024]}|-60,-260,160|0,0,78|0,0,1|0.675782'

scene() { # file volume-entry camera-eye look-at up -> a scene JSON
    printf '{"camera": {"eye": [%s], "look_at": [%s], "up": [%s], "fov_deg": 40}, "volumes": [%s]}\n' "$3" "$4" "$5" "$2" > "$1"
}

# the rays of a camera (480 x 270, pixel centres): tessera trace's 32-byte records
rays() { # eye look_at up file
    python3 - "$1" "$2" "$3" "$4" <<'EOF'
import math, struct, sys
e = [float(x) for x in sys.argv[1].split(',')]; l = [float(x) for x in sys.argv[2].split(',')]
u = [float(x) for x in sys.argv[3].split(',')]
w, h, fov = 480, 270, 40.0
f = [l[i] - e[i] for i in range(3)]; n = math.sqrt(sum(x * x for x in f)); f = [x / n for x in f]
r = [f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]]
n = math.sqrt(sum(x * x for x in r)); r = [x / n for x in r]
v = [r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2], r[0] * f[1] - r[1] * f[0]]
th = math.tan(math.radians(fov) / 2); tw = th * w / h
with open(sys.argv[4], 'wb') as out:
    for y in range(h):
        for x in range(w):
            sx = (2 * (x + 0.5) / w - 1) * tw; sy = (1 - 2 * (y + 0.5) / h) * th
            d = [f[i] + sx * r[i] + sy * v[i] for i in range(3)]
            out.write(struct.pack('<8f', e[0], e[1], e[2], d[0], d[1], d[2], 0.0, float('inf')))
EOF
}

# error of hits B against hits A, in cells: "mean max differ" (rays' |d| from RAYS)
hit_error() { # rays hitsA hitsB spacing
    python3 - "$1" "$2" "$3" "$4" <<'EOF'
import math, struct, sys
rays = open(sys.argv[1], 'rb').read(); a = open(sys.argv[2], 'rb').read(); b = open(sys.argv[3], 'rb').read()
sp = float(sys.argv[4]); n = len(a) // 20
tot = 0.0; mx = 0.0; cnt = 0; differ = 0
for i in range(n):
    ta = struct.unpack_from('<f', a, 20 * i)[0]; tb = struct.unpack_from('<f', b, 20 * i)[0]
    if math.isinf(ta) != math.isinf(tb):
        differ += 1; continue
    if math.isinf(ta):
        continue
    d = struct.unpack_from('<3f', rays, 32 * i + 12); dl = math.sqrt(sum(x * x for x in d))
    e = abs(ta - tb) * dl / sp; tot += e; mx = max(mx, e); cnt += 1
print("%.3g %.3g %d %d" % (tot / cnt if cnt else 0, mx, differ, cnt))
EOF
}

cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
ISO_ROWS=$WORK/iso.md
DVR_ROWS=$WORK/dvr.md
: > "$ISO_ROWS"
: > "$DVR_ROWS"
echo "$VOLUMES" | while IFS='|' read -r name header iso tf eye at up spacing; do
    [ -f "$DATA/$header" ] || { echo "report_volumes: $DATA/$header missing: skipped" >&2; continue; }
    file=$DATA_ABS/$header
    rays "$eye" "$at" "$up" "$WORK/$name.rays"
    for method in exact regula-falsi linear; do
        scene "$WORK/$name-$method.json" "{\"file\": \"$file\", \"iso\": [{\"value\": $iso, \"method\": \"$method\"}]}" "$eye" "$at" "$up"
        line=$(./tessera bench --scene "$WORK/$name-$method.json" --size 1920x1080 --frames "$FRAMES" --threads 2 2> /dev/null | grep '^BENCH ')
        ./tessera trace --scene "$WORK/$name-$method.json" --rays "$WORK/$name.rays" --hits "$WORK/$name-$method.hits" --threads 2 2> /dev/null
        err=$(hit_error "$WORK/$name.rays" "$WORK/$name-exact.hits" "$WORK/$name-$method.hits" "$spacing")
        echo "report_volumes: $name iso $iso $method: $(kv "$line" prim_mrays) Mrays/s, error $err" >&2
        set -- $err
        printf '| %s | %s | %s | %s | %s | %s | %s |\n' "$name" "$iso" "$method" "$(kv "$line" prim_mrays)" "$1" "$2" "$3" >> "$ISO_ROWS"
        printf '%s %s "%s"\n' "$(kv "$line" prim_mrays)" "$1" "$method" >> "$WORK/iso-$name.dat"
    done
    scene "$WORK/$name-ref.json" "{\"file\": \"$file\", \"dvr\": {\"transfer\": $tf, \"step\": 0.015625}}" "$eye" "$at" "$up"
    ./tessera render --scene "$WORK/$name-ref.json" --size 960x540 --threads 2 --out "$WORK/$name-ref.exr" > /dev/null 2>&1
    for pre in false true; do
        for step in 2 1 0.5 0.25; do
            tag=$name-$step-$pre
            scene "$WORK/$tag.json" "{\"file\": \"$file\", \"dvr\": {\"transfer\": $tf, \"step\": $step, \"preintegrated\": $pre}}" "$eye" "$at" "$up"
            ./tessera render --scene "$WORK/$tag.json" --size 960x540 --threads 2 --out "$WORK/$tag.exr" > /dev/null 2>&1
            flip=$(kv "$(./tessera compare "$WORK/$name-ref.exr" "$WORK/$tag.exr" 2> /dev/null)" flip_mean)
            line=$(./tessera bench --scene "$WORK/$tag.json" --size 1920x1080 --frames "$FRAMES" --threads 2 2> /dev/null | grep '^BENCH ')
            echo "report_volumes: $name dvr step $step pre-integrated $pre: $(kv "$line" frame_ms_median) ms, FLIP $flip" >&2
            printf '| %s | %s | %s | %s | %s |\n' "$name" "$step" "$([ $pre = true ] && echo on || echo off)" "$(kv "$line" frame_ms_median)" "$flip" >> "$DVR_ROWS"
            printf '%s %s "%s"\n' "$(kv "$line" frame_ms_median)" "$flip" "$step" >> "$WORK/dvr-$name-$pre.dat"
        done
    done
done

# The curves (gnuplot, when there is one: sh tools/deps.sh --report): Mrays/s
# against hit error per root method, frame time against FLIP per step.
PLOTS=""
if command -v gnuplot > /dev/null 2>&1; then
    term=pngcairo
    gnuplot -e 'set terminal' 2>&1 | grep -q pngcairo || term=png
    series() { # pattern title-sed -> plot clauses for every .dat matching
        for f in $WORK/$1; do
            [ -f "$f" ] || continue
            t=$(basename "$f" .dat | sed "$2")
            printf "'%s' using 1:2 with linespoints pointtype 7 title '%s', '%s' using 1:2:3 with labels left offset char 1,0 notitle, " "$f" "$t" "$f"
        done
    }
    {
        echo "set terminal $term size 900,600"
        echo "set output '$WORK/volumes_iso.png'"
        echo "set title 'Iso-surface root methods: speed against hit error'"
        echo "set xlabel 'Mrays/s (1920x1080, 2 threads, median of $FRAMES frames)'"
        echo "set ylabel 'mean hit error against the exact method (cells)'"
        echo "set grid"
        echo "set offsets graph 0.1, graph 0.2, graph 0.1, graph 0.1"
        printf 'plot %s\n' "$(series 'iso-*.dat' 's/^iso-//')" | sed 's/, $//'
        echo "set output '$WORK/volumes_dvr.png'"
        echo "set title 'Direct volume rendering: frame time against error, points labelled by step (voxels)'"
        echo "set xlabel 'frame time (ms, 1920x1080, 2 threads, median of $FRAMES frames)'"
        echo "set ylabel 'mean FLIP against step 1/64 without pre-integration'"
        echo "set logscale xy"
        printf 'plot %s\n' "$(series 'dvr-*.dat' 's/^dvr-//; s/-false$/, classic/; s/-true$/, pre-integrated/')" | sed 's/, $//'
    } > "$WORK/volumes.gp"
    if gnuplot "$WORK/volumes.gp" 2> "$WORK/gnuplot.err"; then
        PLOTS="volumes_iso.png volumes_dvr.png"
    else
        echo "report_volumes: gnuplot failed (no plots): $(head -n 3 "$WORK/gnuplot.err")" >&2
    fi
else
    echo "report_volumes: no gnuplot (sh tools/deps.sh --report): tables without plots" >&2
fi

SECTION=$WORK/volumes_section.md
{
    echo "## Volumes: iso-surface root methods and volume-rendering step"
    echo
    echo "$(date -u '+%Y-%m-%d %H:%M UTC'), revision $(git rev-parse --short HEAD 2>/dev/null || echo unknown); $(nproc) CPUs, ${cpu:-unknown CPU} (lscpu); load average at start $(cut -d' ' -f1-3 /proc/loadavg). \`sh tools/report_volumes.sh\`."
    echo
    echo "**Iso-surfaces** (the kind ray traces the trilinear field directly). Mrays/s: \`tessera bench\`, 1920x1080, 2 threads, median of $FRAMES frames. Error: each method's hit distance against the exact method's along the same 480x270 rays (\`tessera trace\`), in cells (smallest spacing); *differ*: rays that hit with one method and miss with the other (a double crossing inside one cell that linear interpolation steps over)."
    echo
    echo "| volume | iso | method | Mrays/s | mean error (cells) | max error (cells) | rays that differ |"
    echo "|---|---:|---|---:|---:|---:|---:|"
    cat "$ISO_ROWS"
    echo
    [ -z "$PLOTS" ] || { echo "![Mrays/s against hit error per root method](report/volumes_iso.png)"; echo; }
    echo "**Direct volume rendering** (emission-absorption through the transfer function, midpoint samples or pre-integrated slabs). Frame time: \`tessera bench\`, 1920x1080, 2 threads, median of $FRAMES frames. FLIP: mean LDR-FLIP of a 960x540 picture against the same view at step 1/64 voxel without pre-integration."
    echo
    echo "| volume | step (voxels) | pre-integration | frame ms | mean FLIP |"
    echo "|---|---:|---|---:|---:|"
    cat "$DVR_ROWS"
    [ -z "$PLOTS" ] || { echo; echo "![frame time against FLIP per step, classic and pre-integrated](report/volumes_dvr.png)"; }
} > "$SECTION"
cat "$SECTION"
[ "$OUT" = "-" ] && exit 0
if [ -n "$PLOTS" ]; then
    mkdir -p "$(dirname "$OUT")/report"
    for p in $PLOTS; do cp "$WORK/$p" "$(dirname "$OUT")/report/$p"; done
fi
replace_section "$OUT" "$(head -n 1 "$SECTION")" "$SECTION" "$WORK/out.md"
echo "report_volumes: $OUT updated" >&2
