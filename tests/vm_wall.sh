#!/bin/sh
# tests/vm_wall.sh - end-to-end: tessera drives a 2x2 wall (configs/walls/vm_2x2.json)
# on the 4 heads of a virtio-gpu in a qemu guest (tests/vm/), through DRM/KMS,
# playing a looping camera path. One guest boot for the whole scenario. Input
# is off (--input off): on a DRM wall it is on by default, and the kiosk would
# play the path as its attract tour, eased in from the start camera at a time
# that depends on the input thread; tests/vm_input.sh covers input.
#
# The animation: a scene of spheres without a floor (background pixels are
# cheap; under TCG the guest shows a new frame every 1-2 s, 3 s with a CPU hog
# beside it; a floor or the built-in scene make it 3-7 s) and an orbit of 8
# Catmull-Rom keys that loops every 4 s, played with --time fixed --rate 4:
# frame k shows time k/4 s, an exact binary fraction, so frame k+16 is bit for
# bit frame k and each output has K = 16 possible pictures. Frame 0 has the
# still camera of the earlier version of this test (which used the built-in
# scene). The host renders 2K frames natively (same binary; every ISA gives
# bit-identical images) as references.
#
# Checks, each printed as PASS/FAIL:
#   1. the native references: frame j+K equals frame j on every output (the
#      loop is exact) and the K frames of each output all differ;
#   2. the guest's tessera brings the 4 outputs up (atomic or legacy modeset);
#   3. from the first frame on, every screendump of every head equals, pixel for
#      pixel (tolerance 0), the native render of one frame of that output
#      (a torn or mixed picture fails; qmp.py match says which rows are which);
#   4. frames keep flipping: each head shows >= 3 distinct frames, and each
#      screendump shows the frame tessera logged as on screen around it (the
#      newest on screen before the dump .. the one after the newest after it;
#      pipeline frame f is loop frame f mod K);
#   5. hotplug: Virtual-4's connector is forced off in the guest and a HOTPLUG=1
#      event sent (see the comment at the step for why it is synthetic): tessera
#      reports the output gone, its CRTC is off, heads 0-2 go on showing frames;
#      forced on again: tessera brings it back and it shows frames again;
#   5b. VT switch (chvt 2, chvt 1): tessera lets go through the seat (head 0
#      shows the console), and on return all 4 heads show frames again;
#   6. SIGTERM ends tessera cleanly (exit 0);
#   7. `tessera outputs` after the run has the same card, connector (without
#      EDID) and CRTC lines as before it (the CRTCs were restored: modes,
#      framebuffer, routing).
#      The guest keeps /dev/dri/renderD128 open meanwhile: when the last file
#      of a DRM device closes, the kernel restores the fbdev console itself
#      (checked: a client that restores nothing, kms_fill, then leaves "fb 55"
#      as before; with the render node held it leaves "fb 0"), which would
#      hide a tessera that does not restore;
#   8. head 0 shows the same console picture after the run as before it: the
#      guest first writes a line to the console and hides the (blinking) cursor,
#      so the picture is steady and not all black;
#   9. the legacy modesetting path (TESSERA_DRM_NO_ATOMIC=1; run last, the atomic
#      one is checked above): the wall comes up with legacy modesetting, frames go
#      on screen (their page-flip events come back) and tessera exits 0.
# Exits 0 when all pass. When qemu cannot be installed (no apt, no network) it
# says so and exits 0 with SKIPPED in its last line: never silently.
#
# Guest protocol (files in the shared folder $W; the guest script is guest.sh):
#   guest: outputs-before.txt, then `console-before`; host: screendump of head 0,
#   then `console-before.done`; guest: starts tessera, then runs each
#   `cmd-N.sh` (N = 1, 2, ... in order) the host drops in, output to cmd-N.log,
#   exit status to `cmd-N.done`; host: `done`; guest: SIGTERM, tessera.rc,
#   outputs-after.txt, `console-after`; host: screendump, `console-after.done`;
#   guest: the legacy run's legacy.log and legacy.rc.
#   To add a step while tessera runs: `guest_step N 'COMMAND' [SECS]` below
#   (after the animation check, before `done`), then check $W/cmd-N.done / .log.
#
# Run from the repository root by `make test` (after ./tessera is built). Takes
# 29-54 s here (warm cache, 2 cores, TCG; 70 s with a CPU hog beside it), most
# of it before the first frame: boot 6 s, each tessera start in the guest ~9 s.
# Environment: TESSERA_VM_CACHE (default /tmp/tessera-vm-cache: downloads and the guest),
# VM_KEEP=1 keeps the work folder (screendumps, references, logs).
set -u
cd "$(dirname "$0")/.." || exit 1
NAME=vm_wall
W=$(mktemp -d /tmp/tessera-vm-wall.XXXXXX)
. tests/vm/host_lib.sh

K=16    # frames per loop: period 4 s x rate 4 Hz
RATE=4  # also in guest.sh's tessera run
MIN_FRAMES=3

mkdir -p "$W/bin"
copy_tessera
vm_guest

cp configs/walls/vm_2x2.json "$W/wall.json"
cp tests/data/vm_spheres.json "$W/scene.json"
cp tests/data/vm_loop.json "$W/loop.json"

# the guest (busybox sh in the share); the protocol is in the header
cp tests/vm/guest_lib.sh "$W/"
cat > "$W/guest.sh" <<'EOF'
. ./guest_lib.sh
# a steady console for the screendumps: no blinking, cursor hidden, a line of text
echo 0 > /sys/class/graphics/fbcon/cursor_blink 2>/dev/null
printf '\033[?25l\nvm_wall: the console before tessera runs\n' > /dev/tty0
# The kernel puts the fbdev console back by itself when the last file of the DRM
# device closes, which would hide whether tessera restored the CRTCs: keep one open.
if [ -e /dev/dri/renderD128 ]; then
    exec 3< /dev/dri/renderD128
    echo renderD128 > holder
fi
tessera outputs > outputs-before.txt 2>&1 3<&-
touch console-before
wait_for console-before.done 60
TESSERA_LOG=debug tessera run --wall wall.json --scene scene.json --path loop.json --time fixed --rate 4 --threads 2 \
    --input off > tessera.log 2>&1 3<&- &
pid=$!
run_steps $pid 3600
stop_program $pid
tessera outputs > outputs-after.txt 2>&1 3<&-
touch console-after
wait_for console-after.done 60
# the legacy modesetting path on the same card (TESSERA_DRM_NO_ATOMIC=1): a few frames
TESSERA_DRM_NO_ATOMIC=1 TESSERA_LOG=debug tessera run --wall wall.json --scene scene.json --path loop.json \
    --time fixed --rate 4 --threads 2 --input off --frames 6 > legacy.log 2>&1 3<&-
echo $? > legacy.rc
exec 3<&-
EOF
tests/vm/run-guest.sh -c "$GUEST" -s "$W" -q "$W/qmp.sock" -n 4 -r 640x480 -t 3000 -- 'sh guest.sh' \
    > "$W/guest.console" 2>&1 &
GPID=$!

qmp() { python3 tests/vm/qmp.py "$W/qmp.sock" "$@"; }
dump() { qmp screendump "$2" "$1" > "$W/dump.err" 2>&1; } # HEAD FILE

# the native references, while the guest boots: frames 0 .. 2K-1 of every output
mkdir "$W/ref"
if ! "$W/bin/tessera" render --wall "$W/wall.json" --scene "$W/scene.json" --path "$W/loop.json" --time fixed \
    --rate $RATE --frames $((2 * K)) --threads 2 --out "$W/ref/f_####.bmp" > "$W/native.log" 2>&1; then
    cat "$W/native.log"
    echo "vm_wall: FAIL: the native render failed"
    exit 1
fi
rm -f "$W"/ref/f_????.bmp # the stitched wall images
ref() { printf '%s/ref/f_%04d-Virtual-%d.bmp' "$W" "$2" $(($1 + 1)); } # HEAD FRAME
loop_bad='' same_bad=''
for h in 0 1 2 3; do
    refs=
    j=0
    while [ $j -lt $K ]; do
        cmp -s "$(ref $h $j)" "$(ref $h $((j + K)))" || loop_bad="$loop_bad Virtual-$((h + 1)):$j/$((j + K))"
        refs="$refs $(ref $h $j)"
        j=$((j + 1))
    done
    echo "$refs" > "$W/refs$h"
    # shellcheck disable=SC2086
    [ "$(cksum $refs | cut -d' ' -f1,2 | sort -u | wc -l)" -eq $K ] || same_bad="$same_bad Virtual-$((h + 1))"
done
if [ -z "$loop_bad$same_bad" ]; then
    ok "native references: frame j+$K equals frame j on every output (exact loop), $K distinct frames each"
else
    bad "native references:${loop_bad:+ frames differ although a loop apart:$loop_bad}${same_bad:+; outputs with repeated frames:$same_bad}"
fi
# match HEAD FILE: prints the frame index of that output FILE shows; 1 (reason in $W/match.out) if none
match() {
    # shellcheck disable=SC2046
    python3 tests/vm/qmp.py match "$2" $(cat "$W/refs$1") > "$W/match.out" 2>&1 || return 1
    cut -d' ' -f1 "$W/match.out"
}

# the console before tessera starts
console_before=no
if wait_for console-before 600 && dump 0 "$W/console-before.ppm"; then
    console_before=yes
fi
touch "$W/console-before.done"

# dump_at HEAD FILE: a screendump, and in FILE.frames the frames on screen before and after
# it (tessera's log): the dump shows one of those frames or the one after the second
dump_at() {
    _fb=$(last_frame tessera.log)
    dump "$1" "$2" || return 1
    echo "$_fb $(last_frame tessera.log)" > "$2.frames"
}

# the first frame (boot, `tessera outputs` and tessera's start take ~25 s here under TCG, a
# slower CPU model's TCG several times that); the guest's frame time over 3 frames
# (wait_frame sets FRAME_MS, which scales every time-out after this); then the heads
up=no waiting=0
while [ "$(elapsed)" -lt 900 ] && kill -0 "$GPID" 2>/dev/null && [ "$(last_frame tessera.log)" -lt 0 ]; do
    sleep 1
done
[ "$(last_frame tessera.log)" -ge 0 ] && wait_frame tessera.log $(($(last_frame tessera.log) + 3)) 100
t_frames=$(elapsed)
while [ $(($(elapsed) - t_frames)) -lt "$(frames_s 8)" ] && kill -0 "$GPID" 2>/dev/null &&
    [ "$(last_frame tessera.log)" -ge 0 ]; do
    up=yes
    for h in 0 1 2 3; do
        if ! dump_at $h "$W/first$h.ppm" || ! match $h "$W/first$h.ppm" > /dev/null; then
            up=no waiting=$h
            break
        fi
    done
    [ $up = yes ] && break
    sleep 1
done
t_up=$(elapsed)

# the animation: rounds of screendumps until each head showed MIN_FRAMES distinct pictures
# (matched afterwards, so that the host leaves the CPUs to the guest meanwhile)
rounds=0
if [ $up = yes ]; then
    mkdir "$W/obs"
    for h in 0 1 2 3; do
        cp "$W/first$h.ppm" "$W/obs/0-$h.ppm"
        cp "$W/first$h.ppm.frames" "$W/obs/0-$h.ppm.frames"
        cksum < "$W/first$h.ppm" > "$W/obs/seen$h"
    done
    rounds=1
    t_obs=$(elapsed)
    obs_limit=$(frames_s 12)
    while [ $(($(elapsed) - t_obs)) -lt "$obs_limit" ] && kill -0 "$GPID" 2>/dev/null; do
        for h in 0 1 2 3; do
            f="$W/obs/$rounds-$h.ppm"
            dump_at $h "$f" || break 2
            sum=$(cksum < "$f")
            if grep -qx "$sum" "$W/obs/seen$h"; then
                : > "$f.same" # an earlier dump of this head was identical
            else
                echo "$sum" >> "$W/obs/seen$h"
            fi
        done
        rounds=$((rounds + 1))
        least=$(for h in 0 1 2 3; do wc -l < "$W/obs/seen$h"; done | sort -n | head -n 1)
        [ "$least" -ge $MIN_FRAMES ] && break
        sleep 0.3
    done
    t_obs=$(($(elapsed) - t_obs))
fi

# heads_match SECS HEAD...: until each HEAD shows a frame of the animation; 1 when time ran out
heads_match() {
    _limit=$1
    shift
    _t=$(elapsed)
    while [ $(($(elapsed) - _t)) -lt "$_limit" ] && kill -0 "$GPID" 2>/dev/null; do
        _all=yes
        for _h in "$@"; do
            if ! dump "$_h" "$W/hm$_h.ppm" || ! match "$_h" "$W/hm$_h.ppm" > "$W/hm$_h.idx"; then
                _all=no
                break
            fi
        done
        [ $_all = yes ] && return 0
        sleep 1
    done
    return 1
}

# console_shown SECS: until head 0 shows no frame of the animation (the console took it)
console_shown() {
    _t=$(elapsed)
    while dump 0 "$W/vt2.ppm" && match 0 "$W/vt2.ppm" > /dev/null; do
        [ $(($(elapsed) - _t)) -lt "$1" ] && kill -0 "$GPID" 2>/dev/null || return 1
        sleep 0.5
    done
}

# Hotplug. virtio-gpu sends no uevent when a connector's forced status changes
# (its probe helper does not poll: checked with udevadm monitor), so the test
# makes the connector change with the sysfs status file and sends the event
# udev would: a synthetic "change" uevent of card0 whose SYNTH_ARG_HOTPLUG=1 a
# test-only udev rule turns into HOTPLUG=1. tessera sees exactly what udevd
# broadcasts for a real hotplug; only the kernel's event source is stood in for.
hotplug=no hotplug_why=
rule='ACTION=="change", SUBSYSTEM=="drm", ENV{SYNTH_ARG_HOTPLUG}=="1", ENV{HOTPLUG}="1"'
event='echo "change $(cat /proc/sys/kernel/random/uuid) HOTPLUG=1" > /sys/class/drm/card0/uevent'
if [ $up = yes ]; then
    if ! guest_step 1 "mkdir -p /run/udev/rules.d && echo '$rule' > /run/udev/rules.d/99-test-hotplug.rules && udevadm control --reload && echo off > /sys/class/drm/card0-Virtual-4/status && $event"; then
        hotplug_why="unplugging Virtual-4 in the guest failed: $(cat "$W/cmd-1.log" 2>/dev/null)"
    elif ! log_wait tessera.log "outputs[3] (Virtual-4) is gone" "$(frames_s 4)"; then
        hotplug_why="tessera did not report Virtual-4 gone: $(tail -n 3 "$W/tessera.log")"
    elif ! guest_step 2 'tessera outputs' "$(frames_s 4)" || grep -q -- '-> Virtual-4' "$W/cmd-2.log"; then
        hotplug_why="Virtual-4's CRTC still drives it after the unplug: $(grep CRTC "$W/cmd-2.log" | paste -sd ';')"
    elif ! heads_match "$(frames_s 8)" 0 1 2; then
        hotplug_why="heads 0-2 stopped showing frames of the animation after the unplug: $(cat "$W/match.out")"
    elif ! guest_step 3 "echo on > /sys/class/drm/card0-Virtual-4/status && $event"; then
        hotplug_why="plugging Virtual-4 back failed: $(cat "$W/cmd-3.log" 2>/dev/null)"
    elif ! log_wait tessera.log "outputs[3] (Virtual-4) is back" "$(frames_s 4)"; then
        hotplug_why="tessera did not bring Virtual-4 back: $(tail -n 3 "$W/tessera.log")"
    elif ! heads_match "$(frames_s 12)" 3 0; then
        hotplug_why="Virtual-4 is back but shows no frame of the animation: $(cat "$W/match.out")"
    else
        hotplug=yes
    fi
fi

# VT switch: the seat (libseat's builtin backend: the guest is root, no seatd)
# asks tessera to let go; the console takes the outputs; back on VT 1 the wall
# is lit again.
vt=no vt_why=
if [ $up = yes ] && [ $hotplug = yes ]; then
    if ! guest_step 4 'chvt 2 && cat /sys/class/tty/tty0/active'; then
        vt_why="chvt 2 failed: $(cat "$W/cmd-4.log" 2>/dev/null)"
    elif ! log_wait tessera.log "switched away from our VT" "$(frames_s 4)"; then
        vt_why="tessera did not let go on the VT switch: $(tail -n 3 "$W/tessera.log")"
    elif ! console_shown "$(frames_s 2)"; then
        vt_why="head 0 still shows the wall $(frames_s 2) s after the switch to VT 2"
    elif ! guest_step 5 'chvt 1 && cat /sys/class/tty/tty0/active'; then
        vt_why="chvt 1 failed: $(cat "$W/cmd-5.log" 2>/dev/null)"
    elif ! log_wait tessera.log "back on our VT" "$(frames_s 4)"; then
        vt_why="tessera did not come back with VT 1: $(tail -n 3 "$W/tessera.log")"
    elif ! heads_match "$(frames_s 12)" 0 1 2 3; then
        vt_why="after the return to VT 1 the heads show no frames of the animation: $(cat "$W/match.out")"
    else
        vt=yes
    fi
fi

# stop tessera; match the screendumps while the guest shuts it down
touch "$W/done"
mismatch=
[ $up = yes ] && for h in 0 1 2 3; do
    last=''
    : > "$W/seq$h"
    r=0
    while [ $r -lt $rounds ]; do
        f="$W/obs/$r-$h.ppm"
        [ -e "$f" ] || break
        if [ -e "$f.same" ] && [ -n "$last" ] && cmp -s "$f" "$W/obs/$((r - 1))-$h.ppm"; then
            idx=$last # the same picture as the dump before
        elif idx=$(match $h "$f"); then
            :
        else
            mismatch="head $h, screendump $r: $(cat "$W/match.out")"
            break 2
        fi
        echo "$idx $(cat "$f.frames")" >> "$W/seq$h"
        last=$idx
        r=$((r + 1))
    done
done
console_after=no
if wait_for console-after 600 && dump 0 "$W/console-after.ppm"; then
    console_after=yes
fi
touch "$W/console-after.done"
wait "$GPID"
guest_status=$?
GPID=

# ---- the checks
if grep -q "4 outputs up" "$W/tessera.log" 2>/dev/null; then
    ok "4 outputs up ($(sed -n 's/.*(\(.*\) modesetting).*/\1/p' "$W/tessera.log") modesetting)"
else
    bad "the outputs did not come up: $(tail -n 5 "$W/tessera.log" 2>/dev/null)"
fi
dumps=$(find "$W/obs" -name '*.ppm' 2>/dev/null | wc -l)
if [ $up = no ]; then
    bad "the heads never all showed a frame of the animation within $t_up s (VM_KEEP=1 keeps the screendumps); head $waiting: $(cat "$W/match.out" 2>/dev/null) $(cat "$W/dump.err" 2>/dev/null)"
elif [ -n "$mismatch" ]; then
    bad "a screendump equals no native frame of its output (VM_KEEP=1 keeps them): $mismatch"
else
    ok "all $dumps screendumps of the 4 heads ($rounds rounds) equal native renders of animation frames pixel for pixel (first frame up after $t_up s)"
fi
if [ $up = yes ] && [ -z "$mismatch" ]; then
    # per head: distinct frames, and each dump shows the frame tessera said was on screen
    # (frame f of the pipeline is frame f mod K of the loop: fixed-rate time): one from the
    # newest on screen before the dump to the one after the newest on screen after it
    flips=$(for h in 0 1 2 3; do
        awk -v K=$K -v h=$h -v min=$MIN_FRAMES '{
            if (!($1 in seen)) { seen[$1] = 1; n++ }
            ok = 0
            for (f = $2; f <= $3 + 1 && !ok; f++) ok = f >= 0 && f % K == $1
            if (!ok) wrong = wrong " " $1 " (on screen " $2 ".." $3 ")"
            frames = frames " " $1; last = $3
        } END {
            printf "%s head %d: frames%s: %d distinct, up to frame %d%s\n", (n >= min && wrong == "" ? "ok" : "bad"), h,
                frames, n, last, wrong == "" ? "" : ", not what tessera said was on screen:" wrong
        }' "$W/seq$h"
    done)
    rate=$(sed -n 's/.*: \([0-9.]*\) frames\/s.*/\1/p' "$W/tessera.log" | tail -n 1)
    summary=$(echo "$flips" | sed 's/^[a-z]* //' | paste -sd ';' | sed 's/;/; /g')
    if echo "$flips" | grep -q '^bad'; then
        bad "frames did not keep flipping ($MIN_FRAMES distinct per head needed, each the frame said to be on screen; in $t_obs s): $summary"
    else
        ok "frames keep flipping, each dump the frame tessera said was on screen (observed for $t_obs s, guest ${rate:-?} frames/s): $summary"
    fi
else
    bad "frames keep flipping: not checked (${mismatch:+a screendump matched no frame}${mismatch:-the animation never came up})"
fi
if [ $hotplug = yes ]; then
    ok "hotplug: Virtual-4 unplugged -> reported gone, its CRTC off, heads 0-2 go on; plugged back -> lit again and showing frames of the animation"
else
    bad "hotplug: ${hotplug_why:-not tried (the animation never came up)}"
fi
if [ $vt = yes ]; then
    ok "VT switch: on chvt 2 tessera let go (head 0 shows the console), on chvt 1 all 4 heads show frames of the animation again"
else
    bad "VT switch: ${vt_why:-not tried (an earlier step failed)}"
fi
rc=$(cat "$W/tessera.rc" 2>/dev/null || echo none)
if [ "$rc" = 0 ] && [ "$guest_status" = 0 ]; then
    ok "SIGTERM ended tessera with exit 0"
else
    bad "tessera exit status '$rc' after SIGTERM (guest status $guest_status)"
    tail -n 20 "$W/tessera.log" "$W/guest.console" 2>/dev/null
fi
# card, connector and CRTC lines (not the mode lists; not the EDID either: the
# forced re-plug of the hotplug step leaves Virtual-4 without its EDID blob)
grep -v '^    ' "$W/outputs-before.txt" | sed 's/, edid {[^}]*}//' > "$W/outputs-before.state" 2>/dev/null
grep -v '^    ' "$W/outputs-after.txt" | sed 's/, edid {[^}]*}//' > "$W/outputs-after.state" 2>/dev/null
if ! grep -q '^  CRTC ' "$W/outputs-before.state" 2>/dev/null; then
    bad "no CRTC lines in 'tessera outputs' before the run:"
    cat "$W/outputs-before.txt" 2>/dev/null
elif cmp -s "$W/outputs-before.state" "$W/outputs-after.state"; then
    held=$(cat "$W/holder" 2>/dev/null || echo "nothing: the kernel's own console restore on last close may hide tessera's")
    ok "CRTCs and connectors as before the run (DRM device held open by $held): $(grep '^  CRTC ' "$W/outputs-after.state" | sed 's/^  //' | paste -sd ';' | sed 's/;/; /g')"
else
    bad "'tessera outputs' differs after the run (card, connector and CRTC lines); before:"
    cat "$W/outputs-before.state"
    echo "vm_wall: after:"
    cat "$W/outputs-after.state" 2>/dev/null || echo "(none)"
fi
if [ $console_before = yes ] && python3 tests/vm/qmp.py solid "$W/console-before.ppm" 000000 > /dev/null 2>&1; then
    bad "head 0's console before the run is all black: the text the guest wrote to /dev/tty0 is missing"
elif [ $console_before = yes ] && [ $console_after = yes ] &&
    python3 tests/vm/qmp.py compare "$W/console-before.ppm" "$W/console-after.ppm" 0 > "$W/console.cmp" 2>&1; then
    ok "head 0 shows the console as before the run ($(python3 tests/vm/qmp.py colors "$W/console-after.ppm" 2))"
else
    bad "head 0's console after the run (screendumps before: $console_before, after: $console_after): $(cat "$W/console.cmp" 2>/dev/null)"
fi
legacy_rc=$(cat "$W/legacy.rc" 2>/dev/null || echo none)
legacy_up=$(grep -o '[0-9]* outputs up ([a-z]* modesetting)' "$W/legacy.log" 2>/dev/null)
if [ "$legacy_rc" = 0 ] && [ "$legacy_up" = "4 outputs up (legacy modesetting)" ] && [ "$(last_frame legacy.log)" -ge 3 ]; then
    ok "legacy modesetting (TESSERA_DRM_NO_ATOMIC=1): $legacy_up, frames on screen up to frame $(last_frame legacy.log), exit 0"
else
    bad "legacy modesetting (TESSERA_DRM_NO_ATOMIC=1): exit status '$legacy_rc', '${legacy_up:-no outputs up}', last frame on screen $(last_frame legacy.log)"
    tail -n 20 "$W/legacy.log" 2>/dev/null
fi
echo "vm_wall: $PASS passed, $FAIL failed ($(elapsed) s)"
[ $FAIL -eq 0 ]
