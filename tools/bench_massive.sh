#!/bin/sh
# bench_massive.sh - one mesh of 100 M triangles: load, build, peak memory and
# frame rate of tessera against Embree; rewrites the "## Massive models"
# section of BENCHMARKS.md. `make bench-massive` (not part of `make bench`).
#
# Cases (data in $TESSERA_BENCH_DATA, default $TMPDIR/tessera-massive, made
# once and reused while the generator's sources, the command and the file
# sizes are the same: a .key file beside each):
#   fuselage: build/gen-assembly --parts P --triangles T, written both as the
#             .glb (parts and instances) and flattened by the generator itself
#             (--ply: every placed triangle in one binary PLY mesh)
#   bunny:    the CT bunny (../shared/data/meshes/ctbunny_iso900_4M.ply)
#             copied onto a C x R grid by build/ply-replicate, C x R the
#             nearest to T / 4.15 M (5 x 5 = 103.8 M triangles at T = 100 M)
#
# Per flat mesh, each its own process under GNU time -v (peak RSS) after a quiet
# second: tessera (first start), Embree (embree_bench, mode M), tessera again
# (second start: when `tessera bench` prints cache fields, e.g. cache=hit, or
# peak_rss_mb, they get a column). For reference: the fuselage's .glb as parts (tessera) and
# instances (embree_parts), and flattened at load time (tessera --flatten:
# assimp bakes it; embree_parts --flatten; the pair only where assimp fits). A run whose estimated peak does not
# fit in MemAvailable is not started: the table says so. A run during which
# other programs used more than 0.05 CPU is repeated, up to
# BENCH_MASSIVE_ATTEMPTS attempts in all.
#
# Environment: BENCH_MASSIVE_TRIANGLES (100000000; 10000000 to develop),
# BENCH_MASSIVE_PARTS (10000), BENCH_MASSIVE_FRAMES (5), BENCH_MASSIVE_ATTEMPTS (2),
# BENCH_MASSIVE_EMBREE_MODE (p16: Embree's best on these meshes), BENCH_MAX_WAIT
# (seconds of waiting for quiet per whole run, 300), TESSERA_BENCH_DATA, TESSERA_SHARED
# (../shared), TMPDIR.
set -eu

cd "$(dirname "$0")/.."
BENCH_NAME=bench_massive
. tools/bench_lib.sh

OUT=BENCHMARKS.md
TMP=${TMPDIR:-/tmp}
SHARED=${TESSERA_SHARED:-../shared}
DATA=${TESSERA_BENCH_DATA:-$TMP/tessera-massive}
TRIANGLES=${BENCH_MASSIVE_TRIANGLES:-100000000}
PARTS=${BENCH_MASSIVE_PARTS:-10000}
FRAMES=${BENCH_MASSIVE_FRAMES:-5}
MAX_ATTEMPTS=${BENCH_MASSIVE_ATTEMPTS:-2}
MODE=${BENCH_MASSIVE_EMBREE_MODE:-p16}
WAIT_BUDGET_S=${BENCH_MAX_WAIT:-300}
SIZE=1920x1080
THREADS=2
NOISE_LIMIT=0.05
GNU_TIME=/usr/bin/time
BUNNY=$SHARED/data/meshes/ctbunny_iso900_4M.ply
GEN=build/gen-assembly
REPLICATE=build/ply-replicate
EMBREE_PARTS=build/embree_parts
# estimated peak resident bytes a triangle, from 10 M-triangle runs (tessera 134,
# embree_bench 131, embree_parts --flatten 135, tessera --flatten through assimp 490-600)
# with a margin; a run is started only when this fits in MemAvailable less 1 GB
EST_TESSERA=150
EST_EMBREE=150
EST_ASSIMP=650

min_s() { echo "$(($1 / 60)) min $(($1 % 60)) s"; }
gb() { awk -v b="$1" 'BEGIN { printf "%.1f", b / 1e9 }'; }

# meta NAME...: the variables as shell assignments, for --summarize
meta() {
    for name in "$@"; do
        value=""
        eval "value=\${$name}"
        printf "%s='%s'\n" "$name" "$(printf '%s' "$value" | sed "s/'/'\\\\''/g")"
    done
}

# measure: make or reuse the data, run every case into $WORK/runs.log, record $WORK/meta
measure() {
    require_whole "BENCH_MASSIVE_TRIANGLES=$TRIANGLES" "BENCH_MASSIVE_PARTS=$PARTS" "BENCH_MASSIVE_FRAMES=$FRAMES" \
        "BENCH_MASSIVE_ATTEMPTS=$MAX_ATTEMPTS" "BENCH_MAX_WAIT=$WAIT_BUDGET_S"
    case $MODE in single | p4 | p8 | p16) ;; *)
        echo "$BENCH_NAME: BENCH_MASSIVE_EMBREE_MODE must be single, p4, p8 or p16, got '$MODE'" >&2
        exit 2
        ;;
    esac
    require_tessera_and_peer "$SHARED/tools/peer"
    for f in "$GEN" "$REPLICATE" "$EMBREE_PARTS"; do
        if [ ! -x "$f" ]; then
            echo "$BENCH_NAME: $f not found; build it first (make bench-massive builds tessera, $GEN, $REPLICATE" \
                "and $EMBREE_PARTS)" >&2
            exit 1
        fi
    done
    if ! "$GNU_TIME" -v true > /dev/null 2>&1; then
        echo "$BENCH_NAME: GNU time ($GNU_TIME -v) is missing: sh tools/deps.sh --bench installs it" >&2
        exit 1
    fi
    if [ ! -f "$BUNNY" ]; then
        echo "$BENCH_NAME: the CT bunny is missing ($BUNNY; TESSERA_SHARED sets ../shared)" >&2
        exit 1
    fi

    mkdir -p "$DATA"
    WORK=$(mktemp -d "$TMP/tessera-bench-massive.XXXXXX")
    LOG=$WORK/runs.log
    STEPS=$WORK/steps.tsv
    : > "$LOG"
    : > "$STEPS"
    # the structure cache (docs/scenes.md "Structure cache") starts empty: the first start builds and writes it,
    # the second maps it; removed at the end (several GB)
    TESSERA_CACHE_DIR=$WORK/cache
    export TESSERA_CACHE_DIR
    unset TESSERA_CACHE
    cp ./tessera "$WORK/tessera"
    cp "$EMBREE_PARTS" "$WORK/embree_parts"
    TESSERA=$WORK/tessera
    EPARTS=$WORK/embree_parts
    start_s=$(date +%s)
    LOAD_AT_START=$(uptime | sed 's/.*load average: /load average /')
    RUN_MS=0

    mem_avail_kb() { awk '/^MemAvailable:/ { print $2 }' /proc/meminfo; }
    # step NAME MS: one line of the step timings
    step() { printf '%s\t%s\n' "$1" "$2" >> "$STEPS"; }

    # the Embree harness, built in this run's directory
    t0=$(now_ms)
    if ! build_peer "$WORK/peer" "$SHARED/tools/peer" "$WORK/peer_build.log"; then
        echo "$BENCH_NAME: building the Embree harness failed:" >&2
        cat "$WORK/peer_build.log" >&2
        exit 1
    fi
    EMBREE=$WORK/peer/embree_bench
    step "build the Embree harness" $(($(now_ms) - t0))

    # ---- the data, made once
    # made_before KEYFILE KEY FILE...: the files exist with the sizes KEYFILE recorded for KEY
    made_before() {
        mb_keyfile=$1 mb_key=$2
        shift 2
        [ -f "$mb_keyfile" ] || return 1
        [ "$(sed -n 1p "$mb_keyfile")" = "$mb_key" ] || return 1
        mb_sizes=""
        for mb_f in "$@"; do
            [ -f "$mb_f" ] || return 1
            mb_sizes="$mb_sizes $(wc -c < "$mb_f")"
        done
        [ "$(sed -n 2p "$mb_keyfile")" = "$mb_sizes" ]
    }
    # remember KEYFILE KEY FILE...: record KEY and the sizes for made_before
    remember() {
        rm_keyfile=$1 rm_key=$2
        shift 2
        rm_sizes=""
        for rm_f in "$@"; do
            rm_sizes="$rm_sizes $(wc -c < "$rm_f")"
        done
        printf '%s\n%s\n' "$rm_key" "$rm_sizes" > "$rm_keyfile"
    }
    src_hash() { cat "$@" | sha256sum | cut -c1-16; }
    # room BYTES: is there that much free disk in $DATA?
    room() {
        free_kb=$(df -Pk "$DATA" | awk 'NR == 2 { print $4 }')
        if [ $(($1 / 1024 + 1048576)) -gt "$free_kb" ]; then
            echo "$BENCH_NAME: $DATA has $((free_kb / 1048576)) GB free, the data needs about $(gb "$1") GB more" >&2
            exit 1
        fi
    }

    FUS=$DATA/fuselage-p$PARTS-t$TRIANGLES
    FUS_KEY="gen-assembly --parts $PARTS --triangles $TRIANGLES -o .glb --ply .ply $(src_hash tools/gen_assembly/*.[ch])"
    t0=$(now_ms)
    if made_before "$FUS.key" "$FUS_KEY" "$FUS.glb" "$FUS.ply"; then
        echo "$BENCH_NAME: reusing $FUS.glb and $FUS.ply" >&2
        FUS_MADE="reused; first $(sed -n 3p "$FUS.key")"
    else
        rm -f "$FUS.key" "$FUS.glb" "$FUS.ply"
        room $((TRIANGLES * 26))
        echo "$BENCH_NAME: generating $FUS.glb and .ply" >&2
        if ! "$GNU_TIME" -f 'gen_peak_rss_kb=%M' "$GEN" --parts "$PARTS" --triangles "$TRIANGLES" -o "$FUS.glb" \
            --ply "$FUS.ply" > "$FUS.gen" 2> "$WORK/gen.err"; then
            cat "$WORK/gen.err" >&2
            exit 1
        fi
        remember "$FUS.key" "$FUS_KEY" "$FUS.glb" "$FUS.ply"
        FUS_MADE="made in $(awk -v ms=$(($(now_ms) - t0)) 'BEGIN { printf "%.1f", ms / 1000 }') s, peak RSS $(($(sed -n 's/^gen_peak_rss_kb=//p' "$WORK/gen.err") / 1024)) MB"
        echo "$FUS_MADE" >> "$FUS.key"
    fi
    step "gen-assembly: the fuselage .glb and its flattened .ply" $(($(now_ms) - t0))
    FUS_TRIS=$(sed -n 's/.*flattened.* triangles=\([0-9]*\).*/\1/p' "$FUS.gen")

    # the bunny: copies = round(T / its triangles), on the squarest grid holding them
    BUNNY_TRIS=$(sed -n 's/^element face \([0-9]*\).*/\1/p' "$BUNNY" | head -n 1)
    copies=$(((TRIANGLES + BUNNY_TRIS / 2) / BUNNY_TRIS))
    [ "$copies" -lt 1 ] && copies=1
    cols=$(awk -v n="$copies" 'BEGIN { c = int(sqrt(n)); if (c * c < n) c++; print c }')
    rows=$(((copies + cols - 1) / cols))
    BUN=$DATA/ctbunny-$cols"x"$rows
    BUN_KEY="ply-replicate --grid ${cols}x$rows $(wc -c < "$BUNNY") $(src_hash tools/ply_replicate/*.c)"
    t0=$(now_ms)
    if made_before "$BUN.key" "$BUN_KEY" "$BUN.ply"; then
        echo "$BENCH_NAME: reusing $BUN.ply" >&2
        BUN_MADE="reused; first $(sed -n 3p "$BUN.key")"
    else
        rm -f "$BUN.key" "$BUN.ply"
        room $((BUNNY_TRIS * cols * rows * 20))
        echo "$BENCH_NAME: replicating the CT bunny ${cols}x$rows into $BUN.ply" >&2
        if ! "$GNU_TIME" -f 'rep_peak_rss_kb=%M' "$REPLICATE" --grid "${cols}x$rows" -o "$BUN.ply" "$BUNNY" \
            > "$BUN.gen" 2> "$WORK/rep.err"; then
            cat "$WORK/rep.err" >&2
            exit 1
        fi
        remember "$BUN.key" "$BUN_KEY" "$BUN.ply"
        BUN_MADE="made in $(awk -v ms=$(($(now_ms) - t0)) 'BEGIN { printf "%.1f", ms / 1000 }') s, peak RSS $(($(sed -n 's/^rep_peak_rss_kb=//p' "$WORK/rep.err") / 1024)) MB"
        echo "$BUN_MADE" >> "$BUN.key"
    fi
    step "ply-replicate: the CT bunny ${cols}x$rows" $(($(now_ms) - t0))
    BUN_TRIS=$(sed -n 's/.* triangles=\([0-9]*\).*/\1/p' "$BUN.gen")

    # ---- the runs
    # fits EST_BYTES_PER_TRI TRIANGLES: the estimate fits in MemAvailable less 1 GB; else FIT_NOTE says why
    fits() {
        need_kb=$(($2 * $1 / 1024))
        avail_kb=$(mem_avail_kb)
        FIT_NOTE="does not fit: needs about $(gb $((need_kb * 1024))) GB ($1 B a triangle), MemAvailable was $(gb $((avail_kb * 1024))) GB"
        [ $((need_kb + 1048576)) -le "$avail_kb" ]
    }

    # run ROW PROGRAM COMMAND...: one measurement under GNU time, repeated while noisy.
    # PROGRAM: tessera, embree_bench or embree_parts. Log (tabs): row, clean|noisy, wall ms,
    # peak RSS KB, camera, the result line (with load_s, mem_mib, hits added for embree_bench).
    run() {
        run_row=$1 run_prog=$2
        shift 2
        attempt=1
        while :; do
            wait_quiet
            r0=$(now_ms)
            if ! "$GNU_TIME" -v "$@" > "$WORK/run.out" 2> "$WORK/run.err"; then
                echo "$BENCH_NAME: this command failed:" >&2
                echo "  $*" >&2
                tail -n 40 "$WORK/run.err" >&2
                exit 1
            fi
            ms=$(($(now_ms) - r0))
            RUN_MS=$((RUN_MS + ms))
            rss=$(sed -n 's/^[[:space:]]*Maximum resident set size (kbytes): *//p' "$WORK/run.err")
            case $run_prog in
            tessera)
                line=$(grep '^BENCH ' "$WORK/run.out" | tail -n 1)
                cam=$(sed -n 's/^tessera: camera //p' "$WORK/run.err")
                ;;
            embree_bench)
                line="$(grep '^RESULT ' "$WORK/run.out" | tail -n 1)"
                line="$line load_s=$(sed -n 's/^triangles .* load \([0-9.]*\) s.*/\1/p' "$WORK/run.out")"
                line="$line mem_mib=$(sed -n 's/^build .* embree mem \([0-9.]*\) MiB.*/\1/p' "$WORK/run.out")"
                line="$line hits=$(sed -n 's/^checksum *hits \([0-9]*\).*/\1/p' "$WORK/run.out")"
                cam=$(sed -n 's/^camera *//p' "$WORK/run.out")
                ;;
            *)
                line=$(grep '^RESULT ' "$WORK/run.out" | tail -n 1)
                cam=$(sed -n 's/^camera //p' "$WORK/run.out")
                ;;
            esac
            other=$(kv "$line" cpu_other)
            [ -z "$other" ] && other=0
            if awk -v o="$other" -v lim="$NOISE_LIMIT" 'BEGIN { exit !(o >= 0 && o <= lim) }'; then
                status=clean
            else
                status=noisy
            fi
            printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$run_row" "$status" "$ms" "${rss:-0}" "$cam" "$line" >> "$LOG"
            step "$run_row (attempt $attempt, $status)" "$ms"
            echo "$BENCH_NAME: $run_row: $((ms / 1000)) s, peak RSS $((${rss:-0} / 1024)) MB, $status (cpu_other $other)" >&2
            [ "$status" = clean ] && return 0
            [ "$attempt" -ge "$MAX_ATTEMPTS" ] && return 0
            attempt=$((attempt + 1))
        done
    }
    # skip ROW NOTE: a run not started
    skip() {
        printf '%s\tskipped\t0\t0\t-\t%s\n' "$1" "$2" >> "$LOG"
        echo "$BENCH_NAME: $1: $2" >&2
    }

    tbench() { # ROW FILE [--flatten]: tessera bench on FILE
        tb_row=$1 tb_file=$2
        shift 2
        run "$tb_row" tessera "$TESSERA" bench --scene "$tb_file" "$@" --size $SIZE --threads $THREADS --frames "$FRAMES"
    }
    flat_case() { # NAME FILE TRIANGLES: tessera, Embree, tessera again
        if fits $EST_TESSERA "$3"; then tbench "$1|tessera|first start" "$2"; else skip "$1|tessera|first start" "$FIT_NOTE"; fi
        if fits $EST_EMBREE "$3"; then
            run "$1|Embree (embree_bench $MODE)|-" embree_bench "$EMBREE" -r $SIZE -t $THREADS -f "$FRAMES" -m "$MODE" "$2"
        else
            skip "$1|Embree (embree_bench $MODE)|-" "$FIT_NOTE"
        fi
        if fits $EST_TESSERA "$3"; then tbench "$1|tessera|second start" "$2"; else skip "$1|tessera|second start" "$FIT_NOTE"; fi
        # cold: the page cache dropped first (as root: sync + drop_caches, all of it; else GNU dd's
        # nocache, posix_fadvise DONTNEED, over the model and its cache), so both come from the disk
        # (in a VM the host may still cache the disk: the cold figure is then the host's speed)
        if fits $EST_TESSERA "$3"; then
            sync
            if ! { echo 1 > /proc/sys/vm/drop_caches; } 2> /dev/null; then
                for ev_f in "$2" "$TESSERA_CACHE_DIR"/*.tcache; do
                    [ -f "$ev_f" ] && dd if="$ev_f" iflag=nocache count=0 status=none 2> /dev/null || true
                done
            fi
            tbench "$1|tessera|second start, cold" "$2"
        else
            skip "$1|tessera|second start, cold" "$FIT_NOTE"
        fi
    }
    flat_case "fuselage, flattened by gen-assembly (.ply)" "$FUS.ply" "$FUS_TRIS"
    flat_case "CT bunny ${cols}x$rows (.ply)" "$BUN.ply" "$BUN_TRIS"
    rm -rf "$TESSERA_CACHE_DIR" # several GB; the runs below read no mesh file of 16 MiB or more
    # references: the same fuselage as parts and instances, and flattened while loading
    g="fuselage (.glb)"
    tbench "$g|tessera, parts and instances|-" "$FUS.glb"
    run "$g|Embree (embree_parts $MODE), instances|-" embree_parts "$EPARTS" -r $SIZE -t $THREADS -f "$FRAMES" -m "$MODE" \
        "$FUS.glb"
    # the pair runs where assimp's flattening fits; elsewhere the .ply rows have Embree on the same triangles
    g="fuselage (.glb, flattened while loading)"
    if fits $EST_ASSIMP "$FUS_TRIS"; then
        tbench "$g|tessera --flatten (assimp)|-" "$FUS.glb" --flatten
        run "$g|Embree (embree_parts $MODE) --flatten|-" embree_parts "$EPARTS" -r $SIZE -t $THREADS -f "$FRAMES" \
            -m "$MODE" --flatten "$FUS.glb"
    else
        skip "$g|tessera --flatten (assimp)|-" "$FIT_NOTE"
        skip "$g|Embree (embree_parts $MODE) --flatten|-" "not run without its tessera pair: Embree on the same triangles is the .ply's row"
    fi
    total_s=$(($(date +%s) - start_s))

    revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
    git diff --quiet HEAD -- engine tools 2>/dev/null || revision="$revision (plus uncommitted changes)"
    cpu_model=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
    embree_version=$(dpkg-query -W -f='${Version}' libembree-dev 2>/dev/null || echo unknown)
    mem_total=$(awk '/^MemTotal:/ { printf "%.1f", $2 / 1048576 }' /proc/meminfo)
    run_date=$(date -u '+%Y-%m-%d %H:%M UTC')
    cpus=$(nproc)
    cp "$FUS.gen" "$WORK/fuselage.gen"
    cp "$BUN.gen" "$WORK/bunny.gen"
    meta EST_TESSERA EST_EMBREE EST_ASSIMP TRIANGLES PARTS FRAMES MODE MAX_ATTEMPTS NOISE_LIMIT SIZE THREADS DATA BUNNY cols rows FUS_MADE BUN_MADE total_s RUN_MS LOAD_AT_START \
        revision cpu_model embree_version mem_total run_date cpus > "$WORK/meta"
}

if [ "${1:-}" = --summarize ]; then
    if [ ! -f "${2:-}/meta" ] || [ ! -f "${2:-}/runs.log" ]; then
        echo "$BENCH_NAME: --summarize needs the directory of an earlier run (with meta and runs.log)" >&2
        exit 2
    fi
    WORK=$2
elif [ $# -gt 0 ]; then
    echo "$BENCH_NAME: unknown argument '$1' (usage: sh tools/bench_massive.sh [--summarize DIR])" >&2
    exit 2
else
    measure
fi
LOG=$WORK/runs.log
STEPS=$WORK/steps.tsv
# shellcheck disable=SC1091 # written by measure
. "$WORK/meta"

# ---- the section
isa=$(grep -o ' isa=[a-z0-9]*' "$LOG" | head -n 1 | sed 's/ isa=//')
# fields tessera bench may print: a BVH cache's (cache=hit|miss, cache_s=...) and its own peak_rss_mb;
# each gets a column when some run printed it
cache_keys=$(grep -o ' \(cache[a-z_]*\|peak_rss_mb\)=' "$LOG" | sort -u | tr -d ' =' | tr '\n' ' ')
# the last attempt of each row
awk -F '\t' '{ last[$1] = $0; if (!($1 in seen)) { seen[$1] = 1; order[++n] = $1 } }
    END { for (i = 1; i <= n; i++) print last[order[i]] }' "$LOG" > "$WORK/rows.tsv"

{
    echo "## Massive models"
    echo
    echo "\`sh tools/bench_massive.sh\` (\`make bench-massive\`; not part of \`make bench\`) at revision $revision,"
    echo "$run_date; $cpus CPUs, ${cpu_model:-unknown CPU} (lscpu), $mem_total GiB of"
    echo "memory (shared: other programs ran beside it); tessera kernels ISA ${isa:-?}; Embree $embree_version (Debian"
    echo "libembree-dev), build quality high, mode $MODE. Scale: BENCH_MASSIVE_TRIANGLES=$TRIANGLES. $FRAMES timed"
    echo "frames (+1 warm-up) a run, $SIZE, $THREADS threads, primary rays, eyelight shading. The run took"
    echo "$(min_s "$total_s"), $(min_s $((RUN_MS / 1000))) of it in the measured programs; load when it began:"
    echo "$LOAD_AT_START."
    echo
    echo "The meshes (in \`$DATA\`, made once and reused):"
    echo
    echo "- fuselage: \`build/gen-assembly --parts $PARTS --triangles $TRIANGLES -o F.glb --ply F.ply\`"
    echo "  ($FUS_MADE): \`$(sed 's/ file=.*//' "$WORK/fuselage.gen" | tr '\n' ';' | sed 's/;$//; s/;/`; `/g')\`. The .ply is the"
    echo "  assembly flattened by the generator: every placed triangle, node transforms baked in, one mesh."
    echo "- CT bunny: \`build/ply-replicate --grid ${cols}x$rows -o B.ply $BUNNY\` ($BUN_MADE):"
    echo "  \`$(sed 's/ file=.*//' "$WORK/bunny.gen")\`."
    echo
    echo '```sh'
    echo "/usr/bin/time -v ./tessera bench --scene FILE [--flatten] --size $SIZE --threads $THREADS --frames $FRAMES"
    echo "/usr/bin/time -v embree_bench -r $SIZE -t $THREADS -f $FRAMES -m $MODE FILE.ply      # ../shared/tools/peer"
    echo "/usr/bin/time -v build/embree_parts -r $SIZE -t $THREADS -f $FRAMES -m $MODE [--flatten] F.glb"
    echo '```'
    echo
    echo "Load s: tessera \`load_s\` (the file into the mesh: its own PLY reader, or assimp for --flatten);"
    echo "embree_bench: its loader; embree_parts: the assembly (its flat copy is baked after). Build s:"
    echo "\`build_s\` / Embree's \`rtcCommitScene\`. Held B/tri: tessera = (mesh + accel bytes) / triangles (the two"
    echo "in brackets);"
    echo "Embree = its memory monitor after the build / triangles (embree_bench frees its loader's copy before"
    echo "the build). Peak RSS: GNU time's maximum resident set size of the whole process (load, build"
    echo "and frames). Mrays/s: tessera's \`prim_mrays\` (median of per-frame rates); Embree's W x H /"
    echo "\`median_ms\`. Every program frames the mesh itself by the same rule; hits: primary hits of the last frame."
    echo "A run starts only when its estimated peak fits in MemAvailable less 1 GB: tessera $EST_TESSERA, Embree"
    echo "$EST_EMBREE and assimp's flattening (tessera --flatten) $EST_ASSIMP bytes a triangle, from 10 M-triangle runs"
    echo "(peak RSS 125-138, 123-135 and 490-600 B/tri) with a margin."
    echo
    printf '| mesh | program | start | triangles | load s | build s | held B/tri | peak RSS GB | peak RSS B/tri | Mrays/s | hits | camera as tessera'"'"'s | cpu_other |'
    for k in $cache_keys; do printf ' %s |' "$k"; done
    echo
    printf '|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|'
    for k in $cache_keys; do printf -- '---|'; done
    echo
    while IFS="$(printf '\t')" read -r row status ms rss cam line; do
        mesh=${row%%|*} rest=${row#*|}
        prog=${rest%%|*} start=${rest#*|}
        if [ "$status" = skipped ]; then
            printf '| %s | %s | %s | - | %s | | | | | | | | |' "$mesh" "$prog" "$start" "$line"
            for k in $cache_keys; do printf ' |'; done
            echo
            continue
        fi
        case $prog in
        tessera*)
            tris=$(kv "$line" triangles_instanced)
            held=$(awk -v m="$(kv "$line" mesh_bytes)" -v a="$(kv "$line" accel_bytes)" -v t="$tris" \
                'BEGIN { if (t > 0) printf "%.1f (%.1f + %.1f)", (m + a) / t, m / t, a / t }')
            rate=$(kv "$line" prim_mrays)
            ;;
        *)
            tris=$(kv "$line" tris)
            held=$(awk -v m="$(kv "$line" mem_mib)" -v t="$tris" 'BEGIN { printf "%.1f", (t > 0 ? m * 1048576 / t : 0) }')
            res=$(kv "$line" res)
            rate=$(awk -v w="${res%x*}" -v h="${res#*x}" -v ms="$(kv "$line" median_ms)" \
                'BEGIN { printf "%.3f", (ms > 0 ? w * h / (ms * 1000) : 0) }')
            ;;
        esac
        # the camera: tessera's first run on this mesh is the reference
        same=-
        case $prog/$start in
        tessera*/"first start" | tessera*/-)
            ref_cam=$cam ref_mesh=$mesh same="(the reference)"
            ;;
        *)
            if [ "$mesh" = "${ref_mesh:-}" ]; then
                same=no
                [ "$cam" = "$ref_cam" ] && same=yes
            fi
            ;;
        esac
        printf '| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s%s |' "$mesh" "$prog" "$start" \
            "$tris" "$(kv "$line" load_s)" "$(kv "$line" build_s)" "$held" "$(gb $((rss * 1024)))" \
            "$(awk -v r="$rss" -v t="$tris" 'BEGIN { printf "%.0f", (t > 0 ? r * 1024 / t : 0) }')" "$rate" \
            "$(kv "$line" hits)" "$same" "$(kv "$line" cpu_other)" "$([ "$status" = noisy ] && echo ' (noisy)')"
        for k in $cache_keys; do printf ' %s |' "$(kv "$line" "$k")"; done
        echo
    done < "$WORK/rows.tsv"
    echo
    awk -F '\t' -v lim="$NOISE_LIMIT" '$2 != "skipped" { n++; if ($2 == "noisy") noisy++ }
        END { if (n) printf "Noise: %d of %d runs were noisy (other programs used more than %s CPU of the %s during the timed frames, column cpu_other; repeated up to BENCH_MASSIVE_ATTEMPTS=%s attempts in all): their Mrays/s and build s are what a shared machine gave, not what the programs can do.\n", noisy, n, lim, cpus, attempts }' \
        cpus="$cpus" attempts="$MAX_ATTEMPTS" "$WORK/rows.tsv"
    echo
    case " $cache_keys" in
    *" cache"*) ;;
    *) echo "\`tessera bench\` printed no BVH cache field: the second start loads and builds again, as the first." ;;
    esac
    echo
    echo "Step timings (wall clock, each run including its load and build):"
    echo
    echo "| step | s |"
    echo "|---|---:|"
    while IFS="$(printf '\t')" read -r name ms; do
        echo "| $(echo "$name" | tr '|' ' ') | $(awk -v m="$ms" 'BEGIN { printf "%.1f", m / 1000 }') |"
    done < "$STEPS"
    echo
    echo "The raw lines: \`$LOG\` (not kept in the repository)."
    echo
} > "$WORK/section.md"
cat "$WORK/section.md"

# into BENCHMARKS.md: in place of the old section, else before "## The pipeline" (which stays last)
replace_section "$OUT" "## Massive models" "$WORK/section.md" "$WORK/BENCHMARKS.md"
echo "$BENCH_NAME: wrote the massive-models section of $OUT ($(min_s "$total_s"))" >&2
