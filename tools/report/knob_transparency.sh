# knob_transparency.sh - the transparency section of REPORT.md: how far a
# ray blends transparent surfaces (renderer.transparency.min_transmittance
# and max_layers, docs/pipeline-config.md) against frame time and error, at
# global opacity 0.3. Sourced by tools/report/report.sh, which calls
# knob_transparency once with the scenes measured; it writes
# $WORK/section_transparency.md and its pictures into $WORK/plots/.
#
# Scenes: a 10,000-part assembly (build/gen-assembly --parts 10000
# --triangles 2000000, generated into $WORK: the same options give the same
# bytes), seen from close by so that skin, frames and stringers overlap
# along most rays, and the shared meshes among the scenes given (the dragon,
# seen through itself). Not the built-in scene: the other knobs' scenes stay
# as they are.
#
# Reference: NOT the scene's jittered mean. Transparency is blended per
# pixel ray, so the reference is the same pixel-centre rays (--sampler
# single, as every setting) with the limits removed: min_transmittance 1e-6,
# max_layers 64 (report_knob_reference). The error of a setting is then only
# what its limits cut off, with no antialiasing in it.
#
# Settings, named L<max_layers>-m<min_transmittance> ('1_255' for 1/255):
# two series through the default L16-m1_255, one varying each limit.
#
# shellcheck shell=sh disable=SC2046,SC2034,SC2154
# (SC2046: a series' settings are passed as separate words on purpose; SC2034,
# SC2154: SCENE_ARG_assembly is read by lib.sh, rs and note are set through eval)

TR_OPACITY=0.3
TR_THRESHOLDS="1_255 0.02 0.05 0.1 0.25" # min_transmittance at max_layers 16
TR_LAYERS="2 4 8 16 64"                  # max_layers at min_transmittance 1/255
TR_DEFAULT=L16-m1_255
# the assembly's camera: beside the fuselage, looking at its side from 5.7 units (eye, look-at, up, fov)
TR_ASSEMBLY_CAMERA=40,1.5,5.5,40,0,0,0,1,0,60

tr_value() { # threshold word -> the number
    case $1 in
        1_255) echo 0.00392156862745098 ;;
        *) echo "$1" ;;
    esac
}
tr_label() { # threshold word -> how the text writes it
    case $1 in
        1_255) echo 1/255 ;;
        *) echo "$1" ;;
    esac
}
tr_settings() { # every setting, in measuring order (the default once)
    for m in $TR_THRESHOLDS; do printf 'L16-m%s ' "$m"; done
    for l in $TR_LAYERS; do [ "$l" = 16 ] || printf 'L%s-m1_255 ' "$l"; done
    echo
}
tr_config() { # setting -> its config file (written on first use)
    tc_file=$WORK/transparency/$1.json
    if [ ! -f "$tc_file" ]; then
        tc_layers=${1%%-*}
        tc_layers=${tc_layers#L}
        printf '{"opacity": %s, "renderer": {"transparency": {"min_transmittance": %s, "max_layers": %s}}}\n' \
            "$TR_OPACITY" "$(tr_value "${1#*-m}")" "$tc_layers" > "$tc_file"
    fi
    echo "$tc_file"
}
tr_camera() { # scene -> its camera option, '~' for the space
    case $1 in
        assembly) echo "~--camera~$TR_ASSEMBLY_CAMERA" ;;
        *) echo "" ;;
    esac
}
# The fastest setting of a scene whose metric is at most BOUND, into FAST (empty: none).
tr_fastest_within() { # scene metric bound
    FAST=$(awk -F '\t' -v s="$1" -v c="$(report_metric_column "$2")" -v b="$3" \
        '$1 == s && $c <= b && (best == "" || $3 < ms) { best = $2; ms = $3 } END { print best }' \
        "$WORK/transparency.tsv")
}
TR_FLIP_BOUND=0.001 # a mean FLIP nobody sees: under half of what one ray per pixel costs in the antialiasing section
# The most layers a setting blends at a uniform opacity TR_OPACITY: max_layers,
# or fewer where the threshold stops the ray first (after n layers the light
# left is (1 - opacity)^n: the first n with that below min_transmittance).
tr_layers_blended() { # setting
    awk -v a="$TR_OPACITY" -v m="$(tr_value "${1#*-m}")" -v l="$(echo "${1%%-*}" | tr -d L)" 'BEGIN {
        n = 1; t = 1 - a; while (t >= m && n < l) { n++; t *= 1 - a }; print n }'
}
tr_ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }'; }

# The section's plots from $WORK/transparency.tsv (tools/report/replot.sh redraws them alone).
tr_plots() {
    thr_series="threshold=$(for m in $TR_THRESHOLDS; do printf 'L16-m%s:%s,' "$m" "$(tr_label "$m")"; done | sed 's/,$//')"
    lay_series="layers=$(for l in $TR_LAYERS; do
        if [ "$l" = 16 ]; then printf 'L16-m1_255:,'; else printf 'L%s-m1_255:L%s,' "$l" "$l"; fi
    done | sed 's/,$//')"
    report_plot transparency flip "mean FLIP against the reference (0 = identical)" \
        "Transparency at opacity $TR_OPACITY: frame time against mean FLIP" '' "$thr_series" "$lay_series"
    report_plot transparency rmse "RMSE against the reference (linear RGB)" \
        "Transparency at opacity $TR_OPACITY: frame time against RMSE" '' "$thr_series" "$lay_series"
}

knob_transparency() { # scene labels...
    out=$WORK/section_transparency.md
    tr_load_before=$(cat /proc/loadavg)
    tr_start=$(date -u '+%Y-%m-%d %H:%M UTC')
    mkdir -p "$WORK/transparency"
    tr_scenes=assembly
    for scene in "$@"; do
        [ "$scene" = default ] || tr_scenes="$tr_scenes $scene"
    done
    # the assembly: a scene of this knob's own
    [ -x build/gen-assembly ] || report_fail "build/gen-assembly not built: run 'make build/gen-assembly' (or make report)"
    report_run build/gen-assembly --parts 10000 --triangles 2000000 -o "$WORK/transparency/assembly.glb"
    tr_gen=$(cat "$WORK/cmd.out")
    SCENE_ARG_assembly=$WORK/transparency/assembly.glb
    printf '{"opacity": %s, "renderer": {"transparency": {"min_transmittance": 1e-6, "max_layers": 64}}}\n' \
        "$TR_OPACITY" > "$WORK/transparency/reference.json"
    for scene in $tr_scenes; do
        cam=$(tr_camera "$scene")
        report_knob_reference transparency "$scene" "--sampler~single~--config~$WORK/transparency/reference.json$cam"
        eval "TR_REF_SECONDS_$scene=\$REF_SECONDS"
        set_list=""
        for s in $(tr_settings); do
            set_list="$set_list $s=--sampler~single~--config~$(tr_config "$s")$cam"
        done
        # shellcheck disable=SC2086
        report_curve transparency "$scene" $set_list
    done
    tr_plots
    cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
    tr_load_after=$(cat /proc/loadavg)
    {
        echo "## Transparency: termination threshold and layer count"
        echo
        echo "Every surface at opacity $TR_OPACITY (a pipeline config with \`\"opacity\": $TR_OPACITY\`), the raytracer with"
        echo "transparent shadows (the default), one ray through each pixel centre (\`--sampler single\`). Two"
        echo "series through the default (\`min_transmittance\` 1/255, \`max_layers\` 16): \`min_transmittance\`"
        echo "$(for m in $TR_THRESHOLDS; do printf '%s, ' "$(tr_label "$m")"; done | sed 's/, $//') at \`max_layers\` 16, and \`max_layers\`"
        echo "$(echo "$TR_LAYERS" | sed 's/ /, /g') at \`min_transmittance\` 1/255 (settings named L<layers>-m<threshold>)."
        echo
        echo "**Reference: not the jittered mean of the other sections.** Transparency is blended per pixel"
        echo "ray, so the reference is the same pixel-centre rays with the limits removed (\`min_transmittance\`"
        echo "1e-6, \`max_layers\` 64; \`report_knob_reference\` in tools/report/lib.sh): an error here is only what"
        echo "the limits cut off, no antialiasing in it. At opacity $TR_OPACITY the 64th layer still lets"
        echo "$(awk -v a="$TR_OPACITY" 'BEGIN { printf "%.1e", (1 - a) ^ 64 }') of the light through, below what any 8-bit output shows."
        echo
        echo "Scenes:"
        for scene in $tr_scenes; do
            eval "rs=\$TR_REF_SECONDS_$scene"
            case $scene in
                assembly)
                    echo "- **assembly**: \`build/gen-assembly --parts 10000 --triangles 2000000\` ($(echo "$tr_gen" |
                        sed 's/ file=.*//')), camera \`--camera $TR_ASSEMBLY_CAMERA\`: beside the fuselage, skin, frames,"
                    echo "  stringers and pipes overlapping along most rays. Reference render: $rs s."
                    ;;
                *)
                    eval "note=\$SCENE_NOTE_$scene"
                    echo "- **$scene**: $note, seen through itself. Reference render: $rs s."
                    ;;
            esac
        done
        echo
        echo "Machine: ${cpu:-unknown CPU} (lscpu), $(nproc) CPUs, $THREADS render threads; measured from $tr_start,"
        echo "load average (/proc/loadavg) before: $tr_load_before; after: $tr_load_after."
        if [ "$SIZE" != 1920x1080 ]; then
            echo "Image size **$SIZE** (reduced: \`REPORT_SIZE=$SIZE REPORT_FRAMES=$FRAMES REPORT_KNOBS=\"$RUN_KNOBS\" make report\`;"
            echo "the other sections may be at another size, see the header)."
        else
            echo "Image size $SIZE."
        fi
        echo "Frame time:"
        echo "\`tessera render --scene S --size $SIZE --threads $THREADS --frames $FRAMES --display null --sampler single"
        echo "--config L<layers>-m<threshold>.json\`, mean ms/frame of a run, median of $RUNS runs taken in turn over"
        echo "the settings (min-max in brackets). Error: \`tessera compare REFERENCE IMAGE\` on EXR renders."
        echo
        echo "Layers blended: the most surfaces a ray blends under the setting at a uniform opacity $TR_OPACITY"
        echo "(\`max_layers\`, or the first n with $(awk -v a="$TR_OPACITY" 'BEGIN { print 1 - a }')^n below \`min_transmittance\`), so at this opacity the"
        echo "threshold series is a layer count too, and the two defaults stop a ray at the same surface."
        echo
        echo "| scene | max_layers | min_transmittance | layers blended | frame ms (min-max) | × default | mean FLIP | FLIP q3 | RMSE | PSNR dB |"
        echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        for scene in $tr_scenes; do
            report_row transparency "$scene" "$TR_DEFAULT"
            ms_def=$MS
            for s in $(tr_settings); do
                report_row transparency "$scene" "$s"
                l=${s%%-*}
                mark=""
                [ "$s" != "$TR_DEFAULT" ] || mark=" (default)"
                echo "| $scene | ${l#L} | $(tr_label "${s#*-m}")$mark | $(tr_layers_blended "$s") | $MS ($MS_LO-$MS_HI) |" \
                    "$(tr_ratio "$MS" "$ms_def") |" \
                    "$FLIP | $FLIP_Q3 | $RMSE | $PSNR |"
            done
        done
        echo
        echo "The numbers: [report/transparency.tsv](report/transparency.tsv) (columns as report/antialiasing.tsv)."
        echo
        echo "![frame time against mean FLIP](report/transparency_flip.png)"
        echo
        echo "![frame time against RMSE](report/transparency_rmse.png)"
        echo
        echo "### The defaults on the curves"
        echo
        for scene in $tr_scenes; do
            report_knee transparency "$scene" flip $(for m in $TR_THRESHOLDS; do printf 'L16-m%s ' "$m"; done)
            knee_m=$KNEE
            report_knee transparency "$scene" flip $(for l in $TR_LAYERS; do printf 'L%s-m1_255 ' "$l"; done)
            knee_l=$KNEE
            report_row transparency "$scene" "$TR_DEFAULT"
            d_ms=$MS d_flip=$FLIP
            report_row transparency "$scene" L64-m1_255
            l64_ms=$MS l64_flip=$FLIP
            report_row transparency "$scene" L8-m1_255
            l8_ms=$MS l8_flip=$FLIP
            report_row transparency "$scene" L16-m0.02
            m2_ms=$MS m2_flip=$FLIP
            echo "- **$scene**: the knee (mean FLIP; Kneedle, as the antialiasing section) of the"
            echo "  \`min_transmittance\` series is at $knee_m, of the \`max_layers\` series at $knee_l. The default"
            echo "  ($d_ms ms, mean FLIP $d_flip): \`max_layers\` 64 costs $(tr_ratio "$l64_ms" "$d_ms")× and brings FLIP to $l64_flip;"
            echo "  \`max_layers\` 8 costs $(tr_ratio "$l8_ms" "$d_ms")× with FLIP $l8_flip; \`min_transmittance\` 0.02"
            echo "  costs $(tr_ratio "$m2_ms" "$d_ms")× with FLIP $m2_flip."
            tr_fastest_within "$scene" flip "$TR_FLIP_BOUND"
            if [ -n "$FAST" ]; then
                report_row transparency "$scene" "$FAST"
                echo "  The fastest setting within mean FLIP $TR_FLIP_BOUND of the reference: $FAST ($MS ms,"
                echo "  $(tr_ratio "$MS" "$d_ms")× the default's time, FLIP $FLIP)."
            fi
        done
        echo
        # the reading, on the assembly (the scene with many layers)
        report_row transparency assembly "$TR_DEFAULT"
        d_ms=$MS d_flip=$FLIP
        report_knee transparency assembly flip $(for m in $TR_THRESHOLDS; do printf 'L16-m%s ' "$m"; done)
        km=$KNEE
        report_row transparency assembly "$km"
        km_ms=$MS km_flip=$FLIP
        report_knee transparency assembly flip $(for l in $TR_LAYERS; do printf 'L%s-m1_255 ' "$l"; done)
        kl=$KNEE
        report_row transparency assembly "$kl"
        kl_ms=$MS kl_flip=$FLIP
        report_row transparency assembly L64-m1_255
        l64_ms=$MS
        echo "**Defaults kept: \`min_transmittance\` 1/255, \`max_layers\` 16.** At opacity $TR_OPACITY they stop a ray at the"
        echo "same surface, the 16th, with at most $(awk -v a="$TR_OPACITY" 'BEGIN { printf "%.2f", 100 * (1 - a) ^ 16 }') % of the light left. On the assembly the default is"
        echo "mean FLIP $d_flip from the reference with no limits, the flat end of both curves."
        for series in "min_transmittance:$km:$km_ms:$km_flip" "max_layers:$kl:$kl_ms:$kl_flip"; do
            sn=${series%%:*} rest=${series#*:}
            sk=${rest%%:*} rest=${rest#*:}
            if [ "$sk" = "$TR_DEFAULT" ]; then
                echo "The default is the knee of the \`$sn\` series."
            else
                echo "The knee of the \`$sn\` series is $sk (mean FLIP ${rest#*:}, $(tr_ratio "${rest%%:*}" "$d_ms")× the default's time): the"
                echo "default lies past it, on the side of the picture."
            fi
        done
        echo "What a lower limit cuts off is the deep layers, which a see-through inspection view is for,"
        echo "so the defaults stay where the error is invisible. Raising \`max_layers\` to 64 at 1/255 blends"
        echo "the same 16 layers (the table's layers blended; $(tr_ratio "$l64_ms" "$d_ms")× the default's time, which is the runs'"
        echo "noise). At a lower opacity the threshold lets more layers through (at 0.1: 53) and"
        echo "\`max_layers\` 16 becomes the limit that binds; not measured here. *(This reading is written in"
        echo "tools/report/knob_transparency.sh; the numbers in it are computed from the table.)*"
    } > "$out"
    cp "$WORK/transparency.tsv" "$WORK/plots/transparency.tsv"
}
