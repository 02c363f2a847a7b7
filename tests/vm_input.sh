#!/bin/sh
# tests/vm_input.sh - end-to-end: people steer tessera's DRM wall with input
# devices in a qemu guest (tests/vm/), and what the wall shows is what the
# recorded input transactions give when replayed natively on the host.
#
# One guest boot: tessera runs the 2x2 wall (configs/walls/vm_2x2.json, 4
# virtio-gpu heads at 640x480) in real time with input on (libinput, udev seat
# backend, devices opened through the seat), no idle tour, --record-input
# rec.txt in the share, and a uinput touchscreen (tests/vm/uinput_touch.c,
# made in the guest, 640x480 units) mapped to output Virtual-3 (bottom left)
# with --map-input. The host drives it:
#   keyboard  (QMP, virtio keyboard): W held 0.6 s (flight), H over a sphere
#             (hide it), U (unhide all)
#   mouse     (QMP, virtio mouse, relative): left drag (orbit), wheel (dolly)
#   tablet    (QMP, virtio tablet, absolute over the whole wall): move, click
#             (pick: status line), right drag (pan)
#   touch     (uinput in the guest, on Virtual-3): one-finger drag (orbit),
#             pinch (dolly), tap (pick), double tap (fly-to)
#   touchpad  (uinput in the guest, `uinput_touch -p`): pinch (dolly), three-finger
#             swipe (pan), two-finger scroll (the wheel)
#   hotplug   the touchscreen unplugged, another plugged in (tap on it)
#   garbage   3000 raw events from that touchscreen out of every range, in
#             bursts (the kiosk goes on; the heads equal the replay of what
#             they made), then Home
#   VT switch chvt 2, chvt 1, then a key (the devices were revoked and taken back)
#   quit chord Ctrl+Alt+Q at the end.
# Then a second run, with --idle-timeout 8 (longer on a slow guest: 8 frames'
# time + 6 s) and the default tour (an orbit of the home view): the picture
# moves with nobody there, holds still after a key, and moves again after the
# idle timeout.
# Then a third run on a 10,000-part glTF assembly (build/gen-assembly --parts
# 10000 --triangles 2000000, made here on the host), no shadows, another
# uinput touchscreen mapped to Virtual-4, in four checks (about 3 min):
# the tablet's click picks a skin panel (the record's status names its path:
# "picked part assembly/..."), H hides it (a hide of its instance range; the
# native render of the record without the hide differs where it was); I
# isolates it (the same range); U shows all, a long press on the touchscreen
# selects and isolates the part under the finger, a two-finger tap shows all
# (the record's kinds in that order; heads 1 and 2, which show neither the
# status line nor the cursor, equal the start's native render); C places a
# cutting plane at the tablet's cursor, a middle-button drag pushes it, [
# lowers the opacity (two clip-plane records and an opacity record). Each check
# also asks the heads to equal the native replay of the record, as above.
# Then a fourth run on a particle time series made here (3 LAMMPS dumps of 2,744
# particles with a kinetic-energy column, written by this script) beside a small
# volume's iso-surface: 0 steps forward, . crops by the energy, Y raises the
# iso-value and a side-button drag up raises it further, M gives the volume
# rendered directly the next transfer function (a time-step, a crop, value and
# transfer records, and the status lines); the
# heads equal the native replay, which loads the same step.
# Nothing here waits a fixed time for a picture: under TCG a frame takes 0.3 s
# to 8 s depending on the host's CPU model. tessera in the guest runs with
# TESSERA_LOG=debug and logs each frame on screen; the host waits for those
# lines, for the tour's start/stop lines and for the uinput device's ack of a
# gesture, with time-outs in frames (host_lib.sh: frames_s, wait_frame).
# After each gesture (all of it sent), the host copies rec.txt, renders the
# wall natively with `tessera render --replay-input` (all recorded
# transactions applied, then one frame) and waits until the screendump of every
# head equals its output's native image pixel for pixel (tolerance 0; the
# status line, the cursor and hidden objects are part of both pictures), and
# still does, the record unchanged, 3 frames later; a record that grew
# meanwhile is rendered again.
# Checks (PASS/FAIL): the wall comes up showing the start camera; each gesture
# changed the camera (or the status line / cursor / hidden set) and the 4 heads
# equal the native replay; the quit chord ends tessera with exit 0. (Replay at
# the recorded times is checked by tests/test_input.c, in less time.)
# Exits 0 when all pass; SKIPPED (exit 0, said in the last line) when qemu
# cannot be installed, never silently.
#
# Run from the repository root by `make test` after ./tessera is built. The
# guest (tests/vm/host_lib.sh: vm_guest) is the one vm_wall.sh and vm_cluster.sh
# boot too, in $TESSERA_VM_CACHE (default /tmp/tessera-vm-cache), built by the
# first of them. VM_KEEP=1 keeps the work folder.
set -u
cd "$(dirname "$0")/.." || exit 1
NAME=vm_input
W=$(mktemp -d /tmp/tessera-vm-input.XXXXXX)
. tests/vm/host_lib.sh

mkdir -p "$W/bin"
copy_tessera
vm_guest

cp configs/walls/vm_2x2.json "$W/wall.json"
cp tests/data/vm_spheres.json "$W/scene.json"
# the third run's assembly (make test builds build/gen-assembly; the same options give the same bytes)
GEN=${TESSERA_GEN_ASSEMBLY:-build/gen-assembly}
[ -x "$GEN" ] || make -s "$GEN" > "$W/gen.log" 2>&1
if ! "$GEN" --parts 10000 --triangles 2000000 -o "$W/asm.glb" > "$W/gen.log" 2>&1; then
    cat "$W/gen.log"
    echo "vm_input: FAIL: $GEN did not make the 10,000-part assembly"
    exit 1
fi

# the fourth run's particle series: 3 steps of 14^3 particles on a jittered grid, a
# kinetic energy c_ke per particle (a LAMMPS text dump each), coloured and croppable by it
mkdir -p "$W/steps"
for s in 0 1 2; do
    awk -v s=$s 'BEGIN {
        n = 14; printf "ITEM: TIMESTEP\n%d\nITEM: NUMBER OF ATOMS\n%d\n", 100 * s, n * n * n
        printf "ITEM: BOX BOUNDS pp pp pp\n0 %d\n0 %d\n0 %d\nITEM: ATOMS id type x y z c_ke\n", n, n, n
        id = 0
        for (z = 0; z < n; z++) for (y = 0; y < n; y++) for (x = 0; x < n; x++) {
            id++
            printf "%d 1 %.4f %.4f %.4f %.4f\n", id, x + 0.3 * sin(id + s), y + 0.3 * cos(2 * id + s), z + 0.1 * s,
                (x + y + z + 3 * s) % 12
        }
    }' > "$W/steps/step_$s.dump"
done
# and beside it a 16^3 8-bit volume of a ball (value 200 at the centre falling to 0), its
# iso-surface ray traced directly, the shell in front of it rendered directly (ct-bone over the
# samples' range: opacity from 71 up)
python3 -c '
import math, sys
sys.stdout.buffer.write(bytes(max(0, min(200, int(200 - 25 * math.sqrt((x - 7.5) ** 2 + (y - 7.5) ** 2 + (z - 7.5) ** 2))))
                              for z in range(16) for y in range(16) for x in range(16)))' > "$W/ball.raw"
printf 'file: ball.raw\ndims: 16 x 16 x 16\ntype: uint8\nspacing: 0.5 0.5 0.5\norigin: 17 3 3\n' > "$W/ball.txt"
cat > "$W/particles.json" <<'EOF'
{
  "camera": {"eye": [32, 22, 40], "look_at": [10, 6, 7], "fov_deg": 45},
  "ambient": [0.3, 0.3, 0.3],
  "particles": [{"files": "steps/step_*.dump", "radius": 0.4, "color_by": "c_ke",
                 "color_map": {"map": "viridis", "range": [0, 11]}, "crop": {"attribute": "c_ke"}}],
  "volumes": [{"file": "ball.txt", "iso": [{"value": 100, "color": [0.9, 0.3, 0.2]}],
               "dvr": {"transfer": "ct-bone", "step": 0.5}}]
}
EOF

# the guest (busybox sh in the share): the touchscreen, then tessera, then the
# steps the host drops in (cmd-N.sh, run in order; output cmd-N.log, status cmd-N.done)
cp tests/vm/guest_lib.sh "$W/"
# devcmd.sh FIFO LOG COMMAND: a uinput_touch device in the guest plays COMMAND; returns
# when it has played all of it (its "ok N" line), failing on its "err N"
cat > "$W/devcmd.sh" <<'EOF'
n0=$(grep -c '^ok \|^err ' "$2")
echo "$3" > "$1"
i=0
while [ "$(grep -c '^ok \|^err ' "$2")" -le "$n0" ]; do
    [ $i -lt 1200 ] || { echo "devcmd: no answer from $1 within 60 s"; exit 1; }
    sleep 0.05
    i=$((i + 1))
done
! tail -n 1 "$2" | grep '^err '
EOF
# the guest (busybox sh in the share): the touchscreen, then tessera, then the
# steps the host drops in (cmd-N.sh, run in order; output cmd-N.log, status cmd-N.done).
# TESSERA_LOG=debug: tessera logs each frame on screen, which the host waits for.
cat > "$W/guest.sh" <<'EOF'
. ./guest_lib.sh
export TESSERA_LOG=debug
echo 0 > /sys/class/graphics/fbcon/cursor_blink 2>/dev/null
[ -e /dev/dri/renderD128 ] && exec 3< /dev/dri/renderD128
mkfifo /tmp/touch.fifo
uinput_touch -n tessera-test-touch -s 640x480 -f /tmp/touch.fifo > touch.log 2>&1 3<&- &
tpid=$!
i=0
while ! grep -q ready touch.log 2>/dev/null && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
tessera run --wall wall.json --scene scene.json --threads 2 --idle-timeout 0 --record-input rec.txt \
    --map-input tessera-test-touch=Virtual-3 > tessera.log 2>&1 3<&- &
pid=$!
run_steps $pid 3600
stop_program $pid
# the kiosk left alone: its attract tour (the default orbit) after 8 s without input;
# no shadows (the checks are about the tour, not the picture: frames come sooner)
if [ ! -e done ]; then
    tessera run --wall wall.json --scene scene.json --threads 2 --no-shadows --idle-timeout "$(cat idle_s 2>/dev/null || echo 8)" \
        > tessera2.log 2>&1 3<&- &
    pid=$!
    run_steps $pid 3600 tour-done
    stop_program $pid tessera2.rc
fi
# a 10,000-part assembly, a touchscreen on Virtual-4
if [ ! -e done ]; then
    mkfifo /tmp/touch3.fifo
    uinput_touch -n tessera-test-touch3 -s 640x480 -f /tmp/touch3.fifo > touch3.log 2>&1 3<&- &
    i=0
    while ! grep -q ready touch3.log 2>/dev/null && [ $i -lt 600 ]; do sleep 0.1; i=$((i + 1)); done
    tessera run --wall wall.json --scene asm.glb --threads 2 --no-shadows --idle-timeout 0 --record-input rec3.txt \
        --map-input tessera-test-touch3=Virtual-4 > tessera3.log 2>&1 3<&- &
    pid=$!
    run_steps $pid 3600 asm-done
    stop_program $pid tessera3.rc
    echo quit > /tmp/touch3.fifo
fi
# a particle time series: keys only
if [ ! -e done ]; then
    tessera run --wall wall.json --scene particles.json --threads 2 --no-shadows --idle-timeout 0 \
        --record-input rec4.txt > tessera4.log 2>&1 3<&- &
    pid=$!
    run_steps $pid 3600
    stop_program $pid tessera4.rc
fi
alive $tpid && echo quit > /tmp/touch.fifo
wait $tpid
EOF
# (the time limit only ends a hung guest: every wait below has its own, in frames)
tests/vm/run-guest.sh -c "$GUEST" -s "$W" -q "$W/qmp.sock" -n 4 -r 640x480 -t 3000 -- 'sh guest.sh' \
    > "$W/guest.console" 2>&1 &
GPID=$!

N=0
step() { N=$((N + 1)); guest_step $N "$@"; } # 'COMMAND' [SECS]: the next guest step
# dev_cmd FIFO LOG 'COMMAND': a uinput device in the guest plays COMMAND (all of it)
dev_cmd() {
    step "sh devcmd.sh $1 $2 '$3'" 90 || bad "the guest's uinput device did not play '$3': $(cat "$W/cmd-$N.log" 2>/dev/null)"
}
touch_cmd() { dev_cmd /tmp/touch.fifo touch.log "$1"; }
qmp() { python3 tests/vm/qmp.py "$W/qmp.sock" "$@" > "$W/qmp.out" 2>&1; }
key_event() { # QCODE down|up
    qmp raw "{\"execute\": \"input-send-event\", \"arguments\": {\"events\": [{\"type\": \"key\", \"data\": {\"down\": $([ "$2" = down ] && echo true || echo false), \"key\": {\"type\": \"qcode\", \"data\": \"$1\"}}}]}}"
}
dump() { python3 tests/vm/qmp.py "$W/qmp.sock" screendump "$2" "$1" > "$W/dump.err" 2>&1; } # HEAD FILE

# heads_equal PREFIX REFPREFIX: screendumps of the 4 heads (PREFIX-H.ppm) each equal
# REFPREFIX-Virtual-(H+1).bmp; else 1 with the reason in $_why
heads_equal() {
    for _h in 0 1 2 3; do
        if ! dump $_h "$1-$_h.ppm" ||
            ! python3 tests/vm/qmp.py compare "$1-$_h.ppm" "$2-Virtual-$((_h + 1)).bmp" 0 > "$W/cmp.out" 2>&1; then
            _why="head $_h: $(cat "$W/cmp.out" "$W/dump.err" 2>/dev/null | tr '\n' ' ')"
            return 1
        fi
    done
}
# check NAME, after a gesture has been sent (all of it): wait until the 4 heads equal the
# native render of the transactions recorded so far (`render --replay-input`: camera,
# status line, cursor, hidden objects), and still equal it, the record unchanged, once 3
# more frames are on screen (so the gesture is over: none of its transactions came
# since). The record is read again whenever it grows (a gesture's last transactions reach
# it when the guest's input thread gets to them) and rendered anew. Fails when the
# gesture did nothing (recorded no transaction but cursor moves, and left the picture as
# the previous check's: a camera moved while only background is in view changes no pixel,
# so the record counts too), or the heads do not settle on the record's picture, within
# 16 frames' time (frames_s). With a second argument `may_do_nothing` a check of input
# that need not do anything (garbage) only asks that the heads settle on the replay.
# Which run check looks at: its log, record, scene and the native render's extra options.
CHECK_LOG=tessera.log CHECK_REC=rec.txt CHECK_SCENE=scene.json CHECK_OPTS=
K=0
check() {
    K=$((K + 1))
    _t=$(elapsed)
    _limit=$(frames_s 16)
    _rendered='' _why='the heads were never compared'
    while :; do
        if [ $(($(elapsed) - _t)) -ge "$_limit" ] || ! kill -0 "$GPID" 2>/dev/null; then
            if [ "$_why" = same ]; then
                bad "$1: neither a transaction (but cursor moves) nor the wall's picture came from it within $_limit s ($(($(wc -l < "$W/rec-$K.txt") - 1)) transactions recorded)"
            else
                bad "$1: within $_limit s the heads did not settle on the native replay of the recorded transactions: $_why"
            fi
            return
        fi
        _sum=$(cksum < "$W/$CHECK_REC" 2>/dev/null)
        if [ "$_sum" != "$_rendered" ]; then
            cp "$W/$CHECK_REC" "$W/rec-$K.txt" 2>/dev/null || : > "$W/rec-$K.txt"
            _rendered=$(cksum < "$W/rec-$K.txt")
            # shellcheck disable=SC2086 # CHECK_OPTS: options, split on purpose
            if ! "$W/bin/tessera" render --wall "$W/wall.json" --scene "$W/$CHECK_SCENE" --replay-input "$W/rec-$K.txt" \
                --threads 2 $CHECK_OPTS --out "$W/ref-$K.bmp" > "$W/native-$K.log" 2>&1; then
                bad "$1: the native replay failed: $(tail -n 3 "$W/native-$K.log")"
                return
            fi
        fi
        if [ "${2:-}" != may_do_nothing ] && [ "$K" -gt 1 ] && [ "$(grep -vc ' cursor ' "$W/rec-$K.txt")" = "$(grep -vc ' cursor ' "$W/rec-$((K - 1)).txt")" ] &&
            cmp -s "$W/ref-$K-Virtual-1.bmp" "$W/ref-$((K - 1))-Virtual-1.bmp" &&
            cmp -s "$W/ref-$K-Virtual-2.bmp" "$W/ref-$((K - 1))-Virtual-2.bmp" &&
            cmp -s "$W/ref-$K-Virtual-3.bmp" "$W/ref-$((K - 1))-Virtual-3.bmp" &&
            cmp -s "$W/ref-$K-Virtual-4.bmp" "$W/ref-$((K - 1))-Virtual-4.bmp"; then
            _why=same # the gesture's transactions have not reached the record (or the picture) yet
            sleep 0.5
            continue
        fi
        _f=$(last_frame $CHECK_LOG)
        if heads_equal "$W/dump-$K" "$W/ref-$K" && wait_frame $CHECK_LOG $((_f + 3)) &&
            [ "$(cksum < "$W/$CHECK_REC" 2>/dev/null)" = "$_rendered" ] && heads_equal "$W/dump-$K" "$W/ref-$K"; then
            ok "$1: the 4 heads equal the native replay of the recorded transactions ($(($(wc -l < "$W/rec-$K.txt") - 1)) so far; $(($(elapsed) - _t)) s)"
            return
        fi
        echo "$(elapsed) s, frame $_f: $_why" >> "$W/check-$K.log" # (VM_KEEP=1 keeps it)
        sleep 0.5
    done
}

# px_differ A B: how many pixels of two images differ
px_differ() { python3 tests/vm/qmp.py compare "$1" "$2" 0 2>&1 | sed -n 's/^\([0-9]*\) of .*/\1/p'; }
# heads_differ K1 K2: pixels that differ between the native replays of checks K1 and K2 on
# heads 1, 2 and 4 (head 3 shows the status line)
heads_differ() {
    _hd=0
    for _v in 1 2 4; do _hd=$((_hd + $(px_differ "$W/ref-$1-Virtual-$_v.bmp" "$W/ref-$2-Virtual-$_v.bmp") + 0)); done
    echo $_hd
}
# rec_last REGEX: the record's last line matching REGEX (of the current check's copy), without its time
rec_last() { grep -E "$1" "$W/rec-$K.txt" | tail -n 1 | cut -d' ' -f2-; }
# native NAME RECORD: the native render of RECORD (the current check's scene and options) as
# ref-NAME-Virtual-N.bmp
native() {
    # shellcheck disable=SC2086 # CHECK_OPTS: options, split on purpose
    "$W/bin/tessera" render --wall "$W/wall.json" --scene "$W/$CHECK_SCENE" --replay-input "$2" --threads 2 $CHECK_OPTS \
        --out "$W/ref-$1.bmp" > "$W/native-$1.log" 2>&1 || echo "native render of $2 failed: $(tail -n 1 "$W/native-$1.log")"
}
# The third run: a 10,000-part glTF assembly. Parts are picked by path, hidden, isolated and
# shown again by the tablet, the keyboard and the touchscreen (on Virtual-4). Four checks
# (the heads equal the native replay of the record; each ~4 of the guest's frames), two
# gestures in some, to keep the run short; what each recorded is read back (the path picked,
# the ranges hidden and isolated, the status lines, in order), and native renders of the
# record without the hide, and up to the isolate, show that those changed the picture.
assembly_run() {
    if ! log_wait tessera3.log "outputs up" "$(frames_s 30)" ||
        ! log_wait tessera3.log "added: 'tessera-test-touch3'" "$(frames_s 4)" ||
        ! wait_frame tessera3.log 2 8; then
        bad "assembly: the kiosk did not come up with the 10,000-part assembly: $(tail -n 3 "$W/tessera3.log" 2>/dev/null)"
        return
    fi
    echo "vm_input: the assembly is up after $(elapsed) s: $(grep -o 'scene asm.glb.*' "$W/tessera3.log" | head -n 1)"
    CHECK_LOG=tessera3.log CHECK_REC=rec3.txt CHECK_SCENE=asm.glb CHECK_OPTS=--no-shadows
    printf 'tessera-input-record 2\n' > "$W/rec-asm0.txt"
    native asm0 "$W/rec-asm0.txt" # the start: every part shown, no status line, no cursor

    # the tablet clicks a skin panel in Virtual-4 (pixel (360, 50) of that output: the wall's
    # 336 x 256 mm, Virtual-4's active area from (172, 132) mm at 4 px a mm), which picks it by
    # its path; H hides the part under the cursor: that one
    qmp mouse tablet
    qmp abs 25551 18496
    qmp click left
    qmp key h
    _fail0=$FAIL
    check "assembly: tablet click (pick a part), H (hide it)"
    [ $FAIL -eq $_fail0 ] || return
    _picked=$(rec_last ' status "picked part ' | sed -n 's/^status "picked part \(.*\) triangle [0-9]* at .*/\1/p')
    _hide=$(rec_last ' hide ')
    grep -v ' hide ' "$W/rec-$K.txt" > "$W/rec-asm1.txt"
    native asm1 "$W/rec-asm1.txt"
    _n=$(($(px_differ "$W/ref-asm1-Virtual-4.bmp" "$W/ref-$K-Virtual-4.bmp") + 0))
    if [ -z "$_picked" ]; then
        bad "assembly: the click picked no part: $(grep ' status ' "$W/rec-$K.txt" | head -n 1)"
        return
    elif [ "$(rec_last ' status ')" = "status \"hidden: $_picked\"" ] && [ -n "$_hide" ] && [ "$_n" -gt 100 ]; then
        ok "assembly: picked by path $_picked; H hid it ($_hide; $_n pixels of Virtual-4 changed)"
    else
        bad "assembly: picked $_picked; H: record '$_hide', '$(rec_last ' status ')', $_n pixels of Virtual-4 changed"
    fi

    # I isolates the selection (the part picked)
    _k1=$K
    qmp key i
    check "assembly: I (isolate the selection)"
    _iso=$(rec_last ' isolate ')
    _n=$(heads_differ $_k1 $K)
    if [ "isolate ${_hide#hide }" = "$_iso" ] && [ "$_n" -gt 2000 ] &&
        [ "$(rec_last ' status ')" = "status \"isolated: $_picked (1 instance)\"" ]; then
        ok "assembly: I isolated $_picked ($_iso; $_n pixels changed)"
    else
        bad "assembly: I: record '$_iso' (hidden: '$_hide'), '$(rec_last ' status ')', $_n pixels changed"
    fi

    # U shows all; then on the touchscreen a long press (1.5 s held still) selects and
    # isolates the part under the finger, and a two-finger tap (two fingers 80 px apart,
    # down and up together) shows all again: one check for the three (the picture at the
    # end: every part shown), the record read back in order, and the native render of the
    # record up to the long press's isolate against the start's
    qmp key u
    dev_cmd /tmp/touch3.fifo touch3.log "tap 450 66 1500"
    dev_cmd /tmp/touch3.fifo touch3.log "pinch 450 66 40 40 1"
    check "assembly: U (show all), touch long press (select and isolate), two-finger tap (show all)"
    _order=$(sed -n '1,/ isolate /d; / cursor /d; p' "$W/rec-$K.txt" | cut -d' ' -f2 | tr '\n' ' ')
    _iso=$(rec_last ' isolate ')
    _lp=$(grep ' status "isolated: ' "$W/rec-$K.txt" | tail -n 1 | cut -d' ' -f2-)
    awk -v n="$(grep -n ' isolate ' "$W/rec-$K.txt" | tail -n 1 | cut -d: -f1)" 'NR <= n' "$W/rec-$K.txt" > "$W/rec-asm2.txt"
    native asm2 "$W/rec-asm2.txt"
    _n=$(heads_differ asm0 asm2)
    if [ "$_order" = 'status show-all status isolate status show-all status ' ] && [ "$_iso" != "isolate ${_hide#hide }" ] &&
        echo "$_lp" | grep -q '^status "isolated: assembly/.* ([0-9]* instances*)"$' && [ "$_n" -gt 2000 ] &&
        [ "$(rec_last ' status ')" = 'status "all parts shown"' ] &&
        [ "$(px_differ "$W/ref-asm0-Virtual-1.bmp" "$W/ref-$K-Virtual-1.bmp")" = 0 ] &&
        [ "$(px_differ "$W/ref-asm0-Virtual-2.bmp" "$W/ref-$K-Virtual-2.bmp")" = 0 ]; then
        ok "assembly: U showed all; the long press $(echo "$_lp" | sed 's/^status "\(.*\)"$/\1/') ($_iso; $_n pixels of the replay changed); the two-finger tap showed all (heads 1 and 2 equal the start's)"
    else
        bad "assembly: U, long press, two-finger tap: after the I: '$_order'; '$_iso', '$_lp', $_n pixels of the replay changed; heads 1 and 2 against the start's: $(px_differ "$W/ref-asm0-Virtual-1.bmp" "$W/ref-$K-Virtual-1.bmp"), $(px_differ "$W/ref-asm0-Virtual-2.bmp" "$W/ref-$K-Virtual-2.bmp") pixels differ"
    fi

    # the inspection tools: C puts a cutting plane through the point under the tablet's cursor
    # (the skin panel clicked first), facing the eye; the middle button dragged up the wall
    # pushes it deeper into what it cuts; [ lowers every surface's opacity one step. One check
    # for the three (the heads equal the native replay: clipping, caps by parity and blending
    # are the same in the guest), the record read back: plane 0 set at least twice (placed,
    # then moved), an `opacity all` record, and the picture changed
    _k3=$K
    qmp abs 25551 18496
    qmp key c
    qmp click middle down
    for _i in 1 2 3; do qmp abs 25551 $((18496 - _i * 600)); sleep 0.2; done
    qmp click middle up
    qmp key bracket_left
    check "assembly: C (a cutting plane at the cursor), middle drag (push it), [ (opacity down)"
    _planes=$(grep -c ' clip-plane 0 1 ' "$W/rec-$K.txt")
    _op=$(rec_last ' opacity ')
    _n=$(heads_differ $_k3 $K)
    if [ "$_planes" -ge 2 ] && echo "$_op" | grep -q '^opacity all ' && [ "$_n" -gt 2000 ]; then
        ok "assembly: C placed cutting plane 0 and the drag moved it ($_planes clip-plane records), [ gave '$_op'; $_n pixels changed"
    else
        bad "assembly: C, middle drag, [: $_planes clip-plane records for plane 0, opacity record '$_op', $_n pixels changed"
    fi
}

# The fourth run: a particle time series. 0 steps forward (the next step is loaded and
# swapped in at a barrier; the native replay loads the same file), . crops by the energy;
# Y raises the ball's iso-value, a side-button drag up the wall raises it further;
# each check asks the heads to equal the native replay, and the record holds the
# time-step, crop and value records and their status lines.
particles_run() {
    if ! log_wait tessera4.log "outputs up" "$(frames_s 30)" || ! wait_frame tessera4.log 2 8; then
        bad "particles: the kiosk did not come up with the particle series: $(tail -n 3 "$W/tessera4.log" 2>/dev/null)"
        return
    fi
    CHECK_LOG=tessera4.log CHECK_REC=rec4.txt CHECK_SCENE=particles.json CHECK_OPTS=--no-shadows
    qmp key 0
    check "particles: 0 (the next time step)"
    _step=$(rec_last ' time-step ')
    if [ "$_step" = "time-step 1" ] && [ "$(rec_last ' status ')" = 'status "time step 2/3"' ]; then
        ok "particles: 0 stepped the series ($_step; the heads show the native replay's step)"
    else
        bad "particles: 0: record '$_step', '$(rec_last ' status ')'"
    fi
    _k1=$K
    qmp key dot
    check "particles: . (crop by the energy)"
    _crop=$(rec_last ' crop ')
    _n=$(heads_differ $_k1 $K)
    if echo "$_crop" | grep -q '^crop 0 1 1 ' && [ "$(rec_last ' status ')" = 'status "crop c_ke [0, 2.75]"' ] &&
        [ "$_n" -gt 2000 ]; then
        ok "particles: . cropped by c_ke ($_crop; $_n pixels changed)"
    else
        bad "particles: .: record '$_crop', '$(rec_last ' status ')', $_n pixels changed"
    fi
    _k2=$K
    qmp key y
    check "volume: Y (the iso-value up)"
    _value=$(rec_last ' value ')
    _n=$(heads_differ $_k2 $K)
    # one step of 1/50 of the samples' range (0 to 178: the grid misses the ball's centre) up from 100
    if echo "$_value" | grep -q '^value 1 1 ' && rec_last ' status ' | grep -q '^status "iso-value 103\.[0-9]*"$' &&
        [ "$_n" -gt 50 ]; then
        ok "volume: Y raised the iso-value ($_value; $_n pixels changed)"
    else
        bad "volume: Y: record '$_value', '$(rec_last ' status ')', $_n pixels changed"
    fi
    # the side button dragged up the wall (value-drag): the iso-value follows the pointer,
    # half its range per plane unit, so well above the 103.56 Y left it
    _k3=$K
    qmp abs 25551 20000
    qmp click side down
    for _i in 1 2 3; do qmp abs 25551 $((20000 - _i * 1500)); sleep 0.2; done
    qmp click side up
    check "volume: side-button drag up (value-drag)"
    _value=$(rec_last ' value ')
    _iso=$(rec_last ' status ' | sed -n 's/^status "iso-value \([0-9.]*\)"$/\1/p')
    _n=$(heads_differ $_k3 $K)
    if echo "$_value" | grep -q '^value 1 1 ' && [ -n "$_iso" ] &&
        awk -v v="$_iso" 'BEGIN { exit !(v > 110) }' && [ "$_n" -gt 50 ]; then
        ok "volume: the side-button drag raised the iso-value to $_iso ($_value; $_n pixels changed)"
    else
        bad "volume: side-button drag: record '$_value', '$(rec_last ' status ')', $_n pixels changed"
    fi
    # M: the volume rendered directly takes the next built-in transfer function with opacity
    # (ct-bone -> mri-soft) and the particles the next colour map; the heads equal the replay
    _k4=$K
    qmp key m
    check "volume: M (the next transfer function)"
    _tf=$(rec_last ' transfer ')
    _n=$(heads_differ $_k4 $K)
    if [ "$_tf" = "transfer mri-soft" ] && [ "$_n" -gt 50 ]; then
        ok "volume: M changed the transfer function ($_tf; $_n pixels changed)"
    else
        bad "volume: M: record '$_tf', '$(rec_last ' status ')', $_n pixels changed"
    fi
}

# the wall comes up (boot, tessera's start and first frames take ~25-40 s here under TCG;
# a slower CPU model's TCG several times that)
up=no
while [ "$(elapsed)" -lt 900 ] && kill -0 "$GPID" 2>/dev/null; do
    if grep -q "outputs up" "$W/tessera.log" 2>/dev/null &&
        grep -q "input: device .* added: 'tessera-test-touch'" "$W/tessera.log" &&
        [ "$(last_frame tessera.log)" -ge 0 ]; then
        up=yes
        break
    fi
    sleep 1
done
if [ $up = yes ]; then # the guest's frame time, over 3 frames (wait_frame sets FRAME_MS)
    wait_frame tessera.log $(($(last_frame tessera.log) + 3)) 100 || up=no
fi
if [ $up = no ]; then
    bad "tessera did not come up with the touchscreen and show frames within $(elapsed) s: $(tail -n 5 "$W/tessera.log" 2>/dev/null)"
else
    echo "vm_input: the wall is up after $(elapsed) s; a frame takes up to $FRAME_MS ms in the guest"
    : > "$W/rec-0.txt"
    check "start (no input yet)"

    # touch on Virtual-3 (bottom left of the wall; at the start camera the red
    # sphere covers its top right corner, the larger gold one is around (592, 180))
    touch_cmd "tap 590 35"
    check "touch: tap on Virtual-3 (pick; status line)"
    touch_cmd "doubletap 592 180"
    check "touch: double tap (fly to the point)"

    # tablet (absolute, the whole wall): the middle of the wall shows the gold
    # sphere now; click = pick -> status line, H hides it, U shows it again.
    # (Not at the very middle: that is behind the bezels, and so is a cursor there.)
    qmp mouse tablet
    qmp abs 15000 15000
    qmp click left
    check "tablet: click in the middle (pick; status line, cursor)"
    qmp key h
    check "keyboard: H (hide the object under the cursor)"
    qmp key u
    check "keyboard: U (unhide all)"

    touch_cmd "drag 200 200 420 260 8"
    check "touch: one-finger drag (orbit)"
    touch_cmd "pinch 320 240 60 140 6"
    check "touch: pinch (dolly)"

    # keyboard: Home flies back to the home view
    qmp key home
    check "keyboard: Home (the home view)"

    # mouse (relative; buttons and wheel go to the virtio mouse): the cursor
    # starts in the middle, over the red sphere
    qmp mouse mouse
    qmp click left down
    for _i in 1 2 3 4; do qmp rel 30 8; sleep 0.2; done
    qmp click left up
    check "mouse: left drag (orbit about the picked point)"
    qmp click wheel-up
    qmp click wheel-up
    check "mouse: wheel (dolly towards the cursor)"

    # tablet: right drag pans
    qmp mouse tablet
    qmp abs 20000 12000
    qmp click right down
    for _i in 1 2 3; do qmp abs $((20000 + _i * 1500)) $((12000 + _i * 800)); sleep 0.2; done
    qmp click right up
    check "tablet: right drag (pan)"

    # touchpad gestures: a uinput touchpad in the guest (100 x 60 mm, 40 units a mm; what
    # libinput needs to see a pinch, a swipe or a scroll: tests/vm/README.md)
    step "mkfifo /tmp/pad.fifo; uinput_touch -p -f /tmp/pad.fifo > pad.log 2>&1 3<&- & i=0; while ! grep -q ready pad.log && [ \$i -lt 600 ]; do sleep 0.1; i=\$((i + 1)); done"
    if log_wait tessera.log "added: 'tessera-test-touchpad'" "$(frames_s 4)" &&
        grep -q "input: device .* added: 'tessera-test-touchpad'.*gestures" "$W/tessera.log"; then
        dev_cmd /tmp/pad.fifo pad.log "pinch 2000 1200 300 1200 20"
        check "touchpad: pinch (dolly towards the cursor's point)"
        dev_cmd /tmp/pad.fifo pad.log "swipe3 600 1200 1600 1200 20"
        check "touchpad: three-finger swipe (pan)"
        dev_cmd /tmp/pad.fifo pad.log "pan2 2000 600 2000 1800 20"
        check "touchpad: two-finger scroll (the wheel: dolly)"
    else
        bad "touchpad: tessera did not add the touchpad with gestures: $(grep touchpad "$W/tessera.log" | tail -n 2)"
    fi
    step "echo quit > /tmp/pad.fifo"

    # a touchscreen unplugged and another plugged in while tessera runs
    n_added=$(log_count tessera.log "added: 'tessera-test-touch'")
    step "echo quit > /tmp/touch.fifo"
    if ! log_wait tessera.log "removed: 'tessera-test-touch'" "$(frames_s 4)"; then
        bad "hotplug: tessera did not report the touchscreen removed: $(tail -n 3 "$W/tessera.log")"
    fi
    step "mkfifo /tmp/touch2.fifo; uinput_touch -n tessera-test-touch -s 640x480 -f /tmp/touch2.fifo > touch2.log 2>&1 3<&- & i=0; while ! grep -q ready touch2.log && [ \$i -lt 600 ]; do sleep 0.1; i=\$((i + 1)); done"
    if log_wait tessera.log "added: 'tessera-test-touch'" "$(frames_s 4)" "$n_added"; then
        dev_cmd /tmp/touch2.fifo touch2.log "tap 120 120"
        check "touch: a touchscreen plugged in while running (tap: pick)"
        # a broken or hostile touchscreen: raw events out of every range, in bursts
        # (uinput_touch's garbage); the kiosk goes on, and what the events made of
        # the camera is what the record replays; then Home, for a known view again
        dev_cmd /tmp/touch2.fifo touch2.log "garbage 3000 7"
        check "touch: 3000 garbage events (the kiosk goes on; the heads equal the replay)" may_do_nothing
        qmp key home
        check "keyboard: Home after the garbage"
    else
        bad "hotplug: tessera did not pick up the new touchscreen: $(tail -n 3 "$W/tessera.log")"
    fi
    step "echo quit > /tmp/touch2.fifo"

    # keyboard: W held 0.6 s flies forward. Last before the VT switch, whose check flies
    # Home: how far it flies is how long the guest saw the key held, which a starved guest
    # stretches (seen: 2.4 s, into empty space, where the gestures after it changed nothing)
    key_event w down
    sleep 0.6 # how long the key is held (the gesture), not a wait for the picture
    key_event w up
    check "keyboard: W held (flight)"

    # a VT switch away and back: the seat revokes the input devices, tessera takes them back
    step "chvt 2"
    if ! log_wait tessera.log "input: devices released" "$(frames_s 4)"; then
        bad "VT switch: tessera did not release the input devices on chvt 2: $(tail -n 3 "$W/tessera.log")"
    fi
    step "chvt 1"
    if ! log_wait tessera.log "input: devices taken back" "$(frames_s 4)" ||
        ! log_wait tessera.log "back on our VT" "$(frames_s 4)"; then
        bad "VT switch: tessera did not take the wall and the input devices back on chvt 1: $(tail -n 3 "$W/tessera.log")"
    fi
    qmp key home
    check "keyboard after a VT switch away and back (Home)"

    # the second run's idle timeout: 8 s, or longer than the 6 frames (and the log's lag) the
    # "holds still" check below needs on a slow guest, so the tour cannot come back between
    # its two screendumps (seen: 4.8 s frames, the tour back before the second dump)
    IDLE_S=$((8 * FRAME_MS / 1000 + 6))
    [ $IDLE_S -ge 8 ] || IDLE_S=8
    echo $IDLE_S > "$W/idle_s"

    # the quit chord
    qmp key ctrl+alt+q
    if wait_for tessera.rc "$(frames_s 8)" && [ "$(cat "$W/tessera.rc")" = 0 ] && grep -q "input: quit" "$W/tessera.log"; then
        ok "the quit chord Ctrl+Alt+Q ended tessera with exit 0"
    else
        bad "the quit chord: tessera status '$(cat "$W/tessera.rc" 2>/dev/null)', log: $(tail -n 3 "$W/tessera.log" 2>/dev/null)"
    fi

    # The attract tour, in a second run with --idle-timeout 8 (and the default tour: an
    # orbit). Each check waits for the line tessera logs when it queues the tour's start
    # or stop, then for frames on screen. Frame i is shown while i + 1 renders and logged
    # on screen while i + 2 renders (after the barrier of i + 2, before that of i + 3): so
    # with frame F the newest on screen when the line is read, the change applies at the
    # barrier of frame F + 4 at the latest, and dumps taken once F + 4 and F + 6 are on
    # screen both show frames from after it.
    differ() { ! python3 tests/vm/qmp.py compare "$1" "$2" 0 > /dev/null 2>&1; }
    two_dumps() { # A B: screendumps of head 0 once frames F + 4 and F + 6 are on screen
        _f=$(last_frame tessera2.log)
        wait_frame tessera2.log $((_f + 4)) && dump 0 "$W/$1" && wait_frame tessera2.log $((_f + 6)) && dump 0 "$W/$2"
    }
    if ! log_wait tessera2.log "outputs up" "$(frames_s 30)" ||
        ! log_wait tessera2.log "the attract tour starts" "$(frames_s 8)"; then
        bad "the kiosk's second run did not come up playing its tour: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
    elif ! two_dumps tour-a.ppm tour-b.ppm; then
        bad "kiosk: frames did not come on screen in the second run: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
    elif ! differ "$W/tour-a.ppm" "$W/tour-b.ppm"; then
        bad "kiosk: head 0 showed the same picture two frames apart with nobody there (no tour)"
    else
        ok "kiosk: with nobody there the attract tour plays (head 0 changes from frame to frame)"
        qmp key shift
        t_key=$(elapsed)
        if ! log_wait tessera2.log "the attract tour stops" "$(frames_s 4)"; then
            bad "kiosk: a key did not stop the tour: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
        elif ! two_dumps tour-c.ppm tour-d.ppm; then
            bad "kiosk: frames stopped coming on screen after the key: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
        elif [ "$(log_count tessera2.log "the attract tour starts")" -gt 1 ]; then
            bad "kiosk: the test was too slow: the tour came back ($IDLE_S s idle timeout) before the second screendump"
        elif differ "$W/tour-c.ppm" "$W/tour-d.ppm"; then
            bad "kiosk: the picture still moves after a key press (the tour stopped)"
        else
            ok "kiosk: a key stops the tour (the picture holds still)"
        fi
        if ! log_wait tessera2.log "the attract tour starts" "$((IDLE_S + $(frames_s 4)))" 1; then
            bad "kiosk: the tour did not come back after the idle timeout: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
        elif [ $(($(elapsed) - t_key)) -lt $((IDLE_S - 1)) ]; then
            bad "kiosk: the tour came back $(($(elapsed) - t_key)) s after the key, before the $IDLE_S s idle timeout"
        elif ! two_dumps tour-e.ppm tour-f.ppm; then
            bad "kiosk: frames stopped coming on screen after the tour came back: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
        elif differ "$W/tour-e.ppm" "$W/tour-f.ppm" && differ "$W/tour-d.ppm" "$W/tour-f.ppm"; then
            ok "kiosk: $IDLE_S s after the last input the tour comes back (after $(($(elapsed) - t_key)) s; a frame takes up to $FRAME_MS ms)"
        else
            bad "kiosk: the tour came back but head 0 does not move"
        fi
    fi
    : > "$W/tour-done"
    assembly_run
    : > "$W/asm-done"
    particles_run
fi
: > "$W/done"
wait "$GPID"
GPID=

echo "vm_input: $PASS passed, $FAIL failed ($(elapsed) s)"
[ $FAIL -eq 0 ]
