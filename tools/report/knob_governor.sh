# knob_governor.sh - the frame-budget governor section of REPORT.md (issue
# 13: "the report plots frame time and FLIP per transaction along the path").
# Per scene one run of `tessera bench --path P --rate 30 --budget-ms B`: a
# sender thread queues one camera transaction per 1/30 s of the path while the
# pipeline renders in real time, the governor (engine/frame/governor.h) picking the
# render scale of each moving frame; the bench prints per transaction the
# frame that first showed it, its time, its scale and, for 16 of them spread
# over the path, the mean FLIP of that frame against the full-size
# one-ray-per-pixel frame of the same camera. Sourced by report.sh, which
# calls knob_governor with the scene labels; writes
# $WORK/section_governor.md and $WORK/plots/governor*.
#
# Unlike the other knobs this is not a curve of settings against a converged
# reference: it is one run per scene, and its frame times, scales and FLIP
# all depend on how busy the machine is (the governor answers load by
# lowering the scale). The section says how much CPU other programs took.
#
# Paths: the built-in scene follows configs/paths/orbit.json. That path is
# made for the built-in scene (a circle of radius 7.9 around (0, 0.6, 0)):
# the dragon (about 0.2 units long, near the origin) would be a few pixels in
# it. So the dragon follows the same orbit scaled and moved onto the dragon:
# centred on the look-at point of configs/scenes/dragon.json's camera, at
# that camera's distance and field of view (key times and angles unchanged;
# Catmull-Rom commutes with scaling and moving, so the curve is the orbit's
# too). It is made in $WORK on each run, not kept in configs/paths/.
#
# shellcheck shell=sh

GV_RATE=30         # transactions per second, as a user steering
GV_FLIP_SAMPLES=16 # transactions measured with FLIP (each ~4 s at 1080p, after the run)
GV_BUSY_PERCENT=5  # other programs above this share of the CPUs during a run: said so
GV_ORBIT=configs/paths/orbit.json
GV_DRAGON_SCENE=configs/scenes/dragon.json

# a / b to 2 decimals, and 100 a / b to whole percent
gv_ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }'; }
gv_percent() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.0f", (b > 0 ? 100 * a / b : 0) }'; }

# The path of a scene into GV_PATH, and a phrase saying what it is into
# GV_PATH_NOTE.
gv_path() { # scene label
    case $1 in
        default)
            GV_PATH=$GV_ORBIT
            GV_PATH_NOTE="\`$GV_ORBIT\` (one turn in 8 s at the scene's own camera's distance and height)"
            ;;
        dragon)
            gv_dragon_path
            GV_PATH=$WORK/governor-dragon-orbit.json
            GV_PATH_NOTE="\`$GV_ORBIT\` scaled by $GV_DRAGON_SCALE and moved onto the dragon: centred on ($GV_DRAGON_LOOK), the look-at point of \`$GV_DRAGON_SCENE\`'s camera, at that camera's distance ($GV_DRAGON_DIST) and field of view ($GV_DRAGON_FOV°); the same key times and angles (made afresh on each run, in the work directory)"
            ;;
        *) report_fail "knob governor: no camera path for scene '$1' (see tools/report/knob_governor.sh)" ;;
    esac
}

# The dragon's orbit: each key of orbit.json, eye' = c + s (eye - look_at),
# look_at' = c, fov' = the dragon camera's; s = the dragon camera's distance
# over the first orbit key's.
gv_dragon_path() {
    [ -f "$GV_DRAGON_SCENE" ] || report_fail "knob governor: $GV_DRAGON_SCENE missing (its camera places the dragon's path)"
    gd_cam=$(sed -n 's/^ *"camera": *{\(.*\)}.*/\1/p' "$GV_DRAGON_SCENE" | head -n 1 | tr -d '[]",:{}' |
        awk '{ for (i = 1; i <= NF; i++) if ($i ~ /^[a-z_]+$/) k = $i; else v[k] = v[k] " " $i }
            END { print v["eye"], v["look_at"], v["fov_deg"] }')
    # shellcheck disable=SC2086
    set -- $gd_cam
    [ $# -eq 7 ] || report_fail "knob governor: no camera {eye, look_at, fov_deg} on one line in $GV_DRAGON_SCENE (read: '$gd_cam')"
    GV_DRAGON_LOOK="$4, $5, $6"
    GV_DRAGON_FOV=$7
    GV_DRAGON_DIST=$(awk -v a="$1" -v b="$2" -v c="$3" -v x="$4" -v y="$5" -v z="$6" \
        'BEGIN { printf "%.4f", sqrt((a - x) ^ 2 + (b - y) ^ 2 + (c - z) ^ 2) }')
    # orbit.json's keys, one a line: time ex ey ez lx ly lz
    sed -n 's/.*"time": *\([^,]*\), *"eye": *\[\([^]]*\)\], *"look_at": *\[\([^]]*\)\].*/\1 \2 \3/p' "$GV_ORBIT" |
        tr -d ',' > "$WORK/governor-orbit-keys.txt"
    [ -s "$WORK/governor-orbit-keys.txt" ] || report_fail "knob governor: no keys read from $GV_ORBIT"
    gd_loop=$(sed -n 's/.*"loop": *\([a-z]*\).*/\1/p' "$GV_ORBIT" | head -n 1)
    GV_DRAGON_SCALE=$(awk -v d="$GV_DRAGON_DIST" 'NR == 1 {
            printf "%.5f", d / sqrt(($2 - $5) ^ 2 + ($3 - $6) ^ 2 + ($4 - $7) ^ 2) }' "$WORK/governor-orbit-keys.txt")
    awk -v s="$GV_DRAGON_SCALE" -v cx="$4" -v cy="$5" -v cz="$6" -v fov="$7" -v loop="${gd_loop:-false}" \
        -v from="$GV_ORBIT" -v scene="$GV_DRAGON_SCENE" '
        { t[NR] = $1; for (i = 2; i <= 7; i++) k[NR, i] = $i }
        END {
            print "// made by tools/report/knob_governor.sh: " from " scaled by " s " and moved"
            print "// onto the look-at point of the camera of " scene
            print "{"
            print "  \"format\": \"tessera-camera-path\","
            print "  \"version\": 1,"
            print "  \"interpolation\": \"catmull-rom\","
            print "  \"loop\": " loop ","
            print "  \"keyframes\": ["
            for (n = 1; n <= NR; n++)
                printf "    {\"time\": %s, \"eye\": [%.6f, %.6f, %.6f], \"look_at\": [%s, %s, %s], \"fov_deg\": %s}%s\n",
                    t[n], cx + s * (k[n, 2] - k[n, 5]), cy + s * (k[n, 3] - k[n, 6]), cz + s * (k[n, 4] - k[n, 7]),
                    cx, cy, cz, fov, (n < NR ? "," : "")
            print "  ]"
            print "}"
        }' "$WORK/governor-orbit-keys.txt" > "$WORK/governor-dragon-orbit.json"
}

# CPU seconds of all CPUs (/proc/stat), this shell's children's CPU seconds
# (the shell's `times`: run here, not in a $(...), whose subshell has children
# of its own) and the clock, appended to GV_CPU: what other programs took
# during a run is the difference of the first two between two calls.
gv_cpu() {
    times > "$WORK/governor-times.txt"
    GV_CPU="$GV_CPU $(awk '$1 == "cpu" { print ($2 + $3 + $4 + $7 + $8 + $9) / 100; exit }' /proc/stat 2>/dev/null || echo 0)"
    GV_CPU="$GV_CPU $(tail -n 1 "$WORK/governor-times.txt" |
        awk '{ s = 0; for (i = 1; i <= 2; i++) { split($i, p, "m"); s += p[1] * 60 + p[2] } print s }')"
    GV_CPU="$GV_CPU $(date +%s)"
}

knob_governor() { # scene labels...
    gv_out=$WORK/section_governor.md
    gv_tsv=$WORK/governor.tsv
    : > "$gv_tsv"
    : > "$WORK/governor-summary.txt"
    mkdir -p "$WORK/plots"
    for gv_scene in "$@"; do
        gv_path "$gv_scene"
        echo "report: governor, $gv_scene: bench --path along $GV_PATH, budget $BUDGET_MS ms" >&2
        GV_CPU=""
        gv_cpu
        report_run "$TESSERA" bench --path "$GV_PATH" --rate "$GV_RATE" --scene "$(report_scene_arg "$gv_scene")" \
            --size "$SIZE" --threads "$THREADS" --budget-ms "$BUDGET_MS" --flip-samples "$GV_FLIP_SAMPLES"
        gv_cpu
        cp "$WORK/cmd.out" "$WORK/governor-$gv_scene.out"
        cp "$WORK/cmd.err" "$WORK/governor-$gv_scene.err"
        # other programs' CPU seconds, the run's seconds, their share of all CPUs
        gv_other=$(echo "$GV_CPU" | awk -v n="$(nproc)" '{
                other = ($4 - $1) - ($5 - $2); if (other < 0) other = 0; wall = $6 - $3; if (wall < 1) wall = 1
                printf "%.1f %d %.0f", other, wall, 100 * other / (n * wall) }')
        gv_line=$(grep '^BENCH_PATH ' "$WORK/cmd.out" || true)
        [ -n "$gv_line" ] || report_fail "knob governor: no BENCH_PATH line from the bench on $gv_scene"
        gv_gov=$(sed -n 's/^tessera: governor ([^)]*): \([0-9]*\) moving frames (\([0-9]*\) at a reduced scale, \([0-9]*\) over the budget), \([0-9]*\) refining.*/\1 \2 \3 \4/p' \
            "$WORK/cmd.err")
        [ -n "$gv_gov" ] || report_fail "knob governor: no 'tessera: governor (...)' line on stderr from the bench on $gv_scene"
        # per transaction: scene txn time_s frame frame_ms scale flip ('-' where not sampled)
        awk -v s="$gv_scene" '$1 == "txn" { printf "%s\t%s\t%s\t%s\t%s\t%s\t%s\n", s, $2, $3, $4, $5, $7, $8 }' \
            "$WORK/cmd.out" >> "$gv_tsv"
        grep -q "^$gv_scene	" "$gv_tsv" || report_fail "knob governor: no txn lines from the bench on $gv_scene"
        for gv_key in transactions frames p50_ms p95_ms worst_frame_ms refused flip_mean flip_frames; do
            gv_val=$(report_field "$gv_line" "$gv_key")
            [ -n "$gv_val" ] || report_fail "knob governor: no $gv_key= in: $gv_line"
            printf '%s ' "$gv_val" >> "$WORK/governor-summary.txt"
        done
        echo "$gv_scene $gv_gov $gv_other" >> "$WORK/governor-summary.txt"
        gv_plot "$gv_scene"
    done
    {
        echo "## Frame-budget governor: frame time and FLIP along a camera path"
        echo
        echo "\`tessera bench --path PATH --rate $GV_RATE --size $SIZE --threads $THREADS --budget-ms $BUDGET_MS"
        echo "--flip-samples $GV_FLIP_SAMPLES\`: a sender thread queues one camera transaction per 1/$GV_RATE s of the path, as"
        echo "a user steering would, while the pipeline renders in real time. The governor (engine/frame/governor.h)"
        echo "renders each moving frame at the scale of the ladder 1, 7/8, 3/4, 5/8, 1/2, 3/8, 1/4 its cost"
        echo "model predicts within the $BUDGET_MS ms budget (REPORT_BUDGET_MS), upscaled with \`--upscale bilinear\`"
        echo "(its default) on all render threads. Frame time: the loop step that rendered a frame (its"
        echo "render, upscale and the previous frame's display stage, here the null display). FLIP: for"
        echo "$GV_FLIP_SAMPLES transactions spread evenly over the path (first and last included), the mean FLIP of"
        echo "the frame that first showed it against the full-size one-ray-per-pixel frame of the same"
        echo "camera, rendered after the run: the error the reduced scale and the upscale add, not the"
        echo "error against a converged reference of the other knobs (a frame at scale 1 scores 0). The"
        echo "issue's target: p95 frame time at most $BUDGET_MS × 1.1 ms, the mean FLIP reported."
        echo
        echo "Paths:"
        for gv_scene in "$@"; do
            gv_path "$gv_scene"
            echo "- $gv_scene: $GV_PATH_NOTE."
        done
        echo
        echo "| scene | transactions | frames | p50 ms | p95 ms | p95 / budget | worst ms | over budget | at a reduced scale | commonest scale, 2nd half | mean FLIP (sampled) |"
        echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        while read -r txns frames p50 p95 worst _refused flip nflip scene moving reduced over _refining _other _wall _share; do
            gv_settle "$scene"
            echo "| $scene | $txns | $frames | $p50 | $p95 | $(gv_ratio "$p95" "$BUDGET_MS") | $worst |" \
                "$over ($(gv_percent "$over" "$moving") %) | $reduced ($(gv_percent "$reduced" "$moving") %) |" \
                "$GV_SETTLED | $flip ($nflip) |"
        done < "$WORK/governor-summary.txt"
        echo
        echo "Frames: every frame rendered (more than the transactions: a frame that showed no new"
        echo "transaction counts too); over budget, at a reduced scale: of the moving frames, as counted by"
        echo "the pipeline (stderr's \`tessera: governor\` line). Commonest scale: the scale most transactions of"
        echo "the path's second half were first shown at. The numbers per transaction:"
        echo "[report/governor.tsv](report/governor.tsv) (tab-separated: scene, transaction, time s, frame,"
        echo "frame ms, scale, FLIP or \`-\`)."
        echo
        while read -r txns frames p50 p95 worst refused flip nflip scene moving reduced over _refining other wall share; do
            echo "![$scene: frame time, render scale and FLIP along the path](report/governor_$scene.png)"
            echo
            gv_sentences
            echo
        done < "$WORK/governor-summary.txt"
        echo "**Default shipped: no budget; \`--budget-ms\` turns the governor on.** A budget is a promise about"
        echo "the machine and the wall (how many pixels, how many threads), so the one who installs the wall"
        echo "sets it; without it frames render at full size, as measured by the other knobs. With it, the"
        echo "governor upscales with bilinear, the cheaper filter (see the render-scale section for what"
        echo "the two filters do at equal time). *(This reason is the project's choice, written in"
        echo "tools/report/knob_governor.sh; the verdicts above are computed from the runs.)*"
    } > "$gv_out"
    cp "$gv_tsv" "$WORK/plots/governor.tsv"
}

# The scale most transactions of the second half of the path were first shown
# at, into GV_SETTLED, with its share there (GV_SETTLED_SHARE, %) and the
# range of scales there (GV_SETTLED_LO, GV_SETTLED_HI).
gv_settle() { # scene
    gs=$(awk -F '\t' -v s="$1" '$1 == s { n++; t[n] = $6 }
        END {
            lo = ""; hi = ""
            for (i = int(n / 2) + 1; i <= n; i++) {
                c[t[i]]++; m++
                if (lo == "" || t[i] + 0 < lo + 0) lo = t[i]
                if (hi == "" || t[i] + 0 > hi + 0) hi = t[i]
            }
            best = ""; for (v in c) if (best == "" || c[v] > c[best] || (c[v] == c[best] && v + 0 < best + 0)) best = v
            printf "%s %.0f %s %s\n", best, 100 * c[best] / m, lo, hi
        }' "$WORK/governor.tsv")
    # shellcheck disable=SC2086
    set -- $gs
    GV_SETTLED=$1 GV_SETTLED_SHARE=$2 GV_SETTLED_LO=$3 GV_SETTLED_HI=$4
}

# The sentences under a scene's plot (the variables of the summary line read
# in knob_governor).
gv_sentences() {
    limit=$(awk -v b="$BUDGET_MS" 'BEGIN { printf "%g", 1.1 * b }')
    if awk -v p="$p95" -v l="$limit" 'BEGIN { exit !(p <= l) }'; then
        verdict="within budget × 1.1 ($limit ms): **the issue's target is met**"
    else
        verdict="over budget × 1.1 ($limit ms): **the issue's target is not met**"
    fi
    printf 'On %s the p95 frame time is %s ms, %s× the %s ms budget, %s; the median is %s ms and the worst frame %s ms. ' \
        "$scene" "$p95" "$(gv_ratio "$p95" "$BUDGET_MS")" "$BUDGET_MS" "$verdict" "$p50" "$worst"
    gv_settle "$scene"
    first=$(awk -F '\t' -v s="$scene" '$1 == s && $6 + 0 < 1 { printf "%.2f\n", $3; exit }' "$WORK/governor.tsv")
    if [ -z "$first" ]; then
        printf 'The scale never went below 1: at %s the full-size frame fits the budget, so the governor had nothing to do. ' "$SIZE"
    else
        if [ "$GV_SETTLED_SHARE" -ge 50 ]; then
            settled="settled at $GV_SETTLED ($GV_SETTLED_SHARE % of the transactions of the second half of the path"
        else
            settled="did not settle (in the second half of the path its commonest value, $GV_SETTLED, showed only $GV_SETTLED_SHARE % of the transactions"
        fi
        printf 'The scale first went below 1 at %s s and %s; range %s to %s there); %s of the %s moving frames (%s %%) were at a reduced scale. ' \
            "$first" "$settled" "$GV_SETTLED_LO" "$GV_SETTLED_HI" "$reduced" "$moving" \
            "$(gv_percent "$reduced" "$moving")"
    fi
    # the sampled FLIPs of frames at a reduced scale: count, mean, worst
    # shellcheck disable=SC2046
    set -- $(awk -F '\t' -v s="$scene" '$1 == s && $7 != "-" && $6 + 0 < 1 { n++; f += $7; if ($7 > m) m = $7 }
        END { printf "%d %.5f %.5f\n", n, (n ? f / n : 0), m }' "$WORK/governor.tsv")
    printf 'The mean FLIP of the %s sampled frames is %s; %s of them were at a reduced scale' "$nflip" "$flip" "$1"
    if [ "$1" -gt 0 ]; then
        printf ' (their mean %s, worst %s), the rest at scale 1 score 0. ' "$2" "$3"
    else
        printf ', so it measures nothing of the upscale here. '
    fi
    # a yardstick: the error one ray per pixel at full size already has (antialiasing knob)
    if [ -f "$WORK/antialiasing.tsv" ]; then
        aa=$(awk -F '\t' -v s="$scene" '$1 == s && $2 == "single" { print $6 }' "$WORK/antialiasing.tsv")
        if [ -n "$aa" ]; then
            # shellcheck disable=SC2016
            printf 'For scale: one ray per pixel at full size is %s from the converged reference at the scene'"'"'s own camera (antialiasing section, `single`), so what the governor adds along the path is %s× that (different cameras: an order of magnitude, not a ratio to trust to a digit). ' \
                "$aa" "$(gv_ratio "$flip" "$aa")"
        fi
    fi
    if [ "$refused" != 0 ]; then
        printf '%s transactions were refused (the queue was full). ' "$refused"
    fi
    echo
    echo
    if [ "$share" -gt "$GV_BUSY_PERCENT" ]; then
        echo "**The machine was busy during this run**: other programs took $other CPU-seconds of the $(nproc)"
        echo "CPUs' $wall s ($share %; /proc/stat less this report's own processes). The governor answers load"
        echo "by lowering the scale, so on a busy machine the frame times, the scales and the FLIP are all a"
        echo "busy machine's: a quiet run will show a larger scale and a lower FLIP, not only faster frames."
    else
        echo "Other programs took $other CPU-seconds of the $(nproc) CPUs' $wall s during this run ($share %;"
        echo "/proc/stat less this report's own processes): a quiet enough machine."
    fi
    if [ "$SIZE" != 1920x1080 ]; then
        echo "At $SIZE, not the issue's 1920x1080: the governor's numbers there need \`make report\` at full size."
    fi
}

# A scene's plot, two panels sharing the time axis: above, frame time per
# transaction with the budget and 1.1 × budget lines and the render scale on
# the second y axis; below, the sampled FLIP values.
gv_plot() { # scene
    gp_dat=$WORK/plots/governor-$1.dat
    awk -F '\t' -v s="$1" '$1 == s { print $3, $5, $6, $7 }' "$WORK/governor.tsv" > "$gp_dat"
    gp_limit=$(awk -v b="$BUDGET_MS" 'BEGIN { printf "%g", 1.1 * b }')
    gp_top=$(awk -v l="$gp_limit" '$2 > m { m = $2 } END { if (m < l) m = l; printf "%g", 1.15 * m }' "$gp_dat")
    gp_flip_top=$(awk '$4 != "-" && $4 > m { m = $4 } END { printf "%g", (m > 0 ? 1.3 * m : 0.01) }' "$gp_dat")
    gp=$WORK/plots/governor-$1.gp
    {
        echo "set terminal $GNUPLOT_TERM size 900,700"
        echo "set output '$WORK/plots/governor_$1.png'"
        echo "set datafile missing '-'"
        echo "set termoption noenhanced"
        echo "set multiplot"
        echo "set lmargin 11"
        echo "set rmargin 11"
        echo "set grid"
        echo "set xrange [*:*]"
        echo "set size 1, 0.66"
        echo "set origin 0, 0.34"
        echo "set title \"Governor on $1: frame time and render scale per transaction ($SIZE, $THREADS threads, budget $BUDGET_MS ms)\""
        echo "set xlabel ''"
        echo "set format x ''"
        echo "set ylabel 'frame time (ms, the frame that first showed it)'"
        echo "set yrange [0:$gp_top]"
        echo "set y2label 'render scale (fraction of each edge)'"
        echo "set y2range [0:1.1]"
        echo "set y2tics ('1/4' 0.25, '3/8' 0.375, '1/2' 0.5, '5/8' 0.625, '3/4' 0.75, '7/8' 0.875, '1' 1)"
        echo "set ytics nomirror"
        echo "set key outside top center horizontal"
        printf "plot '%s' using 1:2 with lines lw 1 lc rgb '#1f5fbf' title 'frame time (ms)', " "$gp_dat"
        printf "%s with lines dashtype 2 lw 2 lc rgb '#2a9d3a' title 'budget %s ms', " "$BUDGET_MS" "$BUDGET_MS"
        printf "%s with lines dashtype 2 lw 2 lc rgb '#c0392b' title 'budget x 1.1 = %s ms', " "$gp_limit" "$gp_limit"
        printf "'%s' using 1:3 axes x1y2 with steps lw 2 lc rgb '#e69f00' title 'render scale (right axis)'\n" "$gp_dat"
        echo "unset y2tics"
        echo "unset y2label"
        echo "unset title"
        echo "set ytics mirror"
        echo "set size 1, 0.34"
        echo "set origin 0, 0"
        echo "set format x '%g'"
        echo "set xlabel 'time along the path (s; one transaction per 1/$GV_RATE s)'"
        echo "set ylabel 'mean FLIP vs full size'"
        echo "set yrange [0:$gp_flip_top]"
        echo "unset key"
        printf "plot '%s' using 1:4 with points pointtype 7 pointsize 1.2 lc rgb '#7b3fa0' notitle\n" "$gp_dat"
        echo "unset multiplot"
    } > "$gp"
    report_run "$GNUPLOT" "$gp"
}
