#!/bin/sh
# bench_cluster.sh - a wall of several processes on this machine (cluster/, make bench-cluster):
# one 2x2 headless wall (four 480x270 outputs, the built-in scene orbiting, fixed time, display
# null, BENCH_CLUSTER_FRAMES frames, default 240) rendered by
#   one process without mpirun (2 threads): the baseline;
#   mpirun -np 1 (2 threads): the same with the syncs, whose cost this shows alone;
# (every mpirun with --bind-to none: by default it binds a process to one core, which halves
# a process of 2 threads here)
#   mpirun -np 2 (two outputs each, 1 thread each);
#   mpirun -np 4 (one output each, 1 thread each: 4 processes on this machine's CPUs);
# each BENCH_CLUSTER_RUNS times (default 3, medians). Per run: frames per second, the frame
# sync's stop vote (the leader's wait for every vote: the slowest process) and send (the leader's
# header and records to each once everybody is there), the barrier before the flip, and the flip skew (how far
# apart the processes passed that barrier, per frame; CLOCK_REALTIME, one clock here). Prints the
# section and writes it into BENCHMARKS.md as "## Cluster" (BENCH_CLUSTER_OUT names another
# file; "-" for none).
set -eu
cd "$(dirname "$0")/.."
BENCH_NAME=bench_cluster
WAIT_BUDGET_S=${BENCH_CLUSTER_WAIT_S:-60}
. tools/bench_lib.sh
OUT=${BENCH_CLUSTER_OUT:-BENCHMARKS.md}
FRAMES=${BENCH_CLUSTER_FRAMES:-240}
RUNS=${BENCH_CLUSTER_RUNS:-3}
[ -x ./tessera ] || { echo "bench_cluster: run make bench-cluster" >&2; exit 1; }
command -v mpirun >/dev/null || { echo "bench_cluster: mpirun is missing (tools/deps.sh)" >&2; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
WORK=$(mktemp -d "${TMPDIR:-/tmp}/tessera-bench-cluster.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
bench_started
revision=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)

# the wall with NODES (a JSON array, or "" for none)
wall() {
    cat > "$WORK/$1.json" <<EOF
{"format": "tessera-wall", "version": 1, "units": "mm", "outputs": [
 {"connector": "Virtual-1", "mode": "480x270", "grid": [0, 0], "size_mm": [480, 270]},
 {"connector": "Virtual-2", "mode": "480x270", "grid": [1, 0], "size_mm": [480, 270]},
 {"connector": "Virtual-3", "mode": "480x270", "grid": [0, 1], "size_mm": [480, 270]},
 {"connector": "Virtual-4", "mode": "480x270", "grid": [1, 1], "size_mm": [480, 270]}]$2}
EOF
}
wall one ""
wall np1 ', "nodes": [{"rank": 0, "outputs": ["Virtual-1", "Virtual-2", "Virtual-3", "Virtual-4"]}]'
wall np2 ', "nodes": [{"rank": 0, "outputs": ["Virtual-1", "Virtual-2"]}, {"rank": 1, "outputs": ["Virtual-3", "Virtual-4"]}]'
wall np4 ', "nodes": [{"rank": 0, "outputs": ["Virtual-1"]}, {"rank": 1, "outputs": ["Virtual-2"]}, {"rank": 2, "outputs": ["Virtual-3"]}, {"rank": 3, "outputs": ["Virtual-4"]}]'

# one run: LABEL PROCESSES THREADS; appends "label=.. fps=.. vote=.. send=.. barrier=.. skew=.. skew_max=.." to lines
run() {
    label=$1 np=$2 threads=$3
    wait_quiet
    log="$WORK/$label.log"
    if [ "$np" = 0 ]; then
        ./tessera run --wall "$WORK/one.json" --display null --frames "$FRAMES" --threads "$threads" > "$log" 2>&1
    else
        mpirun -np "$np" --bind-to none ./tessera run --wall "$WORK/np$np.json" --display null --frames "$FRAMES" \
            --threads "$threads" > "$log" 2>&1
    fi
    # frames/s: the slowest process's (they are in step); the leader's sync counts and the skew
    fps=$(sed -n 's/.* thread[s]*: \([0-9.]*\) frames\/s.*/\1/p' "$log" | sort -g | head -n 1)
    lead=$(grep "cluster: rank 0 of" "$log" || true)
    vote=$(printf '%s' "$lead" | sed -n 's/.*stop vote \([0-9]*\) .*/\1/p')
    send=$(printf '%s' "$lead" | sed -n "s/.*leader's records \([0-9]*\) .*/\1/p")
    barrier=$(printf '%s' "$lead" | sed -n 's/.*before the flip \([0-9]*\) .*/\1/p')
    skew=$(sed -n 's/.*flip skew over [0-9]* frames: median \([0-9]*\) us.*/\1/p' "$log")
    skew_max=$(sed -n 's/.*flip skew over .* max \([0-9]*\) us.*/\1/p' "$log")
    echo "label=$label fps=$fps vote=${vote:--} send=${send:--} barrier=${barrier:--} skew=${skew:--} skew_max=${skew_max:--}" >> "$WORK/lines"
}
: > "$WORK/lines"
for r in $(seq "$RUNS"); do
    echo "bench_cluster: round $r of $RUNS" >&2
    run one 0 2
    run np1 1 2
    run np2 2 1
    run np4 4 1
done
# medians per configuration
med() { grep "label=$1 " "$WORK/lines" | while read -r l; do kv "$l" "$2"; done | grep -v '^-$' | median; }
row() {
    printf '| %s | %s | %s | %s | %s | %s | %s | %s |\n' "$2" "$3" "$(med "$1" fps)" "$4" \
        "$(if [ "$1" = one ]; then echo -; else med "$1" vote; fi)" \
        "$(if [ "$1" = one ]; then echo -; else med "$1" send; fi)" \
        "$(if [ "$1" = one ]; then echo -; else med "$1" barrier; fi)" \
        "$(if [ "$1" = one ] || [ "$1" = np1 ]; then echo -; else echo "$(med "$1" skew) / $(med "$1" skew_max)"; fi)"
}
base=$(med one fps)
ratio() { awk -v a="$(med "$1" fps)" -v b="$base" 'BEGIN { if (b > 0) printf "%.2f", a / b; else print "-" }'; }
SECTION=$WORK/section.md
{
    echo "## Cluster"
    echo
    echo "$(date -u '+%Y-%m-%d %H:%M UTC'), revision $revision; $(nproc) CPUs, ${cpu_model:-unknown CPU} (lscpu); load average at the start $load_at_start. \`make bench-cluster\` (\`tools/bench_cluster.sh\`), medians of $RUNS runs."
    echo
    echo "One 2x2 wall of four 480x270 outputs (the built-in scene orbiting, $FRAMES frames, fixed time, display"
    echo "null) rendered by one process and by 1, 2 and 4 processes under \`mpirun\` on this one machine. Every"
    echo "message goes to or from the leader (cluster/README.md). *Vote*: the leader's wait for every follower's"
    echo "stop vote, which is the wait for the slowest process; *send*: the leader sending the header and records"
    echo "to each follower once everybody is there (the sync's own cost); *barrier*: the barrier before the flip"
    echo "(READY from each, then GO), waiting included; *skew*: how far apart the processes passed that barrier for"
    echo "one frame (median / max). All in microseconds a frame, the leader's."
    echo
    echo "| processes | threads each | frames/s | vs one process | vote us | send us | barrier us | skew us |"
    echo "|---|---:|---:|---:|---:|---:|---:|---:|"
    row one "1 (no mpirun)" 2 1.00
    row np1 "1 (mpirun)" 2 "$(ratio np1)"
    row np2 2 1 "$(ratio np2)"
    row np4 4 1 "$(ratio np4)"
    echo
    echo "What this machine can and cannot show: it has $(nproc) CPUs, so 2 processes of 1 thread use what 1"
    echo "process of 2 threads uses, and 4 processes share 2 CPUs (the kernel's scheduler then decides the skew). It"
    echo "shows the cost of keeping processes in step (np 1 against no mpirun), and that sending the records is"
    echo "microseconds; it cannot show how a wall scales with machines, which takes machines."
    echo
} > "$SECTION"
cat "$SECTION"
[ "$OUT" = "-" ] || replace_section "$OUT" "## Cluster" "$SECTION" "$WORK/out.md"
