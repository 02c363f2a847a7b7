# knob_render_scale.sh - the render-scale section of REPORT.md: the frame
# rendered at a fraction of the output size and upscaled (engine/render/upscale.h,
# `tessera render --scale S --upscale F`) against frame time and error, for
# both upscale filters. Sourced by tools/report/report.sh, which calls
# knob_render_scale once with the scenes measured; it writes
# $WORK/section_render_scale.md and its pictures into $WORK/plots/.
#
# Settings are named SCALE-FILTER with '_' for the fraction's '/'
# (3_4-bilinear is --scale 3/4 --upscale bilinear); `1` is full size (no
# upscaling), the first point of both filters' series. All of them sample
# once per pixel (--sampler single), as the kiosk renders.
#
# shellcheck shell=sh disable=SC2046
# (SC2046: a series' settings are passed as separate words on purpose)

RS_SCALES="3_4 1_2 1_3 1_4"
RS_FILTERS="bilinear clamped-cubic"

rs_args() { # setting -> render options
    case $1 in
        1) echo "--sampler single" ;;
        *) echo "--sampler single --scale $(rs_scale "$1") --upscale ${1#*-}" ;;
    esac
}
rs_scale() { echo "${1%%-*}" | tr _ /; }                                  # setting -> 3/4
rs_filter() { case $1 in 1) echo "none" ;; *) echo "${1#*-}" ;; esac }   # setting -> filter
rs_series_settings() { # filter -> its settings, full size first
    printf '1'
    for sc in $RS_SCALES; do printf ' %s' "$sc-$1"; done
    echo
}
# the rendered size of an edge of n pixels at a setting's scale: max(1, round(n s)), as engine/render/upscale.h
rs_px() { # n setting
    awk -v n="$1" -v s="$(rs_scale "$2")" 'BEGIN {
        q = index(s, "/"); f = q ? substr(s, 1, q - 1) / substr(s, q + 1) : s + 0
        v = int(n * f + 0.5); print (v < 1 ? 1 : v) }'
}
rs_ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", (b > 0 ? a / b : 0) }'; }
rs_error() { # scene setting metric -> the metric's value
    awk -F '\t' -v s="$1" -v n="$2" -v c="$(report_metric_column "$3")" '$1 == s && $2 == n { print $c }' \
        "$WORK/render_scale.tsv"
}

# Equal time, one scene and metric: each series' error interpolated at the
# other series' frame times (piecewise linear in log time and log error
# between neighbouring points of a series sorted by time; only times inside
# the other series' range), as the ratio clamped-cubic / bilinear. Sets
# ET_N (comparisons), ET_CUBIC (how many of them clamped-cubic is lower),
# ET_MEDIAN, ET_MIN, ET_MAX (of the ratios), ET_VERDICT (a phrase).
rs_equal_time() { # scene metric
    et=$(awk -F '\t' -v s="$1" -v c="$(report_metric_column "$2")" \
        -v bl="$(rs_series_settings bilinear)" -v cl="$(rs_series_settings clamped-cubic)" '
        function load(list, tx, ty,    k, m, i, j, t, names) {
            m = split(list, names, " ")
            for (i = 1; i <= m; i++) { tx[i] = x[names[i]]; ty[i] = y[names[i]] }
            for (i = 2; i <= m; i++) # insertion sort by time
                for (j = i; j > 1 && tx[j] < tx[j - 1]; j--) {
                    t = tx[j]; tx[j] = tx[j - 1]; tx[j - 1] = t
                    t = ty[j]; ty[j] = ty[j - 1]; ty[j - 1] = t
                }
            return m
        }
        function interp(tx, ty, m, t,    j, u) {
            if (t < tx[1] || t > tx[m]) return -1
            for (j = 1; j < m && tx[j + 1] < t; j++) ;
            if (j == m || tx[j + 1] == tx[j]) return ty[j]
            u = (log(t) - log(tx[j])) / (log(tx[j + 1]) - log(tx[j]))
            return exp(log(ty[j]) + u * (log(ty[j + 1]) - log(ty[j])))
        }
        $1 == s { x[$2] = $3; y[$2] = $c }
        END {
            nb = load(bl, bx, by); nc = load(cl, cx, cy)
            split(bl, bn, " "); split(cl, cn, " ")
            n = 0
            for (i = 2; i <= nc; i++) { # the cubic points (not the shared full size) on the bilinear curve
                v = interp(bx, by, nb, x[cn[i]])
                if (v > 0) r[++n] = y[cn[i]] / v
            }
            for (i = 2; i <= nb; i++) {
                v = interp(cx, cy, nc, x[bn[i]])
                if (v > 0) r[++n] = v / y[bn[i]]
            }
            if (n == 0) { print 0, 0, 1, 1, 1; exit }
            for (i = 2; i <= n; i++)
                for (j = i; j > 1 && r[j] < r[j - 1]; j--) { t = r[j]; r[j] = r[j - 1]; r[j - 1] = t }
            wins = 0
            for (i = 1; i <= n; i++) if (r[i] < 1) wins++
            med = n % 2 ? r[(n + 1) / 2] : (r[n / 2] + r[n / 2 + 1]) / 2
            printf "%d %d %.3f %.3f %.3f\n", n, wins, med, r[1], r[n]
        }' "$WORK/render_scale.tsv")
    # shellcheck disable=SC2086
    set -- $et
    ET_N=$1 ET_CUBIC=$2 ET_MEDIAN=$3 ET_MIN=$4 ET_MAX=$5
    # a winner: lower in at least 3/4 of the comparisons and by 3 % or more at the median
    if [ "$ET_N" -eq 0 ]; then
        ET_VERDICT="no comparison (the two series' frame times do not overlap)"
    elif [ $((4 * ET_CUBIC)) -ge $((3 * ET_N)) ] && awk -v m="$ET_MEDIAN" 'BEGIN { exit !(m <= 0.97) }'; then
        ET_VERDICT="clamped-cubic wins"
    elif [ $((4 * ET_CUBIC)) -le "$ET_N" ] && awk -v m="$ET_MEDIAN" 'BEGIN { exit !(m >= 1.03) }'; then
        ET_VERDICT="bilinear wins"
    else
        ET_VERDICT="a tie (neither lower in 3/4 of the comparisons by 3 % or more at the median)"
    fi
}

# The equal-time pair of a scene for the crops: for a budget of T ms/frame,
# each filter's best setting is its lowest mean FLIP among its settings (full
# size included) that take no longer than T. The budget is the frame time of
# the first of: bilinear's knee, clamped-cubic's knee (by mean FLIP), then
# every other point from the slowest, at which the two filters' best settings
# differ in scale (the eye then judges pixels against filter); when none does,
# clamped-cubic's knee. Sets BUDGET, BUDGET_FROM (the setting), PAIR_B,
# PAIR_C, PAIR_SPLIT (1 when the scales differ).
rs_pair() { # scene
    report_knee render_scale "$1" flip $(rs_series_settings bilinear)
    knee_b=$KNEE
    report_knee render_scale "$1" flip $(rs_series_settings clamped-cubic)
    knee_c=$KNEE
    others=$(awk -F '\t' -v s="$1" '$1 == s && $2 != "1" { print $3 "\t" $2 }' "$WORK/render_scale.tsv" |
        sort -g -r | cut -f2)
    PAIR_SPLIT=0
    for cand in $knee_b $knee_c $others; do
        [ "$cand" != 1 ] || continue
        rs_pair_at "$1" "$cand"
        if [ "$(rs_scale "$PAIR_B")" != "$(rs_scale "$PAIR_C")" ]; then
            PAIR_SPLIT=1
            return
        fi
    done
    [ "$knee_c" != 1 ] || knee_c=1_2-clamped-cubic
    rs_pair_at "$1" "$knee_c"
}
rs_pair_at() { # scene setting: the budget its frame time
    report_row render_scale "$1" "$2"
    BUDGET=$MS
    BUDGET_FROM=$2
    for f in $RS_FILTERS; do
        best=$(awk -F '\t' -v s="$1" -v t="$BUDGET" -v only=" $(rs_series_settings "$f") " '
            $1 == s && index(only, " " $2 " ") && $3 <= t && (b == "" || $6 < e) { b = $2; e = $6 }
            $1 == s && index(only, " " $2 " ") && (q == "" || $3 < qt) { q = $2; qt = $3 }
            END { print (b != "" ? b : q) }' "$WORK/render_scale.tsv")
        case $f in
            bilinear) PAIR_B=$best ;;
            *) PAIR_C=$best ;;
        esac
    done
}

# The section's plots from $WORK/render_scale.tsv (tools/report/replot.sh redraws them alone).
rs_plots() {
    series=""
    for f in $RS_FILTERS; do
        spec=""
        for s in $(rs_series_settings "$f"); do
            label=$(rs_scale "$s")
            # the shared full-size point is labelled by the first series only
            [ "$s" != 1 ] || [ "$f" = bilinear ] || label=""
            spec="$spec,$s:$label"
        done
        series="$series $f=${spec#,}"
    done
    # shellcheck disable=SC2086
    report_plot render_scale flip "mean FLIP against the reference (0 = identical)" \
        "Render scale: frame time against mean FLIP, per upscale filter" "" $series
    # shellcheck disable=SC2086
    report_plot render_scale rmse "RMSE against the reference (linear RGB)" \
        "Render scale: frame time against RMSE, per upscale filter" "" $series
}

knob_render_scale() { # scene labels...
    out=$WORK/section_render_scale.md
    for scene in "$@"; do
        set_list="1=$(rs_args 1 | tr ' ' '~')"
        for sc in $RS_SCALES; do
            for f in $RS_FILTERS; do
                set_list="$set_list $sc-$f=$(rs_args "$sc-$f" | tr ' ' '~')"
            done
        done
        # shellcheck disable=SC2086
        report_curve render_scale "$scene" $set_list
    done
    rs_plots
    width=${SIZE%x*}
    height=${SIZE#*x}
    {
        echo "## Render scale: rendered size and upscale filter"
        echo
        echo "Settings: render scale S = 1, 3/4, 1/2, 1/3, 1/4 of $SIZE (\`--scale S\`: each edge"
        echo "max(1, round(edge × S)) pixels, same view), upscaled to $SIZE by \`--upscale bilinear\` or"
        echo "\`--upscale clamped-cubic\` (Catmull-Rom clamped to the 2×2 nearest rendered pixels;"
        echo "engine/render/upscale.h); one ray through each pixel centre (\`--sampler single\`) throughout. Two"
        echo "series per scene, one per filter, both starting at full size (scale 1, no upscaling)."
        echo
        echo "Frame time: as for every knob, \`tessera render --display null --frames $FRAMES --threads $THREADS\`, the"
        echo "ms/frame it prints (pipeline_run's wall time over the frames rendered), median of $RUNS runs"
        echo "taken in turn over the settings. **The upscale is inside it**: the render threads render the"
        echo "low-res frame, meet at the upscale barrier, then upscale bands of tile rows between them"
        echo "(engine/frame/pipeline.h, RENDER SCALE; the governor's reduced frames are made the same way). The"
        echo "upscale column is that stage's time per frame (the \`render scale\` line's ms/frame: per frame"
        echo "the longest thread's share, median of the same runs), a part of the frame time. Error: the"
        echo "upscaled $SIZE image (EXR) against the same full-size reference as every knob."
        echo
        echo "| scene | scale | filter | rendered | frame ms (min-max) | upscale ms | × scale 1 | mean FLIP | FLIP median | FLIP q3 | RMSE | PSNR dB |"
        echo "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        for scene in "$@"; do
            report_row render_scale "$scene" 1
            ms_full=$MS
            for s in 1 $(for sc in $RS_SCALES; do for f in $RS_FILTERS; do echo "$sc-$f"; done; done); do
                report_row render_scale "$scene" "$s"
                report_upscale_ms render_scale "$scene" "$s"
                echo "| $scene | $(rs_scale "$s") | $(rs_filter "$s") | $(rs_px "$width" "$s")×$(rs_px "$height" "$s") |" \
                    "$MS ($MS_LO-$MS_HI) | ${UPSCALE_MS:-–} | $(rs_ratio "$MS" "$ms_full") | $FLIP | $FLIP_MEDIAN |" \
                    "$FLIP_Q3 | $RMSE | $PSNR |"
            done
        done
        echo
        echo "The numbers: [report/render_scale.tsv](report/render_scale.tsv) (tab-separated: scene, setting,"
        echo "ms median, min, max, flip mean, median, q3, rmse, psnr; setting 3_4-bilinear is scale 3/4,"
        echo "bilinear)."
        echo
        echo "![frame time against mean FLIP per filter](report/render_scale_flip.png)"
        echo
        rs_sentences flip "mean FLIP" "$@"
        echo
        echo "![frame time against RMSE per filter](report/render_scale_rmse.png)"
        echo
        rs_sentences rmse "RMSE" "$@"
        echo
        echo "**Default shipped: scale 1 (full size), filter \`bilinear\`.** \`tessera render\` and \`tessera"
        echo "run\` render at full size unless \`--scale\` or \`--budget-ms\` says otherwise: every step down raises"
        echo "the error (above), so the scale is for when the frame rate cannot be had otherwise. The"
        echo "frame-budget governor (\`--budget-ms\`, the governor section) lowers it only while a moving"
        echo "camera would overrun its budget and refines at full size when the camera stops. The governor"
        echo "ships \`--upscale bilinear\` by default, as \`--scale\` does, because bilinear is the cheaper"
        echo "filter (the upscale column). What the data shows at equal time, by mean FLIP:"
        for scene in "$@"; do
            rs_equal_time "$scene" flip
            if [ "$ET_N" -gt 0 ]; then
                printf '%s, %s (clamped-cubic / bilinear %s at the median of %s comparisons);\n' \
                    "$scene" "$ET_VERDICT" "$ET_MEDIAN" "$ET_N"
            else
                printf '%s, %s;\n' "$scene" "$ET_VERDICT"
            fi
        done
        echo "where bilinear does not lose at equal time, its lower cost decides; where clamped-cubic wins,"
        echo "the default is to be reconsidered on a full-size run on a quiet machine. \`tessera render"
        echo "--scale\`, which this section measures, makes its frames as the governor makes its reduced"
        echo "ones (the same pipeline stage: low-res tiles, the upscale barrier, bands of rows upscaled by"
        echo "every render thread), so these frame times are the governor's at a fixed scale (its own run"
        echo "along a path is in the governor section). *(This reason is the project's"
        echo "choice, written in tools/report/knob_render_scale.sh; the knees and equal-time verdicts are"
        echo "computed from the table.)*"
        for scene in "$@"; do
            rs_equal_time "$scene" flip
            case $ET_VERDICT in
                "clamped-cubic wins"*)
                    echo "On $scene the measured equal-time verdict goes against that default (clamped-cubic's"
                    echo "mean FLIP is $ET_MEDIAN× bilinear's at equal time): the default filter is to be reconsidered"
                    echo "on a full-size run on a quiet machine."
                    ;;
            esac
        done
        echo
        echo "### Reference converged?"
        echo
        for scene in "$@"; do
            report_reference "$scene"
            hf=$(report_field "$REF_HALVES" flip_mean)
            min_flip=$(awk -F '\t' -v s="$scene" '$1 == s && (m == "" || $6 < m) { m = $6 } END { print m }' \
                "$WORK/render_scale.tsv")
            echo "- $scene: the smallest mean FLIP of this curve ($min_flip, full size) is $(rs_ratio "$min_flip" "$hf")× the"
            echo "  FLIP between the reference's two halves ($hf)$(awk -v a="$min_flip" -v b="$hf" 'BEGIN { if (a < 3 * b) printf ": **under 3×, not converged enough for this curve**" }')."
        done
        echo
        echo "### Side by side at equal time"
        echo
        echo "A budget of frame time, and the best each filter does within it: its setting of lowest mean FLIP"
        echo "among those that take no longer (full size included). The budget is the frame time of the first"
        echo "of bilinear's knee, clamped-cubic's knee, then every other point from the slowest, at which the"
        echo "two filters' best settings differ in scale: more pixels against a better filter, in the same time."
        echo "Each is what a governor holding that budget would pick with that filter; their own frame times"
        echo "are below the budget by as much as the step between two scales (the settings are discrete)."
        echo
        for scene in "$@"; do
            rs_pair "$scene"
            report_crops render_scale "$scene" "$PAIR_B" "$PAIR_C"
            report_row render_scale "$scene" "$PAIR_B"
            b_ms=$MS b_flip=$FLIP
            report_row render_scale "$scene" "$PAIR_C"
            echo "![$scene: reference, $(rs_scale "$PAIR_B") $(rs_filter "$PAIR_B"), $(rs_scale "$PAIR_C") $(rs_filter "$PAIR_C") and their FLIP maps](report/$CROP)"
            echo
            echo "$scene, a budget of $BUDGET ms/frame (the frame time of $(rs_scale "$BUDGET_FROM") $(rs_filter "$BUDGET_FROM")) and the best"
            echo "each filter does within it (lowest mean FLIP among its settings that take no longer):"
            echo "bilinear at scale $(rs_scale "$PAIR_B") ($b_ms ms, mean FLIP $b_flip) and clamped-cubic at scale"
            echo "$(rs_scale "$PAIR_C") ($MS ms, $FLIP). The ${CROP_PX}×$CROP_PX pixels at ($CROP_X, $CROP_Y) where the"
            echo "bilinear one differs most from the reference$([ "$CROP_ZOOM" -gt 1 ] && echo ", enlarged $CROP_ZOOM×"): top, the reference and the"
            echo "two; below, their FLIP maps (black 0, pale yellow 1)."
            if [ "$PAIR_SPLIT" = 0 ]; then
                echo "At no point's frame time do the two filters' best settings differ in scale on this curve, so"
                echo "this pair (at clamped-cubic's knee) differs in the filter only."
            fi
            echo
        done
    } > "$out"
    cp "$WORK/render_scale.tsv" "$WORK/plots/render_scale.tsv"
}

# The sentence under a plot: what it shows; per scene and filter, where the
# knee is and what it buys against full size; which filter wins at equal time.
rs_sentences() { # metric name scenes...
    metric=$1
    what=$2
    shift 2
    printf 'Frame time against %s at render scales 1, 3/4, 1/2, 1/3, 1/4, one series per filter ' "$what"
    printf '(bilinear: circles, clamped-cubic: squares), on %s. ' "$(echo "$*" | sed 's/ /, /g')"
    for scene in "$@"; do
        report_row render_scale "$scene" 1
        ms0=$MS
        e0=$(rs_error "$scene" 1 "$metric")
        for f in $RS_FILTERS; do
            # shellcheck disable=SC2046
            report_knee render_scale "$scene" "$metric" $(rs_series_settings "$f")
            if [ "$KNEE" = 1 ]; then
                printf 'On %s with %s the knee is at full size: no scale buys time at a better rate than the straight line to 1/4. ' \
                    "$scene" "$f"
                continue
            fi
            report_row render_scale "$scene" "$KNEE"
            printf 'On %s with %s the knee is at scale %s: %s× the %s of full size (%s to %s) in %s of its frame time (%s to %s ms). ' \
                "$scene" "$f" "$(rs_scale "$KNEE")" "$(rs_ratio "$(rs_error "$scene" "$KNEE" "$metric")" "$e0")" "$what" \
                "$e0" "$(rs_error "$scene" "$KNEE" "$metric")" \
                "$(awk -v a="$MS" -v b="$ms0" 'BEGIN { printf "%.0f %%", (b > 0 ? 100 * a / b : 0) }')" "$ms0" "$MS"
        done
        rs_equal_time "$scene" "$metric"
        if [ "$ET_N" -gt 0 ]; then
            printf 'At equal time on %s, %s: clamped-cubic'"'"'s %s is %s× bilinear'"'"'s at the median of %s comparisons (%s to %s; clamped-cubic lower in %s). ' \
                "$scene" "$ET_VERDICT" "$what" "$ET_MEDIAN" "$ET_N" "$ET_MIN" "$ET_MAX" "$ET_CUBIC"
        else
            printf 'At equal time on %s: %s. ' "$scene" "$ET_VERDICT"
        fi
    done
    echo "(Knee: the point farthest below the line from the fastest to the slowest point of a series, both"
    echo "axes scaled to [0, 1]: Kneedle, Satopää et al. 2011. Equal time: each series' error interpolated,"
    echo "piecewise linear in log frame time and log error, at the frame times of the other series' points"
    echo "that lie within its range, as the ratio clamped-cubic / bilinear; a filter wins when it is lower in"
    echo "at least 3/4 of the comparisons and by 3 % or more at the median.)"
}
