# knob_antialiasing.sh - the antialiasing section of REPORT.md: samples per
# pixel (the pixel sampler, engine/render/sampler.h) against frame time and error.
# Sourced by tools/report/report.sh, which calls knob_antialiasing once with
# the scenes measured; it writes $WORK/section_antialiasing.md and its
# pictures into $WORK/plots/ (lib.sh has the shared machinery).

# The settings, label=render options: `single` is what the kiosk renders (one
# ray through the pixel centre); 1x1 is one jittered ray (same cost, shows
# what randomness alone does); then K x K jittered strata.
AA_SETTINGS="single 1x1 2x2 3x3 4x4"
aa_args() { # label -> render options
    case $1 in
        single) echo "--sampler single" ;;
        1x1) echo "--sampler jittered:1" ;;
        2x2) echo "--sampler jittered:2" ;;
        3x3) echo "--sampler jittered:3" ;;
        4x4) echo "--sampler jittered:4" ;;
    esac
}
aa_samples() { # label -> rays per pixel
    case $1 in
        single | 1x1) echo 1 ;;
        *) echo $((${1%x*} * ${1#*x})) ;;
    esac
}

# ratio a / b to 1 decimal, percent fall from a to b
aa_ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.1f", (b > 0 ? a / b : 0) }'; }
aa_fall() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.0f", (a > 0 ? 100 * (a - b) / a : 0) }'; }

# The section's plots from $WORK/antialiasing.tsv (tools/report/replot.sh redraws them alone).
aa_plots() {
    report_plot antialiasing flip "mean FLIP against the reference (0 = identical)" \
        "Antialiasing: frame time against mean FLIP (single: the pixel centre, apart)" single
    report_plot antialiasing rmse "RMSE against the reference (linear RGB)" \
        "Antialiasing: frame time against RMSE (single: the pixel centre, apart)" single
}

knob_antialiasing() { # scene labels...
    out=$WORK/section_antialiasing.md
    for scene in "$@"; do
        set_list=""
        for s in $AA_SETTINGS; do
            set_list="$set_list $s=$(aa_args "$s" | tr ' ' '~')"
        done
        # (render options travel with '~' for spaces through one word; report_curve splits them back)
        # shellcheck disable=SC2086
        report_curve antialiasing "$scene" $set_list
    done
    aa_plots
    {
        echo "## Antialiasing: samples per pixel"
        echo
        echo "Settings: \`single\` (one ray through the pixel centre: what the kiosk renders, \`--sampler single\`),"
        echo "\`1x1\` (one jittered ray, \`--sampler jittered:1\`), and K×K jittered strata per pixel"
        echo "(\`--sampler jittered:K\`, K = 2, 3, 4; fixed seed 0). Frame time: \`tessera render --display null"
        echo "--frames $FRAMES --threads $THREADS\`, mean ms/frame of a run (pipeline_run's wall time: no process"
        echo "start, scene load, BVH build or image writing), median of $RUNS runs taken in turn over the"
        echo "settings, with the fastest and slowest run. Error: \`tessera compare REFERENCE IMAGE\` on the"
        echo "image rendered to EXR (linear, so no 8-bit rounding), at FLIP's default 67 pixels per degree."
        echo
        echo "| scene | setting | rays/pixel | frame ms (min-max) | × single | mean FLIP | FLIP median | FLIP q3 | RMSE | PSNR dB |"
        echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
        for scene in "$@"; do
            report_row antialiasing "$scene" single
            ms_single=$MS
            for s in $AA_SETTINGS; do
                report_row antialiasing "$scene" "$s"
                echo "| $scene | $s | $(aa_samples "$s") | $MS ($MS_LO-$MS_HI) | $(aa_ratio "$MS" "$ms_single") |" \
                    "$FLIP | $FLIP_MEDIAN | $FLIP_Q3 | $RMSE | $PSNR |"
            done
        done
        echo
        for scene in "$@"; do
            report_row antialiasing "$scene" single
            f0=$FLIP r0=$RMSE
            report_row antialiasing "$scene" 1x1
            echo "On $scene, \`1x1\` (one ray at a random place in the pixel) costs what \`single\` costs and has"
            if awk -v a="$FLIP" -v b="$f0" 'BEGIN { exit !(a > b) }'; then
                verdict="for one ray, the pixel centre is the better guess"
            else
                verdict="for one ray, a random place is no worse than the centre"
            fi
            echo "$(aa_ratio "$FLIP" "$f0")× its mean FLIP, $(aa_ratio "$RMSE" "$r0")× its RMSE: $verdict."
        done
        echo
        echo "The numbers: [report/antialiasing.tsv](report/antialiasing.tsv) (tab-separated: scene, setting,"
        echo "ms median, min, max, flip mean, median, q3, rmse, psnr)."
        echo
        echo "![frame time against mean FLIP](report/antialiasing_flip.png)"
        echo
        aa_sentences flip "mean FLIP" "$@"
        echo
        echo "![frame time against RMSE](report/antialiasing_rmse.png)"
        echo
        aa_sentences rmse "RMSE" "$@"
        echo
        echo "**Default shipped: \`single\`.** A moving camera needs its frame rate first, and \`single\` is the"
        echo "fastest point of the curve; a still camera can afford more, and gets it from refinement over"
        echo "frames (issue 13's governor accumulates jittered samples towards the converged image) rather"
        echo "than from a higher per-frame sample count. *(This reason is the project's choice, written in"
        echo "tools/report/knob_antialiasing.sh; the knees and ratios above are computed from the table.)*"
        echo
        echo "### Reference converged?"
        echo
        for scene in "$@"; do
            report_reference "$scene"
            hf=$(report_field "$REF_HALVES" flip_mean)
            hr=$(report_field "$REF_HALVES" rmse)
            min_flip=$(awk -F '\t' -v s="$scene" '$1 == s && (m == "" || $6 < m) { m = $6 } END { print m }' \
                "$WORK/antialiasing.tsv")
            min_rmse=$(awk -F '\t' -v s="$scene" '$1 == s && (m == "" || $9 < m) { m = $9 } END { print m }' \
                "$WORK/antialiasing.tsv")
            # two independent halves of N/2 rays: var(A - B) = 4 var(reference), so the reference is
            # about RMSE hr / 2 from converged; that adds sqrt(1 + (ref / e)^2) - 1 to a measured RMSE e
            ref_rmse=$(awk -v r="$hr" 'BEGIN { printf "%.2g", r / 2 }')
            inflation=$(awk -v r="$hr" -v e="$min_rmse" 'BEGIN { q = r / 2 / e; printf "%.2f", 100 * (sqrt(1 + q * q) - 1) }')
            times=$(awk -v a="$min_flip" -v b="$hf" 'BEGIN { printf "%.1f", (b > 0 ? a / b : 1e9) }')
            echo "- $scene: the reference's two halves differ by mean FLIP $hf, RMSE $hr, so the reference is"
            echo "  about RMSE $ref_rmse from converged, which adds $inflation % to the smallest RMSE of the curve"
            echo "  ($min_rmse); the smallest mean FLIP of the curve ($min_flip) is $times× the halves' FLIP."
            if awk -v i="$inflation" -v t="$times" 'BEGIN { exit !(i > 1 || t < 3) }'; then
                echo "  **Not converged enough for this curve** (over 1 % or under 3×): raise REPORT_REF_RENDERS."
            fi
        done
        echo
        echo "### Side by side"
        echo
        for scene in "$@"; do
            report_knee antialiasing "$scene" flip
            other=$KNEE
            [ "$other" != single ] || other=2x2
            report_crops antialiasing "$scene" single "$other"
            report_row antialiasing "$scene" single
            a_ms=$MS a_flip=$FLIP
            report_row antialiasing "$scene" "$other"
            echo "![$scene: reference, single, $other and their FLIP maps](report/$CROP)"
            echo
            echo "$scene, the ${CROP_PX}×$CROP_PX pixels at ($CROP_X, $CROP_Y) where \`single\` differs most from the"
            echo "reference$([ "$CROP_ZOOM" -gt 1 ] && echo ", enlarged $CROP_ZOOM×"): top, the reference, \`single\` ($a_ms ms, mean FLIP"
            echo "$a_flip over the whole image) and \`$other\` ($MS ms, $FLIP); below, their FLIP maps (black 0, pale"
            echo "yellow 1). Not equal time: two settings of one knob never cost the same; the render-scale"
            echo "section has equal-time pairs of its two upscale filters (antialiasing at a smaller scale"
            echo "against \`single\` at full size is not measured yet)."
            echo
        done
    } > "$out"
    cp "$WORK/antialiasing.tsv" "$WORK/plots/antialiasing.tsv"
}

# The sentence under a plot: per scene, where the knee is and what the
# steps before and after it buy.
aa_sentences() { # metric name scenes...
    metric=$1
    what=$2
    shift 2
    col=$(report_metric_column "$metric")
    printf 'Frame time against %s for each setting, on %s. ' "$what" "$(echo "$*" | sed 's/ /, /g')"
    for scene in "$@"; do
        report_knee antialiasing "$scene" "$metric"
        knee=$KNEE
        report_row antialiasing "$scene" single
        ms0=$MS
        e0=$(awk -F '\t' -v s="$scene" -v c="$col" '$1 == s && $2 == "single" { print $c }' "$WORK/antialiasing.tsv")
        report_row antialiasing "$scene" "$knee"
        ms1=$MS
        e1=$(awk -F '\t' -v s="$scene" -v c="$col" -v k="$knee" '$1 == s && $2 == k { print $c }' \
            "$WORK/antialiasing.tsv")
        report_row antialiasing "$scene" 4x4
        ms2=$MS
        e2=$(awk -F '\t' -v s="$scene" -v c="$col" '$1 == s && $2 == "4x4" { print $c }' "$WORK/antialiasing.tsv")
        if [ "$knee" = single ]; then
            printf 'On %s the knee is at `single`: no setting buys %s at a better rate than the straight line to 4x4 (%s ms, %s). ' \
                "$scene" "$what" "$ms2" "$e2"
        else
            printf 'On %s the knee is at %s: from `single` to %s the %s falls by %s %% (%s to %s) for %s× the frame time (%s to %s ms)' \
                "$scene" "$knee" "$knee" "$what" "$(aa_fall "$e0" "$e1")" "$e0" "$e1" "$(aa_ratio "$ms1" "$ms0")" "$ms0" "$ms1"
            if [ "$knee" != 4x4 ]; then
                printf '; from %s to 4x4 it falls by another %s %% (to %s) for %s× more (%s ms). ' \
                    "$knee" "$(aa_fall "$e1" "$e2")" "$e2" "$(aa_ratio "$ms2" "$ms1")" "$ms2"
            else
                printf '. '
            fi
        fi
    done
    echo "(Knee: the point farthest below the line from the fastest to the slowest point, both axes"
    echo "scaled to [0, 1]: Kneedle, Satopää et al. 2011.)"
}
