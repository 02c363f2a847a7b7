# lib.sh - what every knob of the speed-against-error report shares
# (sourced by tools/report/report.sh; POSIX sh). A knob file
# (tools/report/knob_NAME.sh) calls these:
#
#   report_curve KNOB SCENE LABEL=ARGS...   measure one curve on one scene
#       (ARGS: tessera render options, '~' for each space between them):
#       per setting an image (EXR, linear) compared with the scene's
#       reference (error and FLIP map), and REPORT_RUNS timed runs taken in
#       turn over the settings; appends rows to $WORK/KNOB.tsv
#   report_plot KNOB METRIC YLABEL TITLE [ALONE]  gnuplot: frame time
#       against one error column for every scene, points labelled with their
#       setting, joined in the order measured (but for setting ALONE)
#   report_plot KNOB METRIC YLABEL TITLE ALONE SERIES...  several series
#       per scene (SERIES: NAME=SETTING[:LABEL],...; see report_plot)
#   report_knee KNOB SCENE METRIC [SETTINGS...]  sets KNEE to the setting at
#       the knee (of the curve of SETTINGS only, when given)
#   report_upscale_ms KNOB SCENE SETTING    sets UPSCALE_MS (median, --scale < 1)
#   report_crops KNOB SCENE A B             side-by-side crops of settings A, B
#   report_row KNOB SCENE SETTING           sets MS FLIP RMSE ... of one row
#   report_knob_reference KNOB SCENE ARGS   the knob's own reference of a
#       scene: one render with ARGS ('~' for spaces), which report_curve and
#       report_crops of that knob then compare with, instead of the scene's
#       jittered mean (for a knob whose reference must trace the same rays
#       as its settings, with only the knob's limits removed)
#
# shellcheck shell=sh disable=SC2034
# (SC2034: the variables set here are read by report.sh and the knob files)
#
# Conventions: every function that runs a program goes through report_run,
# which stops the whole report, naming the command, when it fails; nothing
# is written outside $WORK until report.sh has every section (no half report).
# Results go into variables, not stdout, so no failure is lost in a $(...).

# Stop with a message; $WORK (with the logs) is kept for a look.
report_fail()
{
    echo "report: $*" >&2
    # a reference half made is never cached
    [ -z "${rr_tmp:-}" ] || rm -rf "$rr_tmp"
    if [ -d "${WORK:-}" ]; then
        echo "report: REPORT.md and report/ not written (the previous ones are untouched); work files in $WORK" >&2
    else
        echo "report: REPORT.md and report/ not written (the previous ones are untouched)" >&2
    fi
    exit 1
}

# Run a command; its stdout goes to $WORK/cmd.out, stderr to $WORK/cmd.err
# (and both are appended to $WORK/report.log). On failure: stop, naming it.
report_run()
{
    echo "+ $*" >> "$WORK/report.log"
    code=0
    "$@" > "$WORK/cmd.out" 2> "$WORK/cmd.err" || code=$?
    cat "$WORK/cmd.out" "$WORK/cmd.err" >> "$WORK/report.log"
    if [ "$code" -ne 0 ]; then
        echo "report: this command failed (exit $code):" >&2
        echo "  $*" >&2
        sed 's/^/  | /' "$WORK/cmd.err" | tail -n 8 >&2
        report_fail "stopped"
    fi
}

# key=value field of a one-line record.
report_field() { # line key
    echo "$1" | tr ' ' '\n' | sed -n "s/^$2=//p"
}

# Median of the numbers given (the mean of the middle two for an even count).
report_median()
{
    printf '%s\n' "$@" | sort -g | awk '{ v[NR] = $1 } END {
        if (NR % 2) print v[(NR + 1) / 2]; else printf "%.2f\n", (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}

# The scene argument of a scene label (report.sh registers them in SCENES).
report_scene_arg() { # label
    eval "echo \"\$SCENE_ARG_$1\""
}

# One timed run: mean frame time (ms) of REPORT_FRAMES frames rendered to the
# null display (no image writing; pipeline_run's wall time, so neither process
# start, scene load nor BVH build), into MS_RUN.
report_time_run() { # scene_arg, then render options
    rt_scene=$1
    shift
    report_run "$TESSERA" render --scene "$rt_scene" --size "$SIZE" --threads "$THREADS" --frames "$FRAMES" \
        --display null "$@"
    MS_RUN=$(sed -n 's/.*(\([0-9.]*\) ms\/frame.*/\1/p' "$WORK/cmd.out")
    [ -n "$MS_RUN" ] || report_fail "no 'ms/frame' in the output of: $TESSERA render ... $*"
    # with --scale < 1, the upscale stage's share (render threads, inside the frame time above)
    UPSCALE_RUN=$(sed -n 's/^render scale .*: \([0-9.]*\) ms\/frame upscaling.*/\1/p' "$WORK/cmd.out")
}

# The key of the sources that make a picture, into SOURCE_KEY: engine/,
# app/, wall/ (committed state and any uncommitted diff), or the
# tessera binary outside a git tree.
report_source_key() {
    if git rev-parse --git-dir > /dev/null 2>&1; then
        SOURCE_KEY=$({ git ls-files -s engine app wall; git diff HEAD -- engine app wall; } | sha256sum | cut -c1-16)
    else
        SOURCE_KEY=$(sha256sum "$TESSERA" | cut -c1-16)
    fi
}

# The scene argument's cache key: 'default', or the start of the file's sha256.
report_scene_key() { # scene argument
    if [ "$1" = default ]; then echo default; else sha256sum "$1" | cut -c1-16; fi
}

# A knob's own reference of a scene (see the top of this file): one render
# of `tessera render` with ARGS ('~' for each space, as report_curve's),
# cached in $CACHE under a key of the knob, the scene, the size, ARGS (a word
# of ARGS naming a file counts by its contents, so config files made in
# $WORK key by what they say) and the sources. Registers it for KNOB on
# SCENE (report_ref_for) and sets REF, REF_SECONDS (render time, s).
report_knob_reference() { # knob scene-label args
    rk_knob=$1
    rk_label=$2
    rk_args=$(echo "$3" | tr '~' ' ')
    rk_scene=$(report_scene_arg "$rk_label")
    report_source_key
    rk_args_key=$(for rk_w in $rk_args; do
        if [ -f "$rk_w" ]; then cat "$rk_w"; else echo "$rk_w"; fi
    done | sha256sum | cut -c1-16)
    rk_dir=$CACHE/$rk_knob-$rk_label-$SIZE-$(report_scene_key "$rk_scene")-$rk_args_key-$SOURCE_KEY
    if [ ! -f "$rk_dir/reference.exr" ]; then
        echo "report: $rk_knob reference for $rk_label at $SIZE: $rk_args (not cached yet)" >&2
        mkdir -p "$CACHE"
        rr_tmp=$(mktemp -d "$CACHE/.new.XXXXXX")
        rk_start=$(date +%s)
        # shellcheck disable=SC2086
        report_run "$TESSERA" render --scene "$rk_scene" --size "$SIZE" --threads "$THREADS" \
            --out "$rr_tmp/reference.exr" $rk_args
        echo "$(($(date +%s) - rk_start))" > "$rr_tmp/seconds.txt"
        echo "$rk_args" > "$rr_tmp/args.txt"
        rm -rf "$rk_dir"
        mv "$rr_tmp" "$rk_dir"
        rr_tmp=""
    fi
    eval "KNOB_REF_${rk_knob}_$rk_label=\$rk_dir/reference.exr"
    REF=$rk_dir/reference.exr
    REF_SECONDS=$(cat "$rk_dir/seconds.txt")
}

# The reference a knob's curve on a scene is measured against, into REF: the
# knob's own (report_knob_reference) when it made one, else the scene's.
report_ref_for() { # knob scene-label
    eval "rf_ref=\${KNOB_REF_$1_$2:-}"
    if [ -n "$rf_ref" ]; then
        REF=$rf_ref
    else
        report_reference "$2"
    fi
}

# The reference of a scene: REFERENCE_RENDERS renders of jittered:REFERENCE_K
# (seeds 1..N: the curves use seed 0) averaged by report_img mean, cached in
# $CACHE under a key of the scene, the size, the recipe and the sources that
# make the picture (engine/, app/, wall/: committed state and any
# uncommitted diff). Also the two halves (seeds 1..N/2 against the rest)
# compared, which bounds how far the reference itself is from converged.
# Sets REF (path) and REF_HALVES (tessera compare's line for the halves).
report_reference() { # scene label
    rr_label=$1
    rr_scene=$(report_scene_arg "$rr_label")
    rr_scene_key=$(report_scene_key "$rr_scene")
    report_source_key
    rr_src_key=$SOURCE_KEY
    rr_dir=$CACHE/$rr_label-$SIZE-j${REFERENCE_K}x$REFERENCE_RENDERS-$rr_scene_key-$rr_src_key
    if [ ! -f "$rr_dir/reference.exr" ]; then
        echo "report: reference for $rr_label at $SIZE: $REFERENCE_RENDERS x jittered:$REFERENCE_K (not cached yet)" >&2
        mkdir -p "$CACHE"
        rr_tmp=$(mktemp -d "$CACHE/.new.XXXXXX")
        rr_start=$(date +%s)
        rr_seeds=""
        rr_n=1
        while [ "$rr_n" -le "$REFERENCE_RENDERS" ]; do
            printf '{"sampler": {"name": "jittered", "k": %d, "seed": %d}}\n' "$REFERENCE_K" "$rr_n" > "$rr_tmp/seed$rr_n.json"
            report_run "$TESSERA" render --config "$rr_tmp/seed$rr_n.json" --scene "$rr_scene" --size "$SIZE" \
                --threads "$THREADS" --out "$rr_tmp/seed$rr_n.exr"
            rr_seeds="$rr_seeds $rr_tmp/seed$rr_n.exr"
            rr_n=$((rr_n + 1))
        done
        rr_half=$((REFERENCE_RENDERS / 2))
        # shellcheck disable=SC2086
        set -- $rr_seeds
        rr_first="" rr_second=""
        rr_n=1
        for rr_f in "$@"; do
            if [ "$rr_n" -le "$rr_half" ]; then rr_first="$rr_first $rr_f"; else rr_second="$rr_second $rr_f"; fi
            rr_n=$((rr_n + 1))
        done
        # shellcheck disable=SC2086
        report_run "$REPORT_IMG" mean "$rr_tmp/reference.exr" "$@"
        # shellcheck disable=SC2086
        report_run "$REPORT_IMG" mean "$rr_tmp/half_a.exr" $rr_first
        # shellcheck disable=SC2086
        report_run "$REPORT_IMG" mean "$rr_tmp/half_b.exr" $rr_second
        report_run "$TESSERA" compare "$rr_tmp/half_a.exr" "$rr_tmp/half_b.exr" --threads "$THREADS"
        cp "$WORK/cmd.out" "$rr_tmp/halves.txt"
        echo "$(($(date +%s) - rr_start))" > "$rr_tmp/seconds.txt"
        rm -f "$rr_tmp"/seed* "$rr_tmp"/half_*.exr
        rm -rf "$rr_dir"
        mv "$rr_tmp" "$rr_dir"
        rr_tmp=""
    fi
    REF=$rr_dir/reference.exr
    REF_HALVES=$(cat "$rr_dir/halves.txt")
    REF_SECONDS=$(cat "$rr_dir/seconds.txt")
}

# Measure one knob's curve on one scene (see the top of this file). Rows of
# $WORK/KNOB.tsv: scene setting ms_median ms_min ms_max flip_mean flip_median
# flip_q3 rmse psnr; images in $WORK/img/KNOB-SCENE-SETTING.exr, FLIP maps
# beside them (-map.png).
report_curve() { # knob scene label=args...
    rc_knob=$1
    rc_label=$2
    shift 2
    rc_scene=$(report_scene_arg "$rc_label")
    report_ref_for "$rc_knob" "$rc_label"
    mkdir -p "$WORK/img" "$WORK/times"
    for rc_setting in "$@"; do
        rc_name=${rc_setting%%=*}
        rc_args=$(echo "${rc_setting#*=}" | tr '~' ' ')
        echo "report: $rc_knob, $rc_label, $rc_name: image and error" >&2
        rc_img=$WORK/img/$rc_knob-$rc_label-$rc_name
        # shellcheck disable=SC2086
        report_run "$TESSERA" render --scene "$rc_scene" --size "$SIZE" --threads "$THREADS" --out "$rc_img.exr" $rc_args
        report_run "$TESSERA" compare "$REF" "$rc_img.exr" --map "$rc_img-map.png" --threads "$THREADS"
        cp "$WORK/cmd.out" "$rc_img.compare"
        : > "$WORK/times/$rc_knob-$rc_label-$rc_name"
    done
    # runs in turn over the settings, so a slow spell of the machine spreads over all of them
    rc_run=1
    while [ "$rc_run" -le "$RUNS" ]; do
        echo "report: $rc_knob, $rc_label: timed run $rc_run of $RUNS" >&2
        for rc_setting in "$@"; do
            rc_name=${rc_setting%%=*}
            # shellcheck disable=SC2046
            report_time_run "$rc_scene" $(echo "${rc_setting#*=}" | tr '~' ' ')
            echo "$MS_RUN" >> "$WORK/times/$rc_knob-$rc_label-$rc_name"
            [ -z "$UPSCALE_RUN" ] || echo "$UPSCALE_RUN" >> "$WORK/times/$rc_knob-$rc_label-$rc_name.upscale"
        done
        rc_run=$((rc_run + 1))
    done
    for rc_setting in "$@"; do
        rc_name=${rc_setting%%=*}
        # shellcheck disable=SC2046
        set -- $(cat "$WORK/times/$rc_knob-$rc_label-$rc_name")
        rc_ms=$(report_median "$@")
        rc_lo=$(printf '%s\n' "$@" | sort -g | head -n 1)
        rc_hi=$(printf '%s\n' "$@" | sort -g | tail -n 1)
        rc_line=$(cat "$WORK/img/$rc_knob-$rc_label-$rc_name.compare")
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$rc_label" "$rc_name" "$rc_ms" "$rc_lo" "$rc_hi" \
            "$(report_field "$rc_line" flip_mean)" "$(report_field "$rc_line" flip_median)" \
            "$(report_field "$rc_line" flip_q3)" "$(report_field "$rc_line" rmse)" "$(report_field "$rc_line" psnr)" \
            >> "$WORK/$rc_knob.tsv"
    done
}

# The values of one row: MS MS_LO MS_HI FLIP FLIP_MEDIAN FLIP_Q3 RMSE PSNR.
report_row() { # knob scene setting
    row=$(awk -F '\t' -v s="$2" -v n="$3" '$1 == s && $2 == n' "$WORK/$1.tsv")
    [ -n "$row" ] || report_fail "no measurement of $3 on $2 for $1"
    MS=$(echo "$row" | cut -f3)
    MS_LO=$(echo "$row" | cut -f4)
    MS_HI=$(echo "$row" | cut -f5)
    FLIP=$(echo "$row" | cut -f6)
    FLIP_MEDIAN=$(echo "$row" | cut -f7)
    FLIP_Q3=$(echo "$row" | cut -f8)
    RMSE=$(echo "$row" | cut -f9)
    PSNR=$(echo "$row" | cut -f10)
}

# The median upscale time (ms/frame, tessera render's 'render scale' line) of
# a setting's timed runs into UPSCALE_MS; empty for a setting that does not
# upscale.
report_upscale_ms() { # knob scene setting
    ru_file=$WORK/times/$1-$2-$3.upscale
    UPSCALE_MS=""
    if [ -s "$ru_file" ]; then
        # shellcheck disable=SC2046
        UPSCALE_MS=$(report_median $(cat "$ru_file"))
    fi
}

# Column of a metric in KNOB.tsv.
report_metric_column() {
    case $1 in
        flip) echo 6 ;;
        rmse) echo 9 ;;
        *) report_fail "report_metric_column: unknown metric '$1'" ;;
    esac
}

# The knee of a scene's curve for a metric, into KNEE: the point farthest
# below the straight line from the fastest to the slowest point, with frame
# time and error each scaled to [0, 1] over the curve (Satopää et al. 2011,
# "Kneedle"). The fastest point when no point lies below that line. With
# SETTINGS, the curve of those settings only (one series of several).
report_knee() { # knob scene metric [settings...]
    rk_col=$(report_metric_column "$3")
    rk_knob=$1
    rk_scene=$2
    shift 3
    KNEE=$(awk -F '\t' -v s="$rk_scene" -v c="$rk_col" -v only=" $* " '$1 == s && (only == "  " || index(only, " " $2 " ")) {
            n++; name[n] = $2; x[n] = $3; y[n] = $c }
        END {
            if (n == 0) exit 1
            lo = 1; hi = 1
            for (i = 1; i <= n; i++) { if (x[i] < x[lo]) lo = i; if (x[i] > x[hi]) hi = i }
            ymin = y[1]; ymax = y[1]
            for (i = 1; i <= n; i++) { if (y[i] < ymin) ymin = y[i]; if (y[i] > ymax) ymax = y[i] }
            dx = x[hi] - x[lo]; dy = ymax - ymin
            if (dx <= 0 || dy <= 0) { print name[lo]; exit }
            best = lo; bestd = 0
            for (i = 1; i <= n; i++) {
                u = (x[i] - x[lo]) / dx; v = (y[i] - ymin) / dy
                line = (y[lo] - ymin) / dy + u * ((y[hi] - y[lo]) / dy)
                if (line - v > bestd) { bestd = line - v; best = i }
            }
            print name[best]
        }' "$WORK/$rk_knob.tsv") || report_fail "report_knee: no rows for $rk_scene in $rk_knob"
}

# Plot frame time (x) against one error column (y): one series per scene,
# each point labelled with its setting, the points joined in the order
# measured except setting ALONE (a point apart: another kind of setting).
# Writes $WORK/plots/KNOB_METRIC.png.
#
# With SERIES (ALONE given, '' for none), each scene draws one series per
# SERIES word instead, NAME=SETTING[:LABEL],SETTING[:LABEL],... : the settings
# joined in that order, titled 'SCENE, NAME' (no spaces in NAME), each point
# labelled LABEL (the setting when no ':'; nothing for an empty LABEL, e.g. a
# point two series share, labelled once).
#
# Telling series apart: every series of the plot has a colour of its own
# (REPORT_PLOT_COLOURS in turn), each scene a dash pattern (solid, dashed,
# dotted, ...), each series of a scene a point shape; the key sits under the
# plot, clear of the points. A label has its series' colour and goes beside
# its point where it covers no other label, point or line
# (tools/report/plot_labels.awk). Axes: log where the values span a decade or
# more (max / min >= 10). An error column holding zeros (identical images)
# whose other values span a decade or more is log too, its zeros drawn on a
# dotted floor line a decade below the smallest value above zero, ticked "0";
# any other error axis is linear and starts at 0 (errors are never negative).
REPORT_PLOT_COLOURS="#0072B2 #D55E00 #009E73 #CC79A7 #E69F00 #56B4E9 #000000 #999933 #882255 #44AA99"
REPORT_PLOT_W=900
REPORT_PLOT_H=620
report_plot() { # knob metric ylabel title [alone [series...]]
    rp_knob=$1
    rp_col=$(report_metric_column "$2")
    rp_metric=$2
    rp_ylabel=$3
    rp_title=$4
    rp_alone=${5:-}
    if [ $# -gt 5 ]; then shift 5; else set --; fi # no SERIES: one series per scene
    mkdir -p "$WORK/plots"
    rp_gp=$WORK/plots/$rp_knob-$rp_metric.gp
    rp_list=$WORK/plots/$rp_knob-$rp_metric.series # per series: dat, colour, dash, shape, title
    rp_xlog=$(report_plot_span "$rp_knob" 3)
    rp_ylog=$(report_plot_span "$rp_knob" "$rp_col")
    rp_floor=""
    if [ -z "$rp_ylog" ]; then
        rp_floor=$(report_plot_floor "$rp_knob" "$rp_col")
        [ -z "$rp_floor" ] || rp_ylog=log
    fi
    : > "$rp_list"
    rp_colour=0
    rp_dash=0
    for rp_scene in $(cut -f1 "$WORK/$rp_knob.tsv" | awk '!seen[$0]++'); do
        rp_dash=$((rp_dash + 1))
        if [ $# -eq 0 ]; then
            rp_dat=$WORK/plots/$rp_knob-$rp_scene.dat
            # a blank line (gnuplot: break the line) around the setting that stands apart
            awk -F '\t' -v s="$rp_scene" -v c="$rp_col" -v alone="$rp_alone" -v floor="$rp_floor" '$1 == s {
                    n++
                    if ($2 == alone && n > 1) print ""
                    printf "%s %s \"%s\"\n", $3, (floor != "" && $c + 0 == 0 ? floor : $c), $2
                    if ($2 == alone) print ""
                }' "$WORK/$rp_knob.tsv" > "$rp_dat"
            report_plot_add "$rp_dat" "$rp_scene" 7
            continue
        fi
        rp_n=0
        for rp_series in "$@"; do
            rp_n=$((rp_n + 1))
            rp_name=${rp_series%%=*}
            rp_dat=$WORK/plots/$rp_knob-$rp_scene-$rp_name.dat
            # the series' settings in its order; labels quoted (gnuplot: a string column)
            echo "${rp_series#*=}" | tr ',' '\n' | awk -F '\t' -v s="$rp_scene" -v c="$rp_col" -v floor="$rp_floor" '
                NR == FNR { if ($1 == s) { x[$2] = $3; y[$2] = (floor != "" && $c + 0 == 0 ? floor : $c) }; next }
                {
                    set = $0; label = $0
                    if (index($0, ":")) { set = substr($0, 1, index($0, ":") - 1); label = substr($0, index($0, ":") + 1) }
                    if (!(set in x)) { print "no row for " set > "/dev/stderr"; exit 1 }
                    printf "%s %s \"%s\"\n", x[set], y[set], label
                }' "$WORK/$rp_knob.tsv" - > "$rp_dat" ||
                report_fail "report_plot: series $rp_name of $rp_knob names a setting not measured on $rp_scene"
            # shapes: filled circle, square, triangle, diamond, pentagon, then again
            case $(((rp_n - 1) % 5)) in
                1) rp_pt=5 ;;
                2) rp_pt=9 ;;
                3) rp_pt=13 ;;
                4) rp_pt=15 ;;
                *) rp_pt=7 ;;
            esac
            report_plot_add "$rp_dat" "$rp_scene, $rp_name" "$rp_pt"
        done
    done
    # the key under the plot, two entries a row: the plot area's bottom margin fits it
    rp_keyrows=$((($(wc -l < "$rp_list") + 1) / 2))
    rp_bottom=$((64 + rp_keyrows * 18)) # pixels
    rp_top=$((REPORT_PLOT_H * 8 / 100))
    {
        echo "set terminal $GNUPLOT_TERM size $REPORT_PLOT_W,$REPORT_PLOT_H"
        echo "set output '$WORK/plots/${rp_knob}_$rp_metric.png'"
        echo "set title \"$rp_title\""
        echo "set xlabel 'frame time (ms, median of $RUNS runs, $THREADS threads, $SIZE)'"
        if [ -n "$rp_floor" ]; then
            echo "set ylabel \"$rp_ylabel; 0 on the dotted line\""
        else
            echo "set ylabel \"$rp_ylabel\""
        fi
        echo "set grid"
        # fixed margins: plot_labels.awk places labels in this area's pixels
        echo "set lmargin at screen 0.11; set rmargin at screen 0.97"
        awk -v t="$rp_top" -v b="$rp_bottom" -v h="$REPORT_PLOT_H" \
            'BEGIN { printf "set tmargin at screen %.4f; set bmargin at screen %.4f\n", 1 - t / h, b / h }'
        echo "set key at screen 0.54, screen 0.01 center bottom horizontal maxcols 2 samplen 3 width 2"
        [ "$rp_xlog" = log ] && echo "set logscale x"
        if [ "$rp_ylog" = log ]; then
            echo "set logscale y"
            echo "set format y '%g'"
        fi
        if [ -n "$rp_floor" ]; then
            echo "set ytics add ('0' $rp_floor)"
            echo "set arrow from graph 0, first $rp_floor to graph 1, first $rp_floor nohead dashtype 3 linecolor rgb '#808080'"
        fi
        # ranges and labels
        awk -v xlog="$rp_xlog" -v ylog="$rp_ylog" -v floor="$rp_floor" \
            -v pw="$((REPORT_PLOT_W * 86 / 100))" -v ph="$((REPORT_PLOT_H - rp_top - rp_bottom))" \
            -f tools/report/plot_labels.awk "$rp_list"
        printf 'plot '
        awk -F '\t' '{
                printf "%s'\''%s'\'' using 1:2 with linespoints linewidth 1.5 pointsize 1.3 pointtype %s linecolor rgb '\''%s'\'' dashtype %s title '\''%s'\''",
                    (NR > 1 ? ", " : ""), $1, $4, $2, $3, $5
            }' "$rp_list"
        echo
    } > "$rp_gp"
    report_run "$GNUPLOT" "$rp_gp"
}

# One series of report_plot into its list: the next colour, the scene's dash.
report_plot_add() { # dat title pointtype
    rp_colour=$((rp_colour + 1))
    rpa_c=$(echo "$REPORT_PLOT_COLOURS" | tr ' ' '\n' | awk -v n="$rp_colour" '{ c[NR] = $0 } END { print c[(n - 1) % NR + 1] }')
    printf '%s\t%s\t%s\t%s\t%s\n' "$1" "$rpa_c" "$rp_dash" "$3" "$2" >> "$rp_list"
}

# "log" when a column of KNOB.tsv spans a decade or more (max / min >= 10, all > 0).
report_plot_span() { # knob column
    awk -F '\t' -v c="$2" 'NR == 1 || $c < lo { lo = $c } NR == 1 || $c > hi { hi = $c }
        END { if (lo > 0 && hi / lo >= 10) print "log" }' "$WORK/$1.tsv"
}

# For a column holding zeros whose values above zero span a decade or more:
# the floor its zeros are drawn at, a decade below the smallest value above
# zero, rounded down to a power of ten; nothing otherwise.
report_plot_floor() { # knob column
    awk -F '\t' -v c="$2" '$c + 0 == 0 { zero = 1; next } lo == "" || $c < lo { lo = $c } $c > hi { hi = $c }
        END { if (zero && lo > 0 && hi / lo >= 10) printf "%g\n", 10 ^ (int(log(lo) / log(10) + 100) - 101) }' "$WORK/$1.tsv"
}

# A side-by-side crop of two settings of a knob on a scene, with their FLIP
# maps, around where setting A differs most from the reference: row 1 the
# reference, A, B; row 2 nothing, A's map, B's map; captioned
# (report_caption_montage) with the settings' names (or A_NAME, B_NAME), frame
# times and mean FLIP. Sets CROP (file name in report/), CROP_X, CROP_Y,
# CROP_PX, CROP_ZOOM.
report_crops() { # knob scene A B [A_NAME B_NAME]
    rx_knob=$1
    rx_label=$2
    report_ref_for "$rx_knob" "$rx_label"
    rx_height=${SIZE#*x}
    rx_width=${SIZE%x*}
    CROP_PX=$((CROP_AT_1080 * rx_height / 1080 / 8 * 8))
    [ "$CROP_PX" -ge 32 ] || CROP_PX=32
    if [ "$CROP_PX" -gt "$rx_height" ] || [ "$CROP_PX" -gt "$rx_width" ]; then
        report_fail "$SIZE is too small for a $CROP_PX px crop"
    fi
    CROP_ZOOM=$((CROP_AT_1080 / CROP_PX))
    [ "$CROP_ZOOM" -ge 1 ] || CROP_ZOOM=1
    rx_a=$WORK/img/$rx_knob-$rx_label-$3
    rx_b=$WORK/img/$rx_knob-$rx_label-$4
    report_run "$REPORT_IMG" region "$CROP_PX" "$REF" "$rx_a.exr"
    CROP_X=$(cut -d' ' -f1 "$WORK/cmd.out")
    CROP_Y=$(cut -d' ' -f2 "$WORK/cmd.out")
    mkdir -p "$WORK/plots"
    CROP=${rx_knob}_crop_$rx_label.png
    report_run "$REPORT_IMG" montage "$WORK/plots/bare_$CROP" "$CROP_X" "$CROP_Y" "$CROP_PX" "$CROP_ZOOM" 3 \
        "$REF" "$rx_a.exr" "$rx_b.exr" - "$rx_a-map.png" "$rx_b-map.png"
    rx_an=${5:-$3}
    rx_bn=${6:-$4}
    report_row "$rx_knob" "$rx_label" "$3"
    rx_at="$rx_an|$MS ms, mean FLIP $FLIP"
    report_row "$rx_knob" "$rx_label" "$4"
    report_caption_montage "$WORK/plots/bare_$CROP" "$WORK/plots/$CROP" $((CROP_PX * CROP_ZOOM)) \
        "reference" "$rx_at" "$rx_bn|$MS ms, mean FLIP $FLIP" \
        "FLIP maps:|black 0, pale yellow 1" "FLIP map of|$rx_an" "FLIP map of|$rx_bn"
}

# Captions for a report_crops montage IN (2 rows of 3 cells of CELL pixels,
# 4 apart): a white band above the top row names its three pictures, one
# under the bottom row its three (the first cell of that row is empty), two
# lines each at most ('|' breaks the line); the pictures are copied pixel for
# pixel (gnuplot, pngcairo). Writes OUT.
report_caption_montage() { # in out cell top1 top2 top3 bottom1 bottom2 bottom3
    rc_in=$1
    rc_band=40
    rc_w=$((3 * $3 + 8))
    rc_h=$((2 * $3 + 4))
    rc_gp=$WORK/plots/caption.gp
    {
        echo "set terminal $GNUPLOT_TERM size $rc_w,$((rc_h + 2 * rc_band))"
        echo "set output '$2'"
        echo "unset border; unset tics; unset key"
        echo "set lmargin at screen 0; set rmargin at screen 1; set tmargin at screen 1; set bmargin at screen 0"
        # pixel centres at integer coordinates: the image covers [-0.5, w - 0.5]
        echo "set xrange [-0.5:$rc_w - 0.5]"
        echo "set yrange [-0.5 - $rc_band:$rc_h - 0.5 + $rc_band]"
        echo "set object 1 rectangle from screen 0, screen 0 to screen 1, screen 1 fillcolor rgb 'white' fillstyle solid behind"
        rc_i=0
        shift 3
        for rc_text in "$@"; do
            rc_col=$((rc_i % 3))
            rc_x=$((rc_col * (rc_w + 4) / 3 + 4))
            # a label's position is its first line's: 12 pixels into its band
            if [ "$rc_i" -lt 3 ]; then rc_y=$((rc_h + rc_band - 12)); else rc_y=-12; fi
            rc_text=$(printf '%s\n' "$rc_text" | sed 's/["\\]/\\&/g; s/|/\\n/g')
            printf 'set label %s "%s" at %s, %s left front\n' $((rc_i + 1)) "$rc_text" "$rc_x" "$rc_y"
            rc_i=$((rc_i + 1))
        done
        echo "plot '$rc_in' binary filetype=png with rgbimage"
    } > "$rc_gp"
    report_run "$GNUPLOT" "$rc_gp"
}
