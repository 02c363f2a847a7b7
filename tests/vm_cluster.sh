#!/bin/sh
# tests/vm_cluster.sh - end-to-end: a wall of two machines on DRM/KMS. One qemu
# guest (tests/vm/) with two virtio-gpu cards of two heads each stands in for
# two machines: `mpirun -np 2` (OpenMPI in the guest) starts one tessera per
# card (--card /dev/dri/cardN), each driving its node's two outputs of the 2x2
# wall configs/walls/vm_two_machines.json (card0's Virtual-1 and Virtual-2,
# card1's Virtual-3 and Virtual-4: one kernel numbers connectors across its
# cards; the nodes name the outputs by index). Rank 0 plays
# the camera path and sends every frame's camera to rank 1 (cluster/); both
# flip each frame after the barrier before the flip. The animation is
# vm_wall.sh's: 6 spheres, an 8-key orbit that loops every 4 s, played with
# --time fixed --rate 4, so each output has K = 16 possible pictures, which
# the host renders natively (one process, every output) as references.
#
# Checks, each printed as PASS/FAIL:
#   1. both processes bring up their card's 2 outputs;
#   2. every screendump of the 4 heads (2 per card) equals, pixel for pixel,
#      the native render of one frame of that output: each process shows its
#      part of the one wall, steered by the leader's cameras;
#   3. frames keep flipping (each head >= MIN_FRAMES distinct pictures) and each
#      dump shows a frame the processes' logs put on screen around it;
#   4. frame lock, from the vblank lines each process logs for every flip
#      ("flipped to frame F at vblank S (T s)", one guest clock for both): both
#      flipped the same frames, and no process ever showed frame F + 1 before
#      every output of the other showed F, whatever the speed of the machine.
#      The barrier guarantees it: a process reaches the barrier of F + 1 only
#      after its settle_stage waited for its own flips of F, and commits F + 1
#      only after every process reached that barrier;
#   5. SIGTERM to rank 0 stops both at the same frame, exit 0, and the leader
#      prints the flip skew (no frame out of step) and the scan-out skew (by
#      vblank time) over the frames both flipped.
# Exits 0 when all pass. When qemu cannot be installed it says so and exits 0
# with SKIPPED in its last line, as vm_wall.sh.
#
# Guest protocol (files in the share $W): the guest starts mpirun (rankN.pid,
# tesseraN.log per rank); host: `done` when it has seen enough; guest: SIGTERM
# to rank 0, mpirun's status in mpirun.rc.
#
# Run from the repository root by `make test` (after ./tessera is built).
# Environment: TESSERA_VM_CACHE (default /tmp/tessera-vm-cache), VM_KEEP=1 keeps
# the work folder (screendumps, references, logs).
set -u
cd "$(dirname "$0")/.." || exit 1
NAME=vm_cluster
W=$(mktemp -d /tmp/tessera-vm-cluster.XXXXXX)
. tests/vm/host_lib.sh

K=16    # frames per loop: period 4 s x rate 4 Hz
RATE=4  # also in rank.sh's tessera run
MIN_FRAMES=3

mkdir -p "$W/bin"
copy_tessera
vm_guest

cp configs/walls/vm_two_machines.json "$W/wall.json"
cp tests/data/vm_spheres.json "$W/scene.json"
cp tests/data/vm_loop.json "$W/loop.json"

# one machine of the wall: rank N drives card N. Both processes run in one guest, so the
# seat is left out (LIBSEAT_BACKEND=noop: devices opened directly, no VT handling): two
# processes cannot both own the one VT, which on a wall of real machines each has.
cat > "$W/rank.sh" <<'EOF'
echo $$ > rank$1.pid
exec env TESSERA_LOG=debug LIBSEAT_BACKEND=noop tessera run --wall wall.json --card /dev/dri/card$1 \
    --scene scene.json --path loop.json --time fixed --rate 4 --threads 1 --input off > tessera$1.log 2>&1
EOF
cp tests/vm/guest_lib.sh "$W/"
cat > "$W/guest.sh" <<'EOF'
. ./guest_lib.sh
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
ls /dev/dri > cards.txt 2>&1
mpirun --oversubscribe --bind-to none -np 1 sh rank.sh 0 : -np 1 sh rank.sh 1 > mpirun.log 2>&1 &
mp=$!
run_steps $mp 3600
[ -e rank0.pid ] && kill -TERM "$(cat rank0.pid)" 2>/dev/null
i=0
while alive $mp && [ $i -lt 3000 ]; do sleep 0.1; i=$((i + 1)); done
if alive $mp; then
    kill -KILL $mp
    echo "none (still running 300 s after SIGTERM to rank 0; killed)" > mpirun.rc
else
    wait $mp
    echo $? > mpirun.rc
fi
EOF
tests/vm/run-guest.sh -c "$GUEST" -s "$W" -q "$W/qmp.sock" -g 2 -n 2 -r 640x480 -t 3000 -- 'sh guest.sh' \
    > "$W/guest.console" 2>&1 &
GPID=$!

qmp() { python3 tests/vm/qmp.py "$W/qmp.sock" "$@"; }
# head h of the wall: card h/2 (qemu device gpuN), its head h%2; output Virtual-(h+1)
label() { printf 'Virtual-%d' $(($1 + 1)); }
dump() { qmp screendump "$2" $(($1 % 2)) gpu$(($1 / 2)) > "$W/dump.err" 2>&1; } # HEAD FILE

# the native references, while the guest boots: frames 0 .. K-1 of every output, one process
mkdir "$W/ref"
if ! "$W/bin/tessera" render --wall "$W/wall.json" --scene "$W/scene.json" --path "$W/loop.json" --time fixed \
    --rate $RATE --frames $K --threads 2 --out "$W/ref/f_####.bmp" > "$W/native.log" 2>&1; then
    cat "$W/native.log"
    echo "$NAME: FAIL: the native render failed"
    exit 1
fi
for h in 0 1 2 3; do
    j=0 refs=
    while [ $j -lt $K ]; do
        refs="$refs $(printf '%s/ref/f_%04d-%s.bmp' "$W" $j "$(label $h)")"
        j=$((j + 1))
    done
    echo "$refs" > "$W/refs$h"
done
# match HEAD FILE: the frame index of that output FILE shows; 1 (reason in $W/match.out) if none
match() {
    # shellcheck disable=SC2046
    python3 tests/vm/qmp.py match "$2" $(cat "$W/refs$1") > "$W/match.out" 2>&1 || return 1
    cut -d' ' -f1 "$W/match.out"
}
# the newest frame on screen on both machines (-1 before), and on either
newest_both() {
    _a=$(last_frame tessera0.log) _b=$(last_frame tessera1.log)
    [ "$_a" -lt "$_b" ] && echo "$_a" || echo "$_b"
}
newest_either() {
    _a=$(last_frame tessera0.log) _b=$(last_frame tessera1.log)
    [ "$_a" -gt "$_b" ] && echo "$_a" || echo "$_b"
}

# the first frame on both machines (boot, mpirun and two tessera starts: ~30-60 s here under
# TCG); FRAME_MS from 3 frames of rank 0
while [ "$(elapsed)" -lt 900 ] && kill -0 "$GPID" 2>/dev/null && [ "$(newest_both)" -lt 0 ]; do
    sleep 1
done
up=no
if [ "$(newest_both)" -ge 0 ] && wait_frame tessera0.log $(($(last_frame tessera0.log) + 3)) 100; then
    up=yes
fi
t_up=$(elapsed)

# rounds of screendumps of the 4 heads until each showed MIN_FRAMES distinct pictures; each
# dump's FILE.frames: the newest frame on screen on both before it, on either after it
rounds=0
if [ $up = yes ]; then
    mkdir "$W/obs"
    t_obs=$(elapsed)
    obs_limit=$(frames_s 16)
    while [ $(($(elapsed) - t_obs)) -lt "$obs_limit" ] && kill -0 "$GPID" 2>/dev/null; do
        for h in 0 1 2 3; do
            f="$W/obs/$rounds-$h.ppm"
            before=$(newest_both)
            dump $h "$f" || break 2
            echo "$before $(newest_either)" > "$f.frames"
            cksum < "$f" >> "$W/obs/sums$h"
        done
        rounds=$((rounds + 1))
        least=$(for h in 0 1 2 3; do sort -u "$W/obs/sums$h" | wc -l; done | sort -n | head -n 1)
        [ "$least" -ge $MIN_FRAMES ] && break
        sleep 0.3
    done
    t_obs=$(($(elapsed) - t_obs))
fi
touch "$W/done"

# match the dumps while the guest stops the wall
mismatch=
[ $up = yes ] && for h in 0 1 2 3; do
    : > "$W/seq$h"
    r=0
    while [ $r -lt $rounds ]; do
        f="$W/obs/$r-$h.ppm"
        [ -e "$f" ] || break
        if ! idx=$(match $h "$f"); then
            mismatch="head $h of card $((h / 2)) ($(label $h)), screendump $r: $(cat "$W/match.out")"
            break 2
        fi
        echo "$idx $(cat "$f.frames")" >> "$W/seq$h"
        r=$((r + 1))
    done
done
wait "$GPID"
guest_status=$?
GPID=

# ---- the checks
for n in 0 1; do
    if grep -q "/dev/dri/card$n: 2 outputs up" "$W/tessera$n.log" 2>/dev/null; then
        ok "rank $n: card$n's 2 outputs up ($(sed -n 's/.*(\(.*\) modesetting).*/\1/p' "$W/tessera$n.log") modesetting)"
    else
        bad "rank $n: card$n's outputs did not come up: $(tail -n 5 "$W/tessera$n.log" 2>/dev/null) $(tail -n 5 "$W/mpirun.log" 2>/dev/null) (/dev/dri: $(cat "$W/cards.txt" 2>/dev/null | paste -sd ' '))"
    fi
done
if [ $up = no ]; then
    bad "the wall never showed 3 frames on both machines within $t_up s: $(tail -n 3 "$W/tessera0.log" 2>/dev/null) / $(tail -n 3 "$W/tessera1.log" 2>/dev/null) / $(tail -n 5 "$W/guest.console")"
elif [ -n "$mismatch" ]; then
    bad "a screendump equals no native frame of its output (VM_KEEP=1 keeps them): $mismatch"
else
    ok "all $((rounds * 4)) screendumps of the 4 heads of 2 cards ($rounds rounds) equal native renders of their output pixel for pixel (3 frames on both machines after $t_up s)"
fi
if [ $up = yes ] && [ -z "$mismatch" ]; then
    # frame f of the pipeline is loop frame f mod K; a dump shows a frame from the newest on
    # screen on both before it to the one after the newest on either after it
    flips=$(for h in 0 1 2 3; do
        awk -v K=$K -v h=$h -v min=$MIN_FRAMES '{
            if (!($1 in seen)) { seen[$1] = 1; n++ }
            ok = 0
            for (f = $2; f <= $3 + 1 && !ok; f++) ok = f >= 0 && f % K == $1
            if (!ok) wrong = wrong " " $1 " (on screen " $2 ".." $3 ")"
            frames = frames " " $1
        } END {
            printf "%s head %d: frames%s: %d distinct%s\n", (n >= min && wrong == "" ? "ok" : "bad"), h,
                frames, n, wrong == "" ? "" : ", not what the logs said was on screen:" wrong
        }' "$W/seq$h"
    done)
    summary=$(echo "$flips" | sed 's/^[a-z]* //' | paste -sd ';' | sed 's/;/; /g')
    if echo "$flips" | grep -q '^bad'; then
        bad "frames did not keep flipping ($MIN_FRAMES distinct per head needed, each what the logs said was on screen; in $t_obs s): $summary"
    else
        ok "frames keep flipping on both cards, each dump a frame the logs put on screen (observed for $t_obs s): $summary"
    fi
else
    bad "frames keep flipping: not checked (${mismatch:+a screendump matched no frame}${mismatch:-the wall never came up})"
fi

# frame lock from the vblank lines: "CARD: OUTPUT: flipped to frame F at vblank S (T s)"
lock=$(python3 - "$W/tessera0.log" "$W/tessera1.log" <<'EOF'
import re, sys
pat = re.compile(r"(/dev/dri/card\d+): (\S+): flipped to frame (\d+) at vblank (\d+) \((\d+)\.(\d+) s\)")
flips = []  # per process: frame -> [times of its outputs' flips]
for path in sys.argv[1:]:
    per = {}
    for line in open(path, errors="replace"):
        m = pat.search(line)
        if m:
            per.setdefault(int(m.group(3)), []).append(int(m.group(5)) * 1000000 + int(m.group(6)))
    flips.append(per)
if not all(flips):
    print("bad: no vblank lines in %s" % [sys.argv[1 + i] for i, p in enumerate(flips) if not p]); sys.exit()
common = sorted(set(flips[0]) & set(flips[1]))
# the last frame or two may be flipped by one process only as they stop; the frames one
# flipped and the other did not, below the last common one, break the lock
gaps = [f for p in flips for f in p if f < common[-1] and f not in common] if common else []
# no process shows F + 1 before every output of the other showed F; the smallest margin
ahead, margin = [], None
for f in common:
    if f + 1 not in common:
        continue
    for a, b in ((0, 1), (1, 0)):
        m = min(flips[a][f + 1]) - max(flips[b][f])
        margin = m if margin is None or m < margin else margin
        if m < 0:
            ahead.append("rank %d showed %d at %.6f s before rank %d's last output showed %d at %.6f s"
                         % (a, f + 1, min(flips[a][f + 1]) / 1e6, b, f, max(flips[b][f]) / 1e6))
outputs = [min(len(p[f]) for f in common) for p in flips] if common else [0, 0]
spread = sorted(max(max(p[f]) for p in flips) - min(min(p[f]) for p in flips) for f in common)
verdict = "ok" if len(common) >= 3 and not gaps and not ahead and outputs == [2, 2] else "bad"
print("%s: %d frames flipped by both (%d..%d), every one on %s outputs; frames only one flipped: %s; "
      "a frame ahead of the other: %s (smallest margin %d us); first-to-last output spread median %d us, "
      "max %d us (the guest's flip times)"
      % (verdict, len(common), common[0] if common else -1, common[-1] if common else -1, outputs,
         gaps or "none", "; ".join(ahead[:3]) or "never", margin if margin is not None else -1,
         spread[len(spread) // 2] if spread else -1, spread[-1] if spread else -1))
EOF
)
case $lock in
ok*) ok "frame lock: ${lock#ok: }" ;;
*) bad "frame lock: ${lock#bad: }" ;;
esac

rc=$(cat "$W/mpirun.rc" 2>/dev/null || echo none)
skew=$(grep -h 'cluster: flip skew over' "$W/tessera0.log" 2>/dev/null | tail -n 1)
scan=$(grep -h 'cluster: scan-out skew' "$W/tessera0.log" 2>/dev/null | tail -n 1)
counts=$(grep -h 'cluster: rank [01] of 2' "$W/tessera0.log" "$W/tessera1.log" 2>/dev/null | wc -l)
if [ "$rc" = 0 ] && [ "$guest_status" = 0 ] && [ "$counts" -eq 2 ] &&
    echo "$skew" | grep -q 'frames out of step: 0)' && [ -n "$scan" ]; then
    ok "SIGTERM to rank 0 stopped both processes, exit 0; ${skew#*cluster: }; ${scan#*cluster: }"
else
    bad "stopping: mpirun status '$rc' (guest status $guest_status), $counts count lines, skew '${skew:-none}', scan-out '${scan:-none}'"
    tail -n 8 "$W/tessera0.log" "$W/tessera1.log" "$W/mpirun.log" "$W/guest.console" 2>/dev/null
fi

echo "$NAME: $PASS passed, $FAIL failed ($(elapsed) s)"
[ "$FAIL" -eq 0 ]
