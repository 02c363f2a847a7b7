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
#   VT switch chvt 2, chvt 1, then a key (the devices were revoked and taken back)
#   quit chord Ctrl+Alt+Q at the end.
# Then a second run, with --idle-timeout 8 and the default tour (an orbit of
# the home view): the picture moves with nobody there, holds still after a
# key, and moves again 8 s later.
# After each gesture, once rec.txt has stopped growing, the host copies it,
# renders the wall natively with `tessera render --replay-input` (all recorded
# transactions applied, then one frame) and waits until the screendump of every
# head equals its output's native image pixel for pixel (tolerance 0; the
# status line, the cursor and hidden objects are part of both pictures).
# Checks (PASS/FAIL): the wall comes up showing the start camera; each gesture
# changed the camera (or the status line / cursor / hidden set) and the 4 heads
# equal the native replay; the quit chord ends tessera with exit 0. (Replay at
# the recorded times is checked by tests/test_input.c, in less time.)
# Exits 0 when all pass; SKIPPED (exit 0, said in the last line) when qemu
# cannot be installed, never silently.
#
# Run from the repository root by `make test` after ./tessera is built. The
# guest lives in $TESSERA_VM_CACHE/vm-input (default /tmp/tessera-vm-cache),
# downloads are shared with vm_wall.sh. VM_KEEP=1 keeps the work folder.
set -u
cd "$(dirname "$0")/.." || exit 1
NAME=vm_input
W=$(mktemp -d /tmp/tessera-vm-input.XXXXXX)
. tests/vm/host_lib.sh

mkdir -p "$W/bin"
if ! gcc -std=c11 -O2 -Wall -Wextra -o "$W/bin/uinput_touch" tests/vm/uinput_touch.c > "$W/cc.log" 2>&1; then
    cat "$W/cc.log"
    echo "vm_input: FAIL: tests/vm/uinput_touch.c does not build"
    exit 1
fi
vm_build "$CACHE/vm-input" ./tessera "$W/bin/uinput_touch"

cp configs/walls/vm_2x2.json "$W/wall.json"
cp tests/data/vm_spheres.json "$W/scene.json"

# the guest (busybox sh in the share): the touchscreen, then tessera, then the
# steps the host drops in (cmd-N.sh, run in order; output cmd-N.log, status cmd-N.done)
cp tests/vm/guest_lib.sh "$W/"
cat > "$W/guest.sh" <<'EOF'
. ./guest_lib.sh
echo 0 > /sys/class/graphics/fbcon/cursor_blink 2>/dev/null
[ -e /dev/dri/renderD128 ] && exec 3< /dev/dri/renderD128
mkfifo /tmp/touch.fifo
uinput_touch -n tessera-test-touch -s 640x480 -f /tmp/touch.fifo > touch.log 2>&1 3<&- &
tpid=$!
i=0
while ! grep -q ready touch.log 2>/dev/null && [ $i -lt 100 ]; do sleep 0.1; i=$((i + 1)); done
tessera run --wall wall.json --scene scene.json --threads 2 --idle-timeout 0 --record-input rec.txt \
    --map-input tessera-test-touch=Virtual-3 > tessera.log 2>&1 3<&- &
pid=$!
run_steps $pid 300
stop_program $pid
# the kiosk left alone: its attract tour (the default orbit) after 8 s without input
if [ ! -e done ]; then
    tessera run --wall wall.json --scene scene.json --threads 2 --idle-timeout 8 > tessera2.log 2>&1 3<&- &
    pid=$!
    run_steps $pid 300
    stop_program $pid tessera2.rc
fi
alive $tpid && echo quit > /tmp/touch.fifo
wait $tpid
EOF
tests/vm/run-guest.sh -c "$CACHE/vm-input" -s "$W" -q "$W/qmp.sock" -n 4 -r 640x480 -t 500 -- 'sh guest.sh' \
    > "$W/guest.console" 2>&1 &
GPID=$!

N=0
step() { N=$((N + 1)); guest_step $N "$@"; } # 'COMMAND' [SECS]: the next guest step
touch_cmd() { step "echo '$1' > /tmp/touch.fifo"; }
qmp() { python3 tests/vm/qmp.py "$W/qmp.sock" "$@" > "$W/qmp.out" 2>&1; }
key_event() { # QCODE down|up
    qmp raw "{\"execute\": \"input-send-event\", \"arguments\": {\"events\": [{\"type\": \"key\", \"data\": {\"down\": $([ "$2" = down ] && echo true || echo false), \"key\": {\"type\": \"qcode\", \"data\": \"$1\"}}}]}}"
}
dump() { python3 tests/vm/qmp.py "$W/qmp.sock" screendump "$2" "$1" > "$W/dump.err" 2>&1; } # HEAD FILE

# settle: until rec.txt has not changed for 3 s (the guest shows a frame every 1-2 s)
settle() {
    _last='' _same=0 _n=0
    while [ $_same -lt 6 ] && [ $_n -lt 120 ] && kill -0 "$GPID" 2>/dev/null; do
        _sum=$(cksum < "$W/rec.txt" 2>/dev/null)
        if [ "$_sum" = "$_last" ]; then _same=$((_same + 1)); else _same=0; _last=$_sum; fi
        sleep 0.5
        _n=$((_n + 1))
    done
}
# check NAME: snapshot the record, render it natively, wait for the 4 heads to equal it
K=0
check() {
    K=$((K + 1))
    settle
    cp "$W/rec.txt" "$W/rec-$K.txt" 2>/dev/null || : > "$W/rec-$K.txt"
    if ! ./tessera render --wall "$W/wall.json" --scene "$W/scene.json" --replay-input "$W/rec-$K.txt" \
        --threads 2 --out "$W/ref-$K.bmp" > "$W/native-$K.log" 2>&1; then
        bad "$1: the native replay failed: $(tail -n 3 "$W/native-$K.log")"
        return
    fi
    if [ "$K" -gt 1 ] && cmp -s "$W/ref-$K-Virtual-1.bmp" "$W/ref-$((K - 1))-Virtual-1.bmp" &&
        cmp -s "$W/ref-$K-Virtual-2.bmp" "$W/ref-$((K - 1))-Virtual-2.bmp" &&
        cmp -s "$W/ref-$K-Virtual-3.bmp" "$W/ref-$((K - 1))-Virtual-3.bmp" &&
        cmp -s "$W/ref-$K-Virtual-4.bmp" "$W/ref-$((K - 1))-Virtual-4.bmp"; then
        bad "$1: the wall's picture did not change ($(($(wc -l < "$W/rec-$K.txt") - 1)) transactions recorded)"
        return
    fi
    _t=$(elapsed)
    while :; do
        _all=yes _why=
        for _h in 0 1 2 3; do
            if ! dump $_h "$W/dump-$K-$_h.ppm" ||
                ! python3 tests/vm/qmp.py compare "$W/dump-$K-$_h.ppm" "$W/ref-$K-Virtual-$((_h + 1)).bmp" 0 \
                    > "$W/cmp.out" 2>&1; then
                _all=no _why="head $_h: $(cat "$W/cmp.out" "$W/dump.err" 2>/dev/null | tr '\n' ' ')"
                break
            fi
        done
        if [ $_all = yes ]; then
            ok "$1: the 4 heads equal the native replay of the recorded transactions ($(($(wc -l < "$W/rec-$K.txt") - 1)) so far; $(($(elapsed) - _t)) s)"
            return
        fi
        if [ $(($(elapsed) - _t)) -ge 40 ] || ! kill -0 "$GPID" 2>/dev/null; then
            bad "$1: after 40 s the heads still differ from the native replay: $_why"
            return
        fi
        sleep 1
    done
}

# the wall comes up (boot, tessera's start and first frames take ~25-40 s under TCG)
up=no
while [ "$(elapsed)" -lt 240 ] && kill -0 "$GPID" 2>/dev/null; do
    if grep -q "outputs up" "$W/tessera.log" 2>/dev/null && grep -q "input: device .* added: 'tessera-test-touch'" "$W/tessera.log"; then
        up=yes
        break
    fi
    sleep 1
done
if [ $up = no ]; then
    bad "tessera did not come up with the touchscreen within 240 s: $(tail -n 5 "$W/tessera.log" 2>/dev/null)"
else
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

    # keyboard: Home flies back to the home view; W held 0.6 s flies forward
    qmp key home
    check "keyboard: Home (the home view)"
    key_event w down
    sleep 0.6
    key_event w up
    check "keyboard: W held (flight)"

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
    step "mkfifo /tmp/pad.fifo; uinput_touch -p -f /tmp/pad.fifo > pad.log 2>&1 3<&- & i=0; while ! grep -q ready pad.log && [ \$i -lt 100 ]; do sleep 0.1; i=\$((i + 1)); done; sleep 1"
    if grep -q "input: device .* added: 'tessera-test-touchpad'.*gestures" "$W/tessera.log"; then
        step "echo 'pinch 2000 1200 300 1200 20' > /tmp/pad.fifo"
        check "touchpad: pinch (dolly towards the cursor's point)"
        step "echo 'swipe3 600 1200 1600 1200 20' > /tmp/pad.fifo"
        check "touchpad: three-finger swipe (pan)"
        step "echo 'pan2 2000 600 2000 1800 20' > /tmp/pad.fifo"
        check "touchpad: two-finger scroll (the wheel: dolly)"
    else
        bad "touchpad: tessera did not add the touchpad with gestures: $(grep touchpad "$W/tessera.log" | tail -n 2)"
    fi
    step "echo quit > /tmp/pad.fifo"

    # a touchscreen unplugged and another plugged in while tessera runs
    step "echo quit > /tmp/touch.fifo; sleep 1"
    n_added=$(grep -c "input: device .* added: 'tessera-test-touch'" "$W/tessera.log")
    if ! grep -q "input: device .* removed: 'tessera-test-touch'" "$W/tessera.log"; then
        bad "hotplug: tessera did not report the touchscreen removed: $(tail -n 3 "$W/tessera.log")"
    fi
    step "mkfifo /tmp/touch2.fifo; uinput_touch -n tessera-test-touch -s 640x480 -f /tmp/touch2.fifo > touch2.log 2>&1 3<&- & i=0; while ! grep -q ready touch2.log && [ \$i -lt 100 ]; do sleep 0.1; i=\$((i + 1)); done; sleep 1"
    if [ "$(grep -c "input: device .* added: 'tessera-test-touch'" "$W/tessera.log")" -gt "$n_added" ]; then
        step "echo 'tap 120 120' > /tmp/touch2.fifo"
        check "touch: a touchscreen plugged in while running (tap: pick)"
    else
        bad "hotplug: tessera did not pick up the new touchscreen: $(tail -n 3 "$W/tessera.log")"
    fi
    step "echo quit > /tmp/touch2.fifo"

    # a VT switch away and back: the seat revokes the input devices, tessera takes them back
    step "chvt 2; sleep 2; chvt 1; sleep 2"
    qmp key home
    check "keyboard after a VT switch away and back (Home)"

    # the quit chord
    qmp key ctrl+alt+q
    if wait_for tessera.rc 60 && [ "$(cat "$W/tessera.rc")" = 0 ] && grep -q "input: quit" "$W/tessera.log"; then
        ok "the quit chord Ctrl+Alt+Q ended tessera with exit 0"
    else
        bad "the quit chord: tessera status '$(cat "$W/tessera.rc" 2>/dev/null)', log: $(tail -n 3 "$W/tessera.log" 2>/dev/null)"
    fi

    # the attract tour, in a second run with --idle-timeout 8 (and the default tour: an orbit)
    differ() { ! python3 tests/vm/qmp.py compare "$1" "$2" 0 > /dev/null 2>&1; }
    _n=0
    until grep -q "outputs up" "$W/tessera2.log" 2>/dev/null; do
        [ $_n -lt 90 ] && kill -0 "$GPID" 2>/dev/null || break
        sleep 1
        _n=$((_n + 1))
    done
    sleep 4
    if ! grep -q "outputs up" "$W/tessera2.log" 2>/dev/null; then
        bad "the kiosk's second run did not come up: $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
    elif dump 0 "$W/tour-a.ppm" && sleep 3 && dump 0 "$W/tour-b.ppm" && differ "$W/tour-a.ppm" "$W/tour-b.ppm"; then
        ok "kiosk: with nobody there the attract tour plays (head 0 changes over 3 s)"
        qmp key shift
        sleep 3
        dump 0 "$W/tour-c.ppm"
        sleep 3
        dump 0 "$W/tour-d.ppm"
        if ! differ "$W/tour-c.ppm" "$W/tour-d.ppm"; then
            ok "kiosk: a key stops the tour (the picture holds still)"
        else
            bad "kiosk: the picture still moves after a key press"
        fi
        sleep 7
        dump 0 "$W/tour-e.ppm"
        sleep 3
        dump 0 "$W/tour-f.ppm"
        if differ "$W/tour-e.ppm" "$W/tour-f.ppm" && differ "$W/tour-d.ppm" "$W/tour-f.ppm"; then
            ok "kiosk: 8 s after the last input the tour comes back"
        else
            bad "kiosk: the tour did not come back after the idle timeout"
        fi
    else
        bad "kiosk: head 0 did not change over 3 s with nobody there (no tour): $(tail -n 3 "$W/tessera2.log" 2>/dev/null)"
    fi
fi
: > "$W/done"
wait "$GPID"
GPID=

echo "vm_input: $PASS passed, $FAIL failed ($(elapsed) s)"
[ $FAIL -eq 0 ]
