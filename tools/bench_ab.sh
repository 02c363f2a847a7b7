#!/bin/sh
# bench_ab.sh - two tessera binaries against each other on the shared meshes,
# alternately (A B A B ...), primary rays at 1 and 2 threads: for a change
# that must not change speed (a move, a split), whether it did.
#
#   sh tools/bench_ab.sh OLD_TESSERA NEW_TESSERA
#
# Each round runs, for each mesh and thread count, A then B (the order flips
# every round, so a drift of the machine's speed falls on both), each its own
# process: `tessera bench --scene MESH --size 1920x1080 --threads T --frames F`.
# Prints each run's prim_mrays and cpu_other, then per mesh and thread count
# the median of A and of B and the median of the per-round ratios B/A (1.00:
# the same speed; above 1: B is faster). The machine and ISA head the output.
# Environment: AB_ROUNDS (default 5), AB_FRAMES (default 10), AB_SIZE
# (default 1920x1080), TESSERA_SHARED (default ../shared). Meshes that are not
# there are skipped, said so.
set -eu
[ $# -eq 2 ] || { echo "usage: sh tools/bench_ab.sh OLD_TESSERA NEW_TESSERA" >&2; exit 2; }
A=$1
B=$2
cd "$(dirname "$0")/.."
SHARED=${TESSERA_SHARED:-../shared}
DATA=$SHARED/data/meshes
ROUNDS=${AB_ROUNDS:-5}
FRAMES=${AB_FRAMES:-10}
SIZE=${AB_SIZE:-1920x1080}
TESSERA_CACHE=off # build times are not compared, but a cache would change what is loaded
export TESSERA_CACHE
LOG=$(mktemp "${TMPDIR:-/tmp}/tessera-ab.XXXXXX")

echo "bench_ab: A=$A B=$B rounds=$ROUNDS frames=$FRAMES size=$SIZE"
echo "bench_ab: cpu: $(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo), $(nproc) CPUs"

one() { # one run: label binary mesh threads -> "label mesh threads mrays cpu_other isa"
    line=$("$2" bench --scene "$DATA/$3" --size "$SIZE" --threads "$4" --frames "$FRAMES" 2>/dev/null | grep '^BENCH')
    mrays=$(printf '%s\n' "$line" | sed -n 's/.* prim_mrays=\([0-9.]*\).*/\1/p')
    other=$(printf '%s\n' "$line" | sed -n 's/.* cpu_other=\([0-9.]*\).*/\1/p')
    isa=$(printf '%s\n' "$line" | sed -n 's/.* isa=\([a-z0-9]*\).*/\1/p')
    echo "$1 $3 $4 $mrays $other $isa" | tee -a "$LOG"
}

round=1
while [ "$round" -le "$ROUNDS" ]; do
    for m in stanford_bunny.obj stanford_dragon_vrip.ply ctbunny_iso900_4M.ply; do
        if [ ! -f "$DATA/$m" ]; then
            [ "$round" -eq 1 ] && echo "bench_ab: $DATA/$m not there: skipped"
            continue
        fi
        for t in 1 2; do
            if [ $((round % 2)) -eq 1 ]; then
                one A "$A" "$m" "$t"
                one B "$B" "$m" "$t"
            else
                one B "$B" "$m" "$t"
                one A "$A" "$m" "$t"
            fi
        done
    done
    round=$((round + 1))
done

echo "bench_ab: medians (Mrays/s) and the median of the per-round ratios B/A:"
# runs of one mesh and thread count come in A/B pairs, in order: pair k is the k-th A with the k-th B
awk '
function median(a, n,    i, j, t) {
    for (i = 2; i <= n; i++) { t = a[i]; for (j = i - 1; j >= 1 && a[j] > t; j--) a[j + 1] = a[j]; a[j + 1] = t }
    return n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
}
{ key = $2 " threads=" $3; if (!(key in seen)) { seen[key] = 1; order[++keys] = key }
  if ($1 == "A") a[key, ++na[key]] = $4; else b[key, ++nb[key]] = $4; isa[key] = $6 }
END {
    for (k = 1; k <= keys; k++) {
        key = order[k]; n = na[key] < nb[key] ? na[key] : nb[key]
        for (i = 1; i <= n; i++) { va[i] = a[key, i]; vb[i] = b[key, i]; r[i] = a[key, i] > 0 ? b[key, i] / a[key, i] : 0 }
        printf "bench_ab: %-40s isa=%s A %7.3f  B %7.3f  B/A %.3f (%d pairs)\n", key, isa[key], median(va, n), median(vb, n), median(r, n), n
    }
}' "$LOG"
rm -f "$LOG"
