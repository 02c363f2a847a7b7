#!/bin/sh
# bench_sbvh.sh - spatial splits (docs/scenes.md "Spatial splits"): every mesh traced with and without
# `tessera bench --spatial-splits`, for the gain (primary and primary + shadow Mrays/s) and the
# cost (build seconds, bytes a triangle, references a triangle). Prints a markdown section
# ("## Spatial splits") on stdout, keeps it in $WORK/sbvh_section.md (WORK is printed on stderr)
# and puts it into BENCHMARKS.md with bench_lib's replace_section (BENCH_SBVH_OUT names another
# file; "-" for none). `make bench-sbvh` runs it.
#
# Meshes: the three of $TESSERA_SHARED/data/meshes when present (scanned: few long triangles),
# the gen-assembly CAD assembly flattened into one PLY (build/gen-assembly --ply), and a "pipe
# rack" made here by awk: open tubes in random directions, every side one long thin quad (aspect
# 100-1000, what CAD tessellators make of cylinders), the case spatial splits are for.
#
# Per mesh and round, each run its own process after a quiet second, alternating
#   plain primary, splits primary, plain --shadows, splits --shadows
# A run during which other programs used more than 0.05 CPU (cpu_other) is repeated, up to
# BENCH_SBVH_ATTEMPTS attempts, and the last attempt is kept (counted as noisy). Figures are
# medians over the rounds; gain = splits / plain (> 1: splits faster).
#
# Environment: BENCH_SBVH_ROUNDS (3), BENCH_SBVH_FRAMES (5), BENCH_SBVH_SIZE (1280x720),
# BENCH_SBVH_THREADS (2), BENCH_SBVH_ATTEMPTS (2), BENCH_SBVH_ASSEMBLY_TRIANGLES (1000000),
# BENCH_SBVH_TUBES (3000), BENCH_MAX_WAIT (seconds of waiting for quiet per whole run, 300),
# TMPDIR, TESSERA_SHARED (../shared). Needs ./tessera and build/gen-assembly (make bench-sbvh
# builds both).
set -eu

cd "$(dirname "$0")/.."
BENCH_NAME=bench_sbvh
# shellcheck source=tools/bench_lib.sh
. tools/bench_lib.sh
SHARED=${TESSERA_SHARED:-../shared}
DATA=$SHARED/data/meshes
TMP=${TMPDIR:-/tmp}
OUT=${BENCH_SBVH_OUT:-BENCHMARKS.md}
ROUNDS=${BENCH_SBVH_ROUNDS:-3}
FRAMES=${BENCH_SBVH_FRAMES:-5}
SIZE=${BENCH_SBVH_SIZE:-1280x720}
THREADS=${BENCH_SBVH_THREADS:-2}
MAX_ATTEMPTS=${BENCH_SBVH_ATTEMPTS:-2}
ASM_TRIANGLES=${BENCH_SBVH_ASSEMBLY_TRIANGLES:-1000000}
TUBES=${BENCH_SBVH_TUBES:-3000}
WAIT_BUDGET_S=${BENCH_MAX_WAIT:-300}
NOISE_LIMIT=0.05

require_whole "BENCH_SBVH_ROUNDS=$ROUNDS" "BENCH_SBVH_FRAMES=$FRAMES" "BENCH_SBVH_THREADS=$THREADS" \
    "BENCH_SBVH_ATTEMPTS=$MAX_ATTEMPTS" "BENCH_SBVH_ASSEMBLY_TRIANGLES=$ASM_TRIANGLES" \
    "BENCH_SBVH_TUBES=$TUBES" "BENCH_MAX_WAIT=$WAIT_BUDGET_S"
for tool in ./tessera build/gen-assembly; do
    [ -x "$tool" ] || { echo "bench_sbvh: $tool not found; make bench-sbvh builds it" >&2; exit 1; }
done

WORK=$(mktemp -d "$TMP/tessera-bench-sbvh.XXXXXX")
LOG=$WORK/runs.log
: > "$LOG"
echo "bench_sbvh: work directory $WORK" >&2
cp ./tessera "$WORK/tessera"
TESSERA=$WORK/tessera

# ---- the generated meshes
build/gen-assembly --ply "$WORK/assembly.ply" --triangles "$ASM_TRIANGLES" --seed 1 > "$WORK/gen.log" 2>&1 || {
    cat "$WORK/gen.log" >&2
    exit 1
}
awk -v seed=7 -v tubes="$TUBES" -v sides=24 -v len=20 -v r=0.15 '
BEGIN {
    srand(seed); pi = 3.14159265358979
    printf "ply\nformat ascii 1.0\nelement vertex %d\n", tubes * sides * 2
    printf "property float x\nproperty float y\nproperty float z\nelement face %d\n", tubes * sides * 2
    printf "property list uchar int vertex_indices\nend_header\n"
    for (t = 0; t < tubes; t++) {
        # axis d uniform on the sphere; u, w unit normals to it; centre p in a 40-unit cube
        z = 2 * rand() - 1; a = 2 * pi * rand(); s = sqrt(1 - z * z)
        dx = s * cos(a); dy = s * sin(a); dz = z
        ex = 0; ey = 0; ez = 1
        if (dz > 0.9 || dz < -0.9) { ex = 1; ez = 0 }
        ux = dy * ez - dz * ey; uy = dz * ex - dx * ez; uz = dx * ey - dy * ex
        l = sqrt(ux * ux + uy * uy + uz * uz); ux /= l; uy /= l; uz /= l
        wx = dy * uz - dz * uy; wy = dz * ux - dx * uz; wz = dx * uy - dy * ux
        px = 40 * rand() - 20; py = 40 * rand() - 20; pz = 40 * rand() - 20
        for (e = 0; e < 2; e++)
            for (k = 0; k < sides; k++) {
                c = r * cos(2 * pi * k / sides); sn = r * sin(2 * pi * k / sides); o = (e - 0.5) * len
                printf "%.6f %.6f %.6f\n", px + o * dx + c * ux + sn * wx, py + o * dy + c * uy + sn * wy,
                    pz + o * dz + c * uz + sn * wz
            }
    }
    for (t = 0; t < tubes; t++)
        for (k = 0; k < sides; k++) {
            a0 = 2 * sides * t + k; a1 = 2 * sides * t + (k + 1) % sides
            printf "3 %d %d %d\n3 %d %d %d\n", a0, a1, a0 + sides, a1, a1 + sides, a0 + sides
        }
}' > "$WORK/pipe_rack.ply"

MESHES=""
for m in stanford_bunny.obj stanford_dragon_vrip.ply ctbunny_iso900_4M.ply; do
    if [ -f "$DATA/$m" ]; then MESHES="$MESHES $DATA/$m"; else echo "bench_sbvh: $DATA/$m not found: skipped" >&2; fi
done
MESHES="$MESHES $WORK/assembly.ply $WORK/pipe_rack.ply"

# run MESH VARIANT KIND ARGS...: one measurement (repeated while noisy), logged as
#   mesh variant kind status prim_mrays total_mrays build_s bytes_per_tri triangles references cpu_other
run() {
    r_mesh=$1 r_variant=$2 r_kind=$3
    shift 3
    attempt=1
    while :; do
        wait_quiet
        if ! "$TESSERA" bench --scene "$r_mesh" --size "$SIZE" --frames "$FRAMES" --threads "$THREADS" "$@" \
            > "$WORK/run.out" 2> "$WORK/run.err"; then
            echo "bench_sbvh: tessera bench failed on $r_mesh $*:" >&2
            cat "$WORK/run.err" >&2
            exit 1
        fi
        line=$(grep '^BENCH ' "$WORK/run.out" | tail -n 1)
        other=$(kv "$line" cpu_other)
        status=$(noise_status "$other" "$NOISE_LIMIT")
        echo "bench_sbvh: $(basename "$r_mesh") $r_variant $r_kind: $(kv "$line" prim_mrays) / $(kv "$line" total_mrays)" \
            "Mrays/s, build $(kv "$line" build_s) s ($status, cpu_other $other)" >&2
        [ "$status" = noisy ] && [ "$attempt" -lt "$MAX_ATTEMPTS" ] && { attempt=$((attempt + 1)); continue; }
        printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$(basename "$r_mesh")" "$r_variant" "$r_kind" \
            "$status" "$(kv "$line" prim_mrays)" "$(kv "$line" total_mrays)" "$(kv "$line" build_s)" \
            "$(kv "$line" bytes_per_tri)" "$(kv "$line" triangles)" "$(kv "$line" references)" "$other" >> "$LOG"
        return 0
    done
}

bench_started
for f in $MESHES; do
    r=1
    while [ "$r" -le "$ROUNDS" ]; do
        run "$f" plain primary
        run "$f" splits primary --spatial-splits
        run "$f" plain shadows --shadows
        run "$f" splits shadows --shadows --spatial-splits
        r=$((r + 1))
    done
done
total_s=$(($(date +%s) - start_s))

# ---- the section
SECTION=$WORK/sbvh_section.md
awk -F '\t' -v size="$SIZE" -v rounds="$ROUNDS" -v frames="$FRAMES" -v threads="$THREADS" \
    -v cpu="${cpu_model:-unknown CPU}" -v cpus="$(nproc)" -v load="$load_at_start" -v total_s="$total_s" \
    -v date="$(date -u '+%Y-%m-%d %H:%M UTC')" -v rev="$(git rev-parse --short HEAD 2>/dev/null || echo unknown)" \
    -v tubes="$TUBES" -v asm_tris="$ASM_TRIANGLES" '
function median(key,    n, i, j, tmp, v) {
    n = cnt[key]
    for (i = 1; i <= n; i++) v[i] = val[key, i]
    for (i = 2; i <= n; i++) for (j = i; j > 1 && v[j - 1] > v[j]; j--) { tmp = v[j]; v[j] = v[j - 1]; v[j - 1] = tmp }
    return n % 2 ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2
}
function add(key, x) { cnt[key]++; val[key, cnt[key]] = x }
{
    m = $1; v = $2
    if ($3 == "primary") add(m SUBSEP v SUBSEP "prim", $5)
    else add(m SUBSEP v SUBSEP "shadow", $6)
    add(m SUBSEP v SUBSEP "build", $7)
    bytes[m, v] = $8; tris[m] = $9; refs[m, v] = $10
    if ($4 != "clean") noisy++
    runs++
    if (!(m in seen)) { seen[m] = 1; meshes[++nm] = m }
}
END {
    printf "## Spatial splits\n\n"
    printf "%s, revision %s; %d CPUs, %s (lscpu); load average at start %s. `sh tools/bench_sbvh.sh`:\n", date, rev, cpus, cpu, load
    printf "`tessera bench` at %s, %d threads, with and without `--spatial-splits` (docs/scenes.md \"Spatial splits\"),\n", size, threads
    printf "%d rounds of alternating runs (plain, splits; primary rays, then `--shadows`), %d timed frames each;\n", rounds, frames
    printf "medians over the rounds. Primary: Mrays/s of primary rays alone; + shadows: primary + shadow rays\n"
    printf "per second of a `--shadows` frame. Build: seconds of accel_build (the binned builder is parallel,\n"
    printf "the spatial one serial). Bytes: (mesh + tree) / triangle; references: triangles stored / triangles.\n"
    printf "assembly.ply: `gen-assembly --ply --triangles %d --seed 1`; pipe_rack.ply: %d open tubes of 24\n", asm_tris, tubes
    printf "sides, 20 long, radius 0.15, in random directions (awk, in the script): long thin diagonal triangles.\n"
    printf "%d of %d kept runs were noisy (other programs > 0.05 CPU after the retries); the whole run took %d s.\n\n", noisy + 0, runs + 0, total_s
    printf "| mesh | triangles | primary Mrays/s plain | splits | gain | + shadows plain | splits | gain | build s plain | splits | bytes/tri plain | splits | references/tri |\n"
    printf "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    for (i = 1; i <= nm; i++) {
        m = meshes[i]
        pp = median(m SUBSEP "plain" SUBSEP "prim"); ps = median(m SUBSEP "splits" SUBSEP "prim")
        sp = median(m SUBSEP "plain" SUBSEP "shadow"); ss = median(m SUBSEP "splits" SUBSEP "shadow")
        bp = median(m SUBSEP "plain" SUBSEP "build"); bs = median(m SUBSEP "splits" SUBSEP "build")
        gain_p = pp > 0 ? ps / pp : 0; gain_s = sp > 0 ? ss / sp : 0
        per_tri = tris[m] > 0 ? refs[m, "splits"] / tris[m] : 0
        printf "| %s | %d | %.2f | %.2f | %.3f | %.2f | %.2f | %.3f | %.3f | %.2f | %.1f | %.1f | %.3f |\n", m, tris[m],
            pp, ps, gain_p, sp, ss, gain_s, bp, bs, bytes[m, "plain"], bytes[m, "splits"], per_tri
    }
    printf "\n"
}' "$LOG" > "$SECTION"
cat "$SECTION"
if [ "$OUT" != "-" ]; then
    replace_section "$OUT" "## Spatial splits" "$SECTION" "$WORK/out.tmp"
    echo "bench_sbvh: section written into $OUT" >&2
fi
