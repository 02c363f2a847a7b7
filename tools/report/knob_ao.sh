# knob_ao.sh - the ambient-occlusion section of REPORT.md: the `ao`
# renderer's rays per hit (renderer.ao.rays), its discontinuity filter
# (renderer.ao.filter_px) and accumulated frames (renderer.ao.frames,
# engine/render/render_ao.h FRAMES) against frame time and error. Sourced by
# tools/report/report.sh, which calls knob_ao once with the scenes measured;
# it writes $WORK/section_ao.md and its pictures into $WORK/plots/.
#
# Scenes: the shared meshes among the scenes given (the dragon; missing ones
# are skipped by report.sh) and one generated scene, the 10,000-part
# assembly of the transparency knob (build/gen-assembly, into $WORK), from
# the same close camera, opaque.
#
# Reference: NOT the scene's jittered mean (that would mix antialiasing and
# the raytracer's shading into the AO error): the ao renderer at the pixel
# centres (--sampler single, as every setting) with 64 rays per hit x 16
# frames (renderer.ao.frames 16: 1024 rays along one sequence, ao.h), filter
# off (report_knob_reference).
#
# Settings, named n<rays>-f<filter edge>-x<frames>: rays 1..64 with the
# filter off (1) and on (5), one frame; and the default 8 rays with 4 and 16
# frames, filter off and on: what accumulating frames at a still camera
# gives, at the pixel centre (renderer.ao.frames; the jittered sampler would
# move the pixel positions too and mix antialiasing into the error).
#
# Issue 33 changed the renderer's defaults (16 rays, 0.2 x the diagonal,
# renderer.ao.exponent 2.2; docs/inspection.md, Defaults) for how the picture
# reads, which this knob does not measure. Its configs set rays, filter and
# frames only, so a new run measures at the new distance and response; but
# AO_DEFAULT and the verdict's wording below still take 8 rays with the
# filter as "the default" (the run in REPORT.md predates the change): revise
# them with the next run.
#
# shellcheck shell=sh disable=SC2046,SC2034,SC2154
# (SC2046: a series' settings are passed as separate words on purpose; SC2034,
# SC2154: SCENE_ARG_assembly is read by lib.sh, rs and note are set through eval)

AO_RAY_COUNTS="1 2 4 8 16 32 64"
AO_FRAME_COUNTS="4 16" # besides 1, at 8 rays
AO_DEFAULT=n8-f5-x1
AO_ASSEMBLY_CAMERA=40,1.5,5.5,40,0,0,0,1,0,60

ao_settings() { # every setting, in measuring order
    for f in 1 5; do
        for n in $AO_RAY_COUNTS; do printf 'n%s-f%s-x1 ' "$n" "$f"; done
        for x in $AO_FRAME_COUNTS; do printf 'n8-f%s-x%s ' "$f" "$x"; done
    done
    echo
}
ao_config() { # setting -> its config file (written on first use)
    ac_file=$WORK/ao/$1.json
    if [ ! -f "$ac_file" ]; then
        ac_n=${1%%-*}
        ac_rest=${1#*-f}
        printf '{"renderer": {"name": "ao", "ao": {"rays": %s, "filter_px": %s, "frames": %s}}}\n' \
            "${ac_n#n}" "${ac_rest%%-*}" "${1##*-x}" > "$ac_file"
    fi
    echo "$ac_file"
}
ao_camera() { # scene -> its camera option, '~' for the space
    case $1 in
        assembly) echo "~--camera~$AO_ASSEMBLY_CAMERA" ;;
        *) echo "" ;;
    esac
}
# The fastest setting of a scene whose metric is at most BOUND, into FAST (empty: none).
ao_fastest_within() { # scene metric bound
    FAST=$(awk -F '\t' -v s="$1" -v c="$(report_metric_column "$2")" -v b="$3" \
        '$1 == s && $c <= b && (best == "" || $3 < ms) { best = $2; ms = $3 } END { print best }' \
        "$WORK/ao.tsv")
}
ao_ratio() { awk -v a="$1" -v b="$2" 'BEGIN { printf "%.2f", (b > 0 ? a / b : 0) }'; }

# The section's plots from $WORK/ao.tsv (tools/report/replot.sh redraws them alone).
ao_plots() {
    off_series="filter-off=$(for n in $AO_RAY_COUNTS; do printf 'n%s-f1-x1:%s,' "$n" "$n"; done | sed 's/,$//')"
    on_series="filter-5=$(for n in $AO_RAY_COUNTS; do printf 'n%s-f5-x1:%s,' "$n" "$n"; done | sed 's/,$//')"
    off_frames="frames-filter-off=n8-f1-x1:,$(for x in $AO_FRAME_COUNTS; do printf 'n8-f1-x%s:8x%s,' "$x" "$x"; done | sed 's/,$//')"
    on_frames="frames-filter-5=n8-f5-x1:,$(for x in $AO_FRAME_COUNTS; do printf 'n8-f5-x%s:8x%s,' "$x" "$x"; done | sed 's/,$//')"
    report_plot ao flip "mean FLIP against the reference (0 = identical)" \
        "Ambient occlusion: frame time against mean FLIP (labels: rays per hit, rays x frames)" '' \
        "$off_series" "$on_series" "$off_frames" "$on_frames"
    report_plot ao rmse "RMSE against the reference (linear RGB)" \
        "Ambient occlusion: frame time against RMSE (labels: rays per hit, rays x frames)" '' \
        "$off_series" "$on_series" "$off_frames" "$on_frames"
}

knob_ao() { # scene labels...
    out=$WORK/section_ao.md
    ao_load_before=$(cat /proc/loadavg)
    ao_start=$(date -u '+%Y-%m-%d %H:%M UTC')
    mkdir -p "$WORK/ao"
    ao_scenes=""
    for scene in "$@"; do
        [ "$scene" = default ] || ao_scenes="$ao_scenes $scene"
    done
    ao_scenes="${ao_scenes# } assembly"
    [ -x build/gen-assembly ] || report_fail "build/gen-assembly not built: run 'make build/gen-assembly' (or make report)"
    if [ ! -f "$WORK/transparency/assembly.glb" ]; then
        mkdir -p "$WORK/transparency"
        report_run build/gen-assembly --parts 10000 --triangles 2000000 -o "$WORK/transparency/assembly.glb"
    fi
    SCENE_ARG_assembly=$WORK/transparency/assembly.glb
    printf '{"renderer": {"name": "ao", "ao": {"rays": 64, "filter_px": 1, "frames": 16}}}\n' > "$WORK/ao/reference.json"
    for scene in $ao_scenes; do
        cam=$(ao_camera "$scene")
        report_knob_reference ao "$scene" "--sampler~single~--config~$WORK/ao/reference.json$cam"
        eval "AO_REF_SECONDS_$scene=\$REF_SECONDS"
        set_list=""
        for s in $(ao_settings); do
            set_list="$set_list $s=--sampler~single~--config~$(ao_config "$s")$cam"
        done
        # shellcheck disable=SC2086
        report_curve ao "$scene" $set_list
    done
    ao_plots
    cpu=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
    ao_load_after=$(cat /proc/loadavg)
    {
        echo "## Ambient occlusion: rays per hit, filter, accumulated frames"
        echo
        echo "The \`ao\` renderer (engine/render/render_ao.h), interleave 4 (the default), at the pixel centres"
        echo "(\`--sampler single\`). Settings n<rays>-f<filter>-x<frames>: rays per hit"
        echo "$(echo "$AO_RAY_COUNTS" | sed 's/ /, /g') with the discontinuity filter off (\`filter_px\` 1) and on"
        echo "(\`filter_px\` 5), one frame; and the default 8 rays averaged over $(echo "$AO_FRAME_COUNTS" | sed 's/ / and /')"
        echo "frames (\`renderer.ao.frames\`: each frame the next direction sets of the sequence, at the same pixel"
        echo "centre, so what a still camera accumulates without the jittered sampler's antialiasing mixed in;"
        echo "F frames cost what F frames do, primary rays included)."
        echo
        echo "**Reference: not the jittered mean of the other sections**, but the ao renderer at the same pixel"
        echo "centres with 64 rays × 16 frames (1024 rays per hit along one sequence), filter off: the error is"
        echo "the AO estimate's alone, neither antialiasing nor the raytracer's shading."
        echo
        echo "Scenes:"
        for scene in $ao_scenes; do
            eval "rs=\$AO_REF_SECONDS_$scene"
            case $scene in
                assembly)
                    echo "- **assembly**: the transparency section's assembly and camera (\`--camera $AO_ASSEMBLY_CAMERA\`),"
                    echo "  opaque. Reference render: $rs s."
                    ;;
                *)
                    eval "note=\$SCENE_NOTE_$scene"
                    echo "- **$scene**: $note. Reference render: $rs s."
                    ;;
            esac
        done
        echo
        echo "Machine: ${cpu:-unknown CPU} (lscpu), $(nproc) CPUs, $THREADS render threads; measured from $ao_start,"
        echo "load average (/proc/loadavg) before: $ao_load_before; after: $ao_load_after."
        if [ "$SIZE" != 1920x1080 ]; then
            echo "Image size **$SIZE** (reduced: \`REPORT_SIZE=$SIZE REPORT_FRAMES=$FRAMES REPORT_KNOBS=\"$RUN_KNOBS\" make report\`;"
            echo "the other sections may be at another size, see the header)."
        else
            echo "Image size $SIZE."
        fi
        echo "Frame time:"
        echo "\`tessera render --scene S --size $SIZE --threads $THREADS --frames $FRAMES --display null --sampler single"
        echo "--config n<rays>-f<filter>-x<frames>.json\`, mean ms/frame of a run, median of $RUNS runs taken in turn"
        echo "over the settings (min-max in brackets). Error: \`tessera compare REFERENCE IMAGE\` on EXR renders."
        echo
        echo "| scene | rays/hit | filter | frames | frame ms (min-max) | × default | mean FLIP | FLIP q3 | RMSE | PSNR dB |"
        echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
        for scene in $ao_scenes; do
            report_row ao "$scene" "$AO_DEFAULT"
            ms_def=$MS
            for s in $(ao_settings); do
                report_row ao "$scene" "$s"
                n=${s%%-*}
                rest=${s#*-f}
                mark=""
                [ "$s" != "$AO_DEFAULT" ] || mark=" (default)"
                echo "| $scene | ${n#n}$mark | ${rest%%-*} | ${s##*-x} | $MS ($MS_LO-$MS_HI) | $(ao_ratio "$MS" "$ms_def") |" \
                    "$FLIP | $FLIP_Q3 | $RMSE | $PSNR |"
            done
        done
        echo
        echo "The numbers: [report/ao.tsv](report/ao.tsv) (columns as report/antialiasing.tsv)."
        echo
        echo "![frame time against mean FLIP](report/ao_flip.png)"
        echo
        echo "![frame time against RMSE](report/ao_rmse.png)"
        echo
        echo "### The defaults on the curves"
        echo
        for scene in $ao_scenes; do
            report_knee ao "$scene" flip $(for n in $AO_RAY_COUNTS; do printf 'n%s-f5-x1 ' "$n"; done)
            knee_on=$KNEE
            report_knee ao "$scene" flip $(for n in $AO_RAY_COUNTS; do printf 'n%s-f1-x1 ' "$n"; done)
            knee_off=$KNEE
            report_row ao "$scene" n8-f5-x1
            d_ms=$MS d_flip=$FLIP d_rmse=$RMSE
            report_row ao "$scene" n8-f1-x1
            o_ms=$MS o_flip=$FLIP o_rmse=$RMSE
            report_row ao "$scene" n64-f1-x1
            n64_ms=$MS n64_flip=$FLIP
            report_row ao "$scene" n8-f5-x16
            x16_ms=$MS x16_flip=$FLIP
            echo "- **$scene**: knee (mean FLIP, Kneedle) of the rays series at ${knee_on%%-*} with the filter,"
            echo "  ${knee_off%%-*} without. The default (8 rays, filter 5: $d_ms ms, mean FLIP $d_flip, RMSE $d_rmse) against"
            echo "  8 rays unfiltered ($o_ms ms, $o_flip, $o_rmse): the filter costs $(ao_ratio "$d_ms" "$o_ms")× and"
            echo "  divides mean FLIP by $(ao_ratio "$o_flip" "$d_flip"), RMSE by $(ao_ratio "$o_rmse" "$d_rmse");"
            echo "  64 rays unfiltered: $(ao_ratio "$n64_ms" "$d_ms")× the default's time, FLIP $n64_flip;"
            echo "  8 rays × 16 frames filtered: $(ao_ratio "$x16_ms" "$d_ms")×, FLIP $x16_flip."
            for metric in flip rmse; do
                eval "bound=\$d_$metric"
                ao_fastest_within "$scene" "$metric" "$bound"
                report_row ao "$scene" "$FAST"
                if [ "$FAST" = "$AO_DEFAULT" ]; then
                    echo "  No setting is faster at the default's $metric or lower."
                else
                    echo "  At the default's $metric or lower, the fastest setting is $FAST ($MS ms,"
                    echo "  $(ao_ratio "$MS" "$d_ms")× the default's time; mean FLIP $FLIP, RMSE $RMSE)."
                fi
            done
        done
        echo
        # the reading, on each scene
        for scene in $ao_scenes; do
            report_row ao "$scene" n8-f5-x1
            d_ms=$MS d_rmse=$RMSE
            report_row ao "$scene" n8-f1-x1
            o_ms=$MS o_rmse=$RMSE
            # the fewest unfiltered rays at the default's RMSE or lower
            match=$(awk -F '\t' -v s="$scene" -v b="$d_rmse" '$1 == s && $2 ~ /-f1-x1$/ && $9 <= b {
                    n = substr($2, 2) + 0; if (best == "" || n < best) { best = n; ms = $3 } }
                END { if (best != "") print best, ms }' "$WORK/ao.tsv")
            report_row ao "$scene" n64-f5-x1
            f64_rmse=$RMSE
            report_row ao "$scene" n64-f1-x1
            u64_rmse=$RMSE
            report_row ao "$scene" n8-f5-x16
            af_rmse=$RMSE
            report_row ao "$scene" n8-f1-x16
            au_ms=$MS au_rmse=$RMSE
            printf '%s' "- **$scene**: the filter divides the 8-ray RMSE by $(ao_ratio "$o_rmse" "$d_rmse") for $(ao_ratio "$d_ms" "$o_ms")× the time"
            if [ -n "$match" ]; then
                printf '%s' "; unfiltered, ${match% *} rays reach the default's RMSE, at $(ao_ratio "${match#* }" "$d_ms")× its time"
            else
                printf '%s' "; unfiltered, no ray count up to 64 reaches the default's RMSE"
            fi
            echo ". One frame's filter has a floor: 64 rays filtered RMSE $f64_rmse against $u64_rmse unfiltered; over"
            echo "  frames it shrinks away: 8 rays × 16 frames filtered $af_rmse against $au_rmse unfiltered ($(ao_ratio "$au_ms" "$d_ms")× the default's time)."
        done
        echo
        echo "**Defaults (8 rays per hit, filter 5): kept.** Per scene,"
        echo "from the table:"
        for scene in $ao_scenes; do
            report_row ao "$scene" n8-f5-x1
            d_flip=$FLIP d_rmse=$RMSE
            report_row ao "$scene" n8-f1-x1
            o_flip=$FLIP o_rmse=$RMSE
            report_knee ao "$scene" flip $(for n in $AO_RAY_COUNTS; do printf 'n%s-f5-x1 ' "$n"; done)
            kf=${KNEE%%-*}
            report_knee ao "$scene" rmse $(for n in $AO_RAY_COUNTS; do printf 'n%s-f5-x1 ' "$n"; done)
            kr=${KNEE%%-*}
            if awk -v a="$d_flip" -v b="$o_flip" -v c="$d_rmse" -v d="$o_rmse" 'BEGIN { exit !(a < b && c < d) }'; then
                verdict="the filter lowers both mean FLIP and RMSE at 8 rays"
            elif awk -v c="$d_rmse" -v d="$o_rmse" 'BEGIN { exit !(c < d) }'; then
                verdict="the filter lowers RMSE at 8 rays but raises mean FLIP"
            else
                verdict="the filter does not lower the 8-ray error"
            fi
            if [ "$kf" = n8 ] && [ "$kr" = n8 ]; then
                knee_text="8 rays is the knee of the filtered series for both metrics"
            else
                knee_text="the knee of the filtered series is ${kf#n} rays for FLIP, ${kr#n} for RMSE (the default: 8)"
            fi
            echo "- $scene: $verdict; $knee_text."
        done
        echo
        echo "More rays with the filter on buy little past the knee: what is left is the filter's own error"
        echo "(it averages the AO term over neighbours that pass its tests), the floor in the bullets above."
        echo "Accumulated frames do not stay on that floor: the filter shrinks one ring each time the frames"
        echo "averaged quadruple (frame 0 the whole 5 × 5 box, frames 1-3 3 × 3, from frame 4 none;"
        echo "engine/render/render_ao.h, render_ao_filter_edge), so a still camera refining over frames converges to"
        echo "the reference with the filter on as without it (compare the two 8 × 16 points), while its first"
        echo "frames keep the filter's smoothness. So 8 rays with the filter serve both the moving frames and"
        echo "the start of a refinement. *(This reading is written in tools/report/knob_ao.sh; the per-scene"
        echo "clauses are computed from the table.)*"
    } > "$out"
    cp "$WORK/ao.tsv" "$WORK/plots/ao.tsv"
}
