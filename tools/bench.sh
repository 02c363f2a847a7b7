#!/bin/sh
# bench.sh - load, build and render timings of tessera on the shared meshes
# (../shared/data/meshes), when they are present. Medians of REPS runs.
# Usage: sh tools/bench.sh [reps]      (from the repository root, after make)
set -eu
REPS=${1:-3}
DATA=${TESSERA_DATA:-../shared/data/meshes}
OUT=${TMPDIR:-/tmp}/tessera-bench
mkdir -p "$OUT"
if [ ! -d "$DATA" ]; then
    echo "bench: $DATA not found; nothing to measure" >&2
    exit 0
fi

median() { sort -g | awk '{v[NR]=$1} END {print (NR%2) ? v[(NR+1)/2] : (v[NR/2]+v[NR/2+1])/2}'; }

printf '| mesh | triangles | load s | BVH build s | 1T frames/s | 2T frames/s |\n'
printf '|---|---:|---:|---:|---:|---:|\n'
for mesh in stanford_bunny.obj stanford_dragon_vrip.ply ctbunny_iso900_4M.ply; do
    f="$DATA/$mesh"
    [ -f "$f" ] || continue
    : > "$OUT/load" ; : > "$OUT/build"; : > "$OUT/fps1"; : > "$OUT/fps2"
    r=0
    while [ $r -lt "$REPS" ]; do
        for t in 1 2; do
            ./tessera render --scene "$f" --size 1920x1080 --threads $t --frames 3 --out "$OUT/img.png" \
                > "$OUT/stdout" 2> "$OUT/stderr"
            sed -n 's/.* \([0-9]*\) triangles.*loaded in \([0-9.]*\) s, BVH built in \([0-9.]*\) s.*/\1 \2 \3/p' \
                "$OUT/stderr" > "$OUT/line"
            read -r tris load build < "$OUT/line"
            echo "$load" >> "$OUT/load"
            echo "$build" >> "$OUT/build"
            sed -n 's/.*rendering \([0-9.]*\) frames\/s.*/\1/p' "$OUT/stdout" >> "$OUT/fps$t"
        done
        r=$((r + 1))
    done
    printf '| %s | %s | %s | %s | %s | %s |\n' "$mesh" "$tris" "$(median < "$OUT/load")" \
        "$(median < "$OUT/build")" "$(median < "$OUT/fps1")" "$(median < "$OUT/fps2")"
done
