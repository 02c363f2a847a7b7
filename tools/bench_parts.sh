#!/bin/sh
# bench_parts.sh - parts and instances against the same triangles flattened,
# tessera against Embree's two-level scene (tools/embree_parts); rewrites the
# "## Parts and instances" section of BENCHMARKS.md. `make bench` runs it after
# the other bench scripts; `make bench-parts` alone.
#
# Assemblies (build/gen-assembly, into a scratch directory, deleted at the end):
#   a10k:  --parts 10000  --triangles 10000000
#   a100k: --parts 100000 --triangles 50000000  (skipped when MemAvailable is short)
# The flattened representations (tessera bench --flatten: assimp bakes the node
# transforms into one mesh; embree_parts --flatten) only on assemblies whose
# flattened copy fits in memory (about 0.5 KB a placed triangle at the peak
# of assimp's import).
#
# Per assembly, round and thread count (1, 2), each its own process after a
# quiet second, alternating:
#   tessera parts, Embree instances single, tessera flat, Embree flat single,
#   tessera parts, Embree instances p8, Embree flat p8,
#   tessera parts, Embree instances p16, tessera flat, Embree flat p16
# (3 tessera parts and 2 tessera flat runs a round: a flattened load takes
# half a minute). A run during which other programs used more than 0.05 CPU
# is repeated, up to 3 attempts (BENCH_PARTS_ATTEMPTS). Every run uses one camera: tessera bench's
# framing of the parts scene; before the rounds, both programs frame each
# representation by themselves once and the script checks that they chose the
# same camera and that the hit counts agree within 0.1 %.
# Then `tessera bench --part-txns` on each assembly (BENCH_PARTS_TXNS rounds).
#
# BENCH_PARTS_QUICK=1: a smoke run of this script (1,000 and 2,000 parts, 1 round, 2 frames).
# Environment: BENCH_PARTS_ROUNDS (3), BENCH_PARTS_FRAMES (10), BENCH_PARTS_TXNS
# (50), BENCH_PARTS_ATTEMPTS (3), BENCH_MAX_WAIT (seconds of waiting for quiet per whole run, 300), TMPDIR.
set -eu
# build times are measured: the structure cache (docs/scenes.md "Structure cache") stays off
TESSERA_CACHE=off
export TESSERA_CACHE

cd "$(dirname "$0")/.."
OUT=BENCHMARKS.md
TMP=${TMPDIR:-/tmp}
SIZE=1920x1080
THREADS="1 2"
ROUNDS=${BENCH_PARTS_ROUNDS:-3}
FRAMES=${BENCH_PARTS_FRAMES:-10}
TXNS=${BENCH_PARTS_TXNS:-50}
MAX_ATTEMPTS=${BENCH_PARTS_ATTEMPTS:-3}
NOISE_LIMIT=0.05
WAIT_BUDGET_S=${BENCH_MAX_WAIT:-300}
GEN=build/gen-assembly
EMBREE_SRC=build/embree_parts

for v in "BENCH_PARTS_ATTEMPTS=$MAX_ATTEMPTS" "BENCH_PARTS_ROUNDS=$ROUNDS" "BENCH_PARTS_FRAMES=$FRAMES" "BENCH_PARTS_TXNS=$TXNS" "BENCH_MAX_WAIT=$WAIT_BUDGET_S"; do
    case ${v#*=} in
    '' | *[!0-9]*)
        echo "bench_parts: ${v%%=*} must be a whole number, got '${v#*=}'" >&2
        exit 2
        ;;
    esac
done
for f in ./tessera "$GEN" "$EMBREE_SRC"; do
    if [ ! -x "$f" ]; then
        echo "bench_parts: $f not found; build it first (make bench-parts builds tessera, build/gen-assembly" \
            "and build/embree_parts)" >&2
        exit 1
    fi
done

WORK=$(mktemp -d "$TMP/tessera-bench-parts.XXXXXX")
trap 'rm -f "$WORK"/*.glb' EXIT
LOG=$WORK/runs.log
: > "$LOG"
cp ./tessera "$WORK/tessera"
cp "$EMBREE_SRC" "$WORK/embree_parts"
TESSERA=$WORK/tessera
EMBREE=$WORK/embree_parts
start_s=$(date +%s)
LOAD_AT_START=$(uptime | sed 's/.*load average: /load average /')
WAIT_MS=0
RUN_MS=0
WAIT_BUDGET_SPENT=0
QUIET_TICKS=$(($(nproc) * 4 / 100))
[ "$QUIET_TICKS" -lt 4 ] && QUIET_TICKS=4

now_ms() { echo $(($(date +%s%N) / 1000000)); }
min_s() { echo "$(($1 / 60)) min $(($1 % 60)) s"; }
busy_ticks() { awk '/^cpu /{print $2+$3+$4+$7+$8+$9}' /proc/stat; }
kv() { printf '%s\n' "$1" | tr ' \t' '\n\n' | sed -n "s/^$2=//p" | head -n 1; }

# wait_quiet: up to 30 s for a second with < 0.04 CPU used, while the budget lasts
wait_quiet() {
    if [ $((WAIT_MS / 1000)) -ge "$WAIT_BUDGET_S" ]; then
        if [ "$WAIT_BUDGET_SPENT" = 0 ]; then
            echo "bench_parts: $WAIT_BUDGET_S s of waiting for quiet used up; runs start at once from now on" >&2
            WAIT_BUDGET_SPENT=1
        fi
        return 0
    fi
    w0=$(now_ms)
    i=0
    while [ $i -lt 30 ]; do
        qa=$(busy_ticks)
        sleep 1
        qb=$(busy_ticks)
        if [ $((qb - qa)) -le "$QUIET_TICKS" ]; then
            WAIT_MS=$((WAIT_MS + $(now_ms) - w0))
            return 0
        fi
        i=$((i + 1))
    done
    WAIT_MS=$((WAIT_MS + $(now_ms) - w0))
}

# run TAG ENGINE ASM THREADS MODE COMMAND...: one measurement, repeated while noisy.
# Log: tag, clean|noisy, engine, assembly, threads, mode, command, result line (tabs between).
run() {
    run_tag=$1 run_engine=$2 run_asm=$3 run_threads=$4 run_mode=$5
    shift 5
    attempt=1
    while :; do
        wait_quiet
        r0=$(now_ms)
        if ! "$@" > "$WORK/run.out" 2> "$WORK/run.err"; then
            echo "bench_parts: this command failed:" >&2
            echo "  $*" >&2
            cat "$WORK/run.err" >&2
            exit 1
        fi
        line=$(grep -E '^(BENCH|RESULT|PARTTXN) ' "$WORK/run.out" | tail -n 1)
        other=$(kv "$line" cpu_other)
        [ -z "$other" ] && other=0
        if awk -v o="$other" -v lim="$NOISE_LIMIT" 'BEGIN { exit !(o >= 0 && o <= lim) }'; then
            status=clean
        else
            status=noisy
        fi
        RUN_MS=$((RUN_MS + $(now_ms) - r0))
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$run_tag" "$status" "$run_engine" "$run_asm" "$run_threads" \
            "$run_mode" "$*" "$line" >> "$LOG"
        printf 'bench_parts: %-7s %-13s %-6s %sT %-6s %s (cpu_other %s)\n' "$run_tag" "$run_engine" "$run_asm" \
            "$run_threads" "$run_mode" "$status" "$other" >&2
        [ "$status" = clean ] && return 0
        [ "$attempt" -ge "$MAX_ATTEMPTS" ] && return 0
        attempt=$((attempt + 1))
    done
}

# ---- the assemblies
mem_kb=$(awk '/^MemAvailable:/ { print $2 }' /proc/meminfo)
ASMS=""
NOTES=""
gen() { # NAME PARTS TRIANGLES
    "$GEN" --parts "$2" --triangles "$3" -o "$WORK/$1.glb" > "$WORK/$1.gen" 2>&1 || {
        cat "$WORK/$1.gen" >&2
        exit 1
    }
    ASMS="$ASMS $1"
    echo "bench_parts: $(cat "$WORK/$1.gen")" >&2
}
if [ "${BENCH_PARTS_QUICK:-0}" = 1 ]; then # smoke run of this script: small assemblies, 1 round, 2 frames
    ROUNDS=1 FRAMES=2 TXNS=5
    gen a1k 1000 1000000
    gen a2k 2000 2000000
else
    gen a10k 10000 10000000
    # the 100k assembly as parts needs about 2 GB (both programs); flattened, 50 M triangles ~25 GB
    if [ "${mem_kb:-0}" -ge 4000000 ]; then
        gen a100k 100000 50000000
    else
        NOTES="$NOTES
- The 100,000-part assembly was skipped: MemAvailable was $((mem_kb / 1024)) MB (< 4 GB)."
    fi
fi
flat_ok() { # ASM: does a flattened copy fit? (placed triangles x 500 bytes < MemAvailable)
    tri=$(sed -n 's/.*triangles_instanced=\([0-9]*\).*/\1/p' "$WORK/$1.gen")
    [ $((tri / 1000 * 500)) -lt "${mem_kb:-0}" ]
}

# ---- the camera: tessera's framing of the parts scene, checked against embree_parts'
for a in $ASMS; do
    for rep in parts flat; do
        [ $rep = flat ] && ! flat_ok "$a" && continue
        fl=""
        [ $rep = flat ] && fl=--flatten
        "$TESSERA" bench --scene "$WORK/$a.glb" --size $SIZE --threads 2 --frames 1 --warmup 0 $fl \
            > "$WORK/cam_t.out" 2> "$WORK/cam_t.err"
        "$EMBREE" -r $SIZE -t 2 -f 1 --warmup 0 -m p16 $fl "$WORK/$a.glb" > "$WORK/cam_e.out" 2> "$WORK/cam_e.err"
        cam_t=$(sed -n 's/^tessera: camera //p' "$WORK/cam_t.err")
        cam_e=$(sed -n 's/^camera //p' "$WORK/cam_e.out")
        hits_t=$(kv "$(grep '^BENCH ' "$WORK/cam_t.out")" hits)
        hits_e=$(kv "$(grep '^RESULT ' "$WORK/cam_e.out")" hits)
        same=no
        [ "$cam_t" = "$cam_e" ] && same=yes
        printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$a" "$rep" "$same" "$hits_t" "$hits_e" "$cam_t" >> "$WORK/cameras.tsv"
        echo "bench_parts: $a $rep: tessera camera $cam_t; embree_parts the same: $same; hits $hits_t / $hits_e" >&2
        if [ $rep = parts ]; then
            printf '%s\n' "$cam_t" | sed 's/--eye //; s/ --lookat /,/; s/ --up /,/; s/ --fov /,/' > "$WORK/$a.cam"
        fi
    done
done

# ---- the rounds
for r in $(seq 1 "$ROUNDS"); do
    for a in $ASMS; do
        cam=$(cat "$WORK/$a.cam")
        g=$WORK/$a.glb
        for t in $THREADS; do
            tp() { run primary tessera-parts "$a" "$t" - "$TESSERA" bench --scene "$g" --size $SIZE --threads "$t" \
                --frames "$FRAMES" --camera "$cam"; }
            tf() { flat_ok "$a" && run primary tessera-flat "$a" "$t" - "$TESSERA" bench --scene "$g" --flatten \
                --size $SIZE --threads "$t" --frames "$FRAMES" --camera "$cam"; }
            ep() { run primary embree-parts "$a" "$t" "$1" "$EMBREE" -r $SIZE -t "$t" -f "$FRAMES" -m "$1" \
                --camera "$cam" "$g"; }
            ef() { flat_ok "$a" && run primary embree-flat "$a" "$t" "$1" "$EMBREE" -r $SIZE -t "$t" -f "$FRAMES" \
                -m "$1" --flatten --camera "$cam" "$g"; }
            tp; ep single; tf || true; ef single || true
            tp; ep p8; ef p8 || true
            tp; ep p16; tf || true; ef p16 || true
        done
    done
done

# ---- transactions at the barrier
for a in $ASMS; do
    cam=$(cat "$WORK/$a.cam")
    run txns tessera-txns "$a" 2 - "$TESSERA" bench --scene "$WORK/$a.glb" --size $SIZE --threads 2 \
        --camera "$cam" --part-txns "$TXNS"
done
total_s=$(($(date +%s) - start_s))

# ---- the section
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
git diff --quiet HEAD -- engine tools wall input metrics 2>/dev/null || revision="$revision (plus uncommitted changes)"
cpu_model=$(lscpu 2>/dev/null | sed -n 's/^Model name: *//p' | head -n 1)
embree_version=$(dpkg-query -W -f='${Version}' libembree-dev 2>/dev/null || echo unknown)
isa=$(awk -F '\t' '$3 == "tessera-parts" { print $8; exit }' "$LOG" | tr ' ' '\n' | sed -n 's/^isa=//p')

awk -F '\t' -v out_tables="$WORK/tables.md" -v max_attempts="$MAX_ATTEMPTS" '
function kv(line, key,    n, i, f) {
    n = split(line, f, " ")
    for (i = 1; i <= n; i++) if (index(f[i], key "=") == 1) return substr(f[i], length(key) + 2)
    return ""
}
function sort(a, n,    i, j, x) { for (i = 2; i <= n; i++) { x = a[i]; for (j = i - 1; j >= 1 && a[j] > x; j--) a[j + 1] = a[j]; a[j + 1] = x } }
function median(a, n) { sort(a, n); return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2 }
function add(key, v) { cnt[key]++; val[key, cnt[key]] = v }
function med(key,    i, tmp, n) { n = cnt[key]; if (!n) return ""; for (i = 1; i <= n; i++) tmp[i] = val[key, i]; return median(tmp, n) }
function mx(key,    i, m) { m = ""; for (i = 1; i <= cnt[key]; i++) if (m == "" || val[key, i] + 0 > m + 0) m = val[key, i]; return m }
function mn(key,    i, m) { m = ""; for (i = 1; i <= cnt[key]; i++) if (m == "" || val[key, i] + 0 < m + 0) m = val[key, i]; return m }
function spread(key,    m) { m = med(key); return m > 0 ? sprintf("%.0f%%", 100 * (mx(key) - mn(key)) / m) : "-" }
function rate(e, line,    res, ms) {
    if (e ~ /^tessera/) return kv(line, "prim_mrays")
    res = kv(line, "res"); split(res, wh, "x"); ms = kv(line, "median_ms")
    return ms > 0 ? wh[1] * wh[2] / (ms * 1000) : 0
}
{
    tag = $1; status = $2; e = $3; a = $4; t = $5; m = $6; line = $8
    if (!(a in seen_asm)) { seen_asm[a] = 1; asms[++nasm] = a }
    attempts++; if (status == "noisy") noisy++
    add("other", kv(line, "cpu_other"))
    if (tag == "txns") { txn[a] = line; next }
    # clean runs only, unless a configuration has none (then its noisy ones)
    k = e SUBSEP a SUBSEP t SUBSEP m
    if (status == "clean") { clean[k] = 1; add("c" SUBSEP k, rate(e, line)) } else add("n" SUBSEP k, rate(e, line))
    last[k] = line
    add("hits" SUBSEP e SUBSEP a, kv(line, "hits"))
    if (e ~ /^tessera/) {
        add("load" SUBSEP e SUBSEP a, kv(line, "load_s")); add("build" SUBSEP e SUBSEP a SUBSEP t, kv(line, "build_s"))
    } else {
        add("build" SUBSEP e SUBSEP a SUBSEP t, kv(line, "build_s")); add("eload" SUBSEP e SUBSEP a, kv(line, "load_s"))
    }
}
function r(e, a, t, m,    k) { k = e SUBSEP a SUBSEP t SUBSEP m; return (k in clean) ? "c" SUBSEP k : "n" SUBSEP k }
function fmt(key) { return cnt[key] ? sprintf("%.2f (%s, n=%d)", med(key), spread(key), cnt[key]) : "-" }
function best(e, a, t,    j, mode, b, bm, v) {
    b = ""; split("single p8 p16", modes, " ")
    for (j = 1; j <= 3; j++) { v = med(r(e, a, t, modes[j])); if (v != "" && (b == "" || v + 0 > b + 0)) { b = v; bm = modes[j] } }
    best_mode = bm; return b
}
function ratio(x, y) { return (x != "" && y != "" && y > 0) ? sprintf("**%.2f**", x / y) : "-" }
END {
    o = out_tables
    print "### Primary rays: parts and instances against the same triangles flattened" > o
    print "" > o
    print "| assembly | threads | tessera parts Mrays/s | tessera flat | **parts / flat** | Embree instances, best mode | Embree flat, best mode | tessera parts / Embree instances | tessera flat / Embree flat |" > o
    print "|---|---:|---:|---:|---:|---:|---:|---:|---:|" > o
    for (i = 1; i <= nasm; i++) {
        a = asms[i]
        for (t = 1; t <= 2; t++) {
            tp = med(r("tessera-parts", a, t, "-")); tf = med(r("tessera-flat", a, t, "-"))
            if (tp == "") continue
            ep = best("embree-parts", a, t); epm = best_mode; ef = best("embree-flat", a, t); efm = best_mode
            printf "| %s | %d | %s | %s | %s | %s | %s | %s | %s |\n", a, t, fmt(r("tessera-parts", a, t, "-")),
                fmt(r("tessera-flat", a, t, "-")), ratio(tp, tf), ep == "" ? "-" : epm ": " sprintf("%.2f", ep),
                ef == "" ? "-" : efm ": " sprintf("%.2f", ef), ratio(tp, ep), ratio(tf, ef) > o
        }
    }
    print "" > o
    print "### Embree, every mode: primary Mrays/s (median, spread, n)" > o
    print "" > o
    print "| assembly | representation | threads | single | p8 | p16 |" > o
    print "|---|---|---:|---:|---:|---:|" > o
    for (i = 1; i <= nasm; i++) for (q = 1; q <= 2; q++) for (t = 1; t <= 2; t++) {
        e = q == 1 ? "embree-parts" : "embree-flat"
        if (!cnt[r(e, asms[i], t, "single")]) continue
        printf "| %s | %s | %d | %s | %s | %s |\n", asms[i], q == 1 ? "instances" : "flat", t, fmt(r(e, asms[i], t, "single")),
            fmt(r(e, asms[i], t, "p8")), fmt(r(e, asms[i], t, "p16")) > o
    }
    print "" > o
    print "### Load, build and memory" > o
    print "" > o
    print "Load s: tessera = `scene_load` (parts) or `mesh_load` (flat, assimp), median over the runs; Embree = `assembly_load` (its flat copy is baked after). Build s: median over the runs, 1 / 2 threads (Embree: every `rtcCommitScene`, the mesh scenes and the top scene). Bytes: tessera = mesh arrays + accel; Embree = what its memory monitor saw after the build. Per placed (instanced) triangle and per stored triangle." > o
    print "" > o
    print "| assembly | representation | placed triangles | stored triangles | load s: tessera / Embree | build s 1T: tessera / Embree | build s 2T: tessera / Embree | bytes / placed tri: tessera / Embree | bytes / stored tri: tessera / Embree | hits: tessera / Embree |" > o
    print "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|" > o
    for (i = 1; i <= nasm; i++) for (q = 1; q <= 2; q++) {
        a = asms[i]; te = q == 1 ? "tessera-parts" : "tessera-flat"; ee = q == 1 ? "embree-parts" : "embree-flat"
        lt = r(te, a, 1, "-"); if (!cnt[lt]) continue
        tl = last[te SUBSEP a SUBSEP 1 SUBSEP "-"]; el = last[ee SUBSEP a SUBSEP 1 SUBSEP "p16"]
        placed = kv(tl, "triangles_instanced"); stored = q == 1 ? kv(tl, "triangles") : kv(el, "tris_stored")
        tbytes = kv(tl, "mesh_bytes") + kv(tl, "accel_bytes"); ebytes = kv(el, "mem_mib") * 1048576
        printf "| %s | %s | %d | %d | %.3f / %.3f | %.3f / %.3f | %.3f / %.3f | %.2f / %.2f | %.1f / %.1f | %s / %s |\n", a,
            q == 1 ? "parts, instances" : "flat (one mesh)", placed, q == 1 ? stored : placed,
            med("load" SUBSEP te SUBSEP a), med("eload" SUBSEP ee SUBSEP a),
            med("build" SUBSEP te SUBSEP a SUBSEP 1), med("build" SUBSEP ee SUBSEP a SUBSEP 1),
            med("build" SUBSEP te SUBSEP a SUBSEP 2), med("build" SUBSEP ee SUBSEP a SUBSEP 2),
            tbytes / placed, ebytes / placed, tbytes / (q == 1 ? stored : placed), ebytes / (q == 1 ? stored : placed),
            med("hits" SUBSEP te SUBSEP a), med("hits" SUBSEP ee SUBSEP a) > o
    }
    print "" > o
    print "### Part transactions at the barrier (microseconds)" > o
    print "" > o
    print "`txn_apply` on a frame state + `frame_state_sync_accel` (which refits or commits), one record at a time, as a pipeline'\''s serial section applies it; median / slowest over the rounds." > o
    print "" > o
    print "| assembly | instances | parts | rounds | hide a section (instances) | isolate a bolt | show all | hide one part | show it again | check |" > o
    print "|---|---:|---:|---:|---:|---:|---:|---:|---:|---|" > o
    for (i = 1; i <= nasm; i++) {
        l = txn[asms[i]]; if (l == "") continue
        printf "| %s | %s | %s | %s | %s / %s (%s) | %s / %s | %s / %s | %s / %s | %s / %s | %s |\n", asms[i], kv(l, "instances"),
            kv(l, "parts"), kv(l, "rounds"), kv(l, "hide_section_us_median"), kv(l, "hide_section_us_max"),
            kv(l, "section_instances"), kv(l, "isolate_bolt_us_median"), kv(l, "isolate_bolt_us_max"),
            kv(l, "show_all_us_median"), kv(l, "show_all_us_max"), kv(l, "hide_part_us_median"), kv(l, "hide_part_us_max"),
            kv(l, "show_part_us_median"), kv(l, "show_part_us_max"), kv(l, "check") > o
    }
    print "" > o
    printf "Noise: %d runs, %d of them noisy (other programs used > 0.05 CPU during the timed frames: repeated, up to %d attempts; a configuration without a clean run keeps its noisy ones); median cpu_other over all runs %.2f CPUs.\n", attempts, noisy, max_attempts, med("other") > o
}' "$LOG"

{
    echo "## Parts and instances"
    echo
    echo "\`sh tools/bench_parts.sh\` (\`make bench-parts\`, also the end of \`make bench\`) at revision $revision,"
    echo "$(date -u '+%Y-%m-%d %H:%M UTC'); $(nproc) CPUs, ${cpu_model:-unknown CPU} (lscpu); tessera kernels ISA ${isa:-?};"
    echo "Embree $embree_version (Debian libembree-dev) through \`tools/embree_parts\` (this repository: one Embree"
    echo "scene per mesh, instanced by RTC_GEOMETRY_TYPE_INSTANCE geometries in a top scene; --flatten: one"
    echo "triangle geometry), build quality high. $ROUNDS round(s), $FRAMES timed frames a run, $SIZE, primary"
    echo "rays, eyelight shading. The run took $(min_s "$total_s"): $(min_s $((RUN_MS / 1000))) in the measured"
    echo "programs, $(min_s $((WAIT_MS / 1000))) waiting for quiet seconds; load when it began: $LOAD_AT_START."
    echo
    echo "Assemblies: \`build/gen-assembly\` (tools/gen_assembly/README.md):"
    echo
    for a in $ASMS; do
        echo "- $a: \`$(sed 's/ file=.*//' "$WORK/$a.gen")\`"
    done
    echo "$NOTES"
    echo
    echo '```sh'
    echo "./tessera bench --scene A.glb [--flatten] --size $SIZE --threads T --frames $FRAMES --camera C"
    echo "build/embree_parts -r $SIZE -t T -f $FRAMES -m single|p8|p16 [--flatten] --camera C A.glb"
    echo "./tessera bench --scene A.glb --size $SIZE --threads 2 --camera C --part-txns $TXNS"
    echo '```'
    echo
    echo "Per assembly, round and thread count, alternating, each its own process: tessera parts, Embree"
    echo "instances single, tessera flat, Embree flat single, tessera parts, Embree instances p8, Embree"
    echo "flat p8, tessera parts, Embree instances p16, tessera flat, Embree flat p16. Mrays/s of a run:"
    echo "tessera's \`prim_mrays\` (median of per-frame rates), Embree's W x H / \`median_ms\`; the tables give"
    echo "the median over the runs, spread = (max - min) / median. Ratios are of medians from this run."
    echo "**parts / flat** is the issue's criterion (within 10 %: >= 0.90)."
    echo
    echo "Camera C: tessera bench's framing of the parts scene (the peer's rule over \`scene_bounds\`),"
    echo "given to every run. Checked first, each program framing each representation itself:"
    echo
    echo "| assembly | representation | embree_parts chose tessera's camera | hits of a frame: tessera / Embree | camera |"
    echo "|---|---|---|---:|---|"
    while IFS="$(printf '\t')" read -r a rep same ht he cam; do
        echo "| $a | $rep | $same | $ht / $he | \`$cam\` |"
    done < "$WORK/cameras.tsv"
    echo
    cat "$WORK/tables.md"
    echo
    echo "The raw lines: \`$LOG\` (not kept in the repository; the assemblies were deleted)."
    echo
} > "$WORK/section.md"
cat "$WORK/section.md"

# into BENCHMARKS.md: in place of the old section, else before "## The pipeline" (which stays last)
if [ -f "$OUT" ]; then
    awk -v section="$WORK/section.md" '
        function put() { while ((getline l < section) > 0) print l; done = 1 }
        /^## Parts and instances$/ { put(); skip = 1; next }
        skip && /^## / { skip = 0 }
        skip { next }
        /^## The pipeline$/ && !done { put() }
        { print }
        END { if (!done) put() }' "$OUT" > "$WORK/BENCHMARKS.md"
    cp "$WORK/BENCHMARKS.md" "$OUT"
else
    cp "$WORK/section.md" "$OUT"
fi
echo "bench_parts: wrote the parts section of $OUT ($(min_s "$total_s"))" >&2
