#!/usr/bin/env bash
# tests/vm/input_smoke.sh CACHE
#
# Self-test of the input side of the VM harness: libinput (udev backend, seat0)
# in the guest sees what the host sends over QMP and what a uinput touchscreen
# and a uinput touchpad made in the guest send. One boot (~30 s in all here):
#   1. builds tests/vm/uinput_touch.c and tests/vm/input_probe.c and a guest
#      with them (in $VM_OUT, default CACHE/input; downloads stay in CACHE)
#   2. boots 2 heads at 640x480 with a second virtio tablet bound to head 1
#      (serial=head1); in the guest input_probe logs every libinput device and
#      event to probe.log in the share (transform 640x480), uinput_touch makes
#      the touchscreen "tessera-test-touch" (640x480: coordinates are pixels)
#      and, with -p, the touchpad "tessera-test-touchpad" (a clickpad of
#      100 x 60 mm, 4000x2400 units)
#   3. host, over QMP (qmp.py expect: send, then wait for the probe's line, so
#      each step also measures QMP -> guest kernel -> libinput -> share file):
#      key a, key shift+b, rel 20 10, clicks (default routing, then after
#      `qmp.py mouse mouse`), absolute positions on the default tablet and on
#      head 1's, a click on head 1
#   4. guest (steps the host drops in): uinput_touch tap, drag and pinch on
#      the touchscreen; on the touchpad a pinch out and in, three-finger
#      swipes right and left, two-finger drags down and up, a one-finger drag
#   5. checks probe.log: devices and capabilities, key codes, unaccelerated
#      motion, buttons and the device that got them, transformed absolute
#      coordinates, touch slots, coordinates and frames, the touchpad's
#      gestures (PINCH begin/update/end and its scale, SWIPE and its direction,
#      POINTER_SCROLL_FINGER and its sign, POINTER_MOTION), the removal of
#      both; run-guest's status; no qemu left
# Prints PASS/FAIL lines, the latencies, and "N passed, M failed"; exit status
# 0 only if nothing failed. VM_KEEP=1 keeps the work folder (probe.log, logs).
set -uo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
[ $# -eq 1 ] || { sed -n '2,24p' "$0" >&2; exit 2; }
mkdir -p "$1" || exit 2
CACHE=$(cd "$1" && pwd)
GUEST=${VM_OUT:-$CACHE/input}
QMPY=(python3 "$HERE/qmp.py")

PASS=0 FAIL=0
ok() { echo "PASS: $*"; PASS=$((PASS + 1)); }
bad() { echo "FAIL: $*"; FAIL=$((FAIL + 1)); }
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }
T0=$(now)

W=$(mktemp -d /tmp/vm-input.XXXXXX) # short: the QMP socket lives in it
S=$W/share
mkdir -p "$S" "$W/bin"
GPID=
# shellcheck disable=SC2317  # (called through the trap)
finish() {
  if [ -n "$GPID" ] && kill -0 "$GPID" 2>/dev/null; then
    kill -TERM "$GPID" 2>/dev/null # run-guest.sh stops its qemu
    wait "$GPID" 2>/dev/null
  fi
  if [ "${VM_KEEP:-}" = 1 ]; then echo "input_smoke: kept $W"; else rm -rf "$W"; fi
}
trap finish EXIT
trap 'exit 130' INT; trap 'exit 143' TERM
summary() {
  echo "input_smoke: total $(since "$T0") s"
  echo "$PASS passed, $FAIL failed"
  [ "$FAIL" = 0 ]
  exit
}

# ---- 1. the tools and the guest ---------------------------------------------
CFLAGS=(-std=c11 -O2 -Wall -Wextra -Werror)
if ! pkg-config --exists libinput libudev 2>/dev/null; then
  bad "libinput/libudev development files missing (apt-get install libinput-dev libudev-dev)"
  summary
fi
# shellcheck disable=SC2046
if gcc "${CFLAGS[@]}" -o "$W/bin/uinput_touch" "$HERE/uinput_touch.c" 2>"$W/cc.log" &&
  gcc "${CFLAGS[@]}" -o "$W/bin/input_probe" "$HERE/input_probe.c" \
    $(pkg-config --cflags --libs libinput libudev) 2>>"$W/cc.log"; then
  ok "uinput_touch and input_probe build (-Wall -Wextra -Werror)"
else
  bad "the tools do not build:"; cat "$W/cc.log"; summary
fi
T=$(now)
if VM_OUT=$GUEST "$HERE/build-guest.sh" "$CACHE" "$W/bin/uinput_touch" "$W/bin/input_probe" \
  >"$W/build.log" 2>&1; then
  ok "build-guest.sh ($(since "$T") s): $(tail -n 1 "$W/build.log")"
else
  bad "build-guest.sh failed:"; cat "$W/build.log"; summary
fi

# ---- 2. the guest's side -----------------------------------------------------
# touch.sh CMD...: each CMD to uinput_touch through its FIFO; waits for its
# "ok N" (exit 1 on "err N" or after 10 s). The touchscreen's FIFO and log by
# default; the touchpad's with FIFO=/tmp/pad.fifo LOG=pad.log
cat >"$S/touch.sh" <<'EOF'
fifo=${FIFO:-/tmp/touch.fifo} log=${LOG:-touch.log}
for c in "$@"; do
  n=$(($(grep -cE '^(ok|err) ' "$log") + 1))
  echo "$c" > "$fifo"
  i=0
  until grep -qE "^(ok|err) $n(:|\$)" "$log"; do
    [ $i -lt 100 ] || { echo "touch.sh: no answer to '$c'"; exit 1; }
    sleep 0.1; i=$((i + 1))
  done
  if grep -q "^err $n:" "$log"; then grep "^err $n:" "$log"; exit 1; fi
done
EOF
cat >"$S/guest.sh" <<'EOF'
# wait_for PATTERN FILE SECS (grep -E)
wait_for() {
  i=0
  until grep -qE "$1" "$2" 2>/dev/null; do
    [ $i -lt $(($3 * 10)) ] || { echo "guest: no '$1' in $2 after $3 s"; return 1; }
    sleep 0.1; i=$((i + 1))
  done
}
input_probe -t 110 -s 640x480 > probe.log 2>&1 &
probe=$!
wait_for '^probe: ready' probe.log 30 || exit 1
uinput_touch -f /tmp/touch.fifo -n tessera-test-touch -s 640x480 > touch.log 2>&1 &
wait_for '^uinput_touch: ready' touch.log 10 || exit 1
wait_for '^added .*"tessera-test-touch"' probe.log 10 || exit 1
uinput_touch -p -f /tmp/pad.fifo > pad.log 2>&1 &
wait_for '^uinput_touch: ready' pad.log 10 || exit 1
wait_for '^added .*"tessera-test-touchpad"' probe.log 10 || exit 1
touch ready
# the host's steps: cmd-N.sh -> cmd-N.log, status in cmd-N.done
n=1 i=0
while [ ! -e done ] && [ $i -lt 1000 ]; do
  if [ -e cmd-$n.sh ]; then
    sh cmd-$n.sh > cmd-$n.log 2>&1
    echo $? > cmd-$n.tmp && mv cmd-$n.tmp cmd-$n.done
    n=$((n + 1))
  else
    sleep 0.1; i=$((i + 1))
  fi
done
sh touch.sh quit
FIFO=/tmp/pad.fifo LOG=pad.log sh touch.sh quit
wait_for '^removed .*"tessera-test-touch"' probe.log 10 &&
  wait_for '^removed .*"tessera-test-touchpad"' probe.log 10
rc=$?
kill $probe
wait
exit $rc
EOF

TABLET1="virtio-tablet-pci,id=tablet1,display=gpu0,head=1,serial=head1"
T=$(now)
"$HERE/run-guest.sh" -c "$GUEST" -s "$S" -q "$W/qmp.sock" -n 2 -r 640x480 -t 150 \
  -x "-device $TABLET1" -l "$W/console.log" -- sh guest.sh >/dev/null 2>"$W/run-guest.err" &
GPID=$!

wait_file() { # FILE SECS: until FILE exists, the guest is gone, or SECS passed
  local end=$((SECONDS + $2))
  while [ ! -e "$1" ]; do
    kill -0 "$GPID" 2>/dev/null || return 1
    [ "$SECONDS" -lt "$end" ] || return 1
    sleep 0.1
  done
}
STEP=0
guest_step() { # COMMAND: the guest runs it (sh); 0 if it exited 0
  STEP=$((STEP + 1))
  printf '%s\n' "$1" >"$S/cmd-$STEP.tmp" && mv "$S/cmd-$STEP.tmp" "$S/cmd-$STEP.sh"
  wait_file "$S/cmd-$STEP.done" 30 && [ "$(cat "$S/cmd-$STEP.done")" = 0 ]
}
P=$S/probe.log
Q=(timeout 30 "${QMPY[@]}" "$W/qmp.sock")
# send REGEX CMD...: QMP command, then wait (5 s) for its line in probe.log;
# the latency (ms) goes to LAT[label] via the caller, the line to $W/line
send() {
  local re=$1 out
  shift
  if out=$("${Q[@]}" expect "$P" "$re" 5 "$@"); then
    echo "${out#* }" >"$W/line"
    LAST_MS=${out%% *}
    return 0
  fi
  LAST_MS=
  return 1
}
LATS=''
lat() { LATS="$LATS${LATS:+, }$1 ${LAST_MS:-?} ms"; }
has() { grep -qE "$1" "$P"; } # REGEX: a line of probe.log matches
node_of() { # REGEX of an "added" line -> its event node (eventN)
  sed -nE "/^added $1/{s/^added (event[0-9]+) .*/\\1/p;q}" "$P"
}

if wait_file "$S/ready" 120; then
  ok "guest up, input_probe ready and the touchscreen and touchpad added ($(since "$T") s after start)"
else
  bad "the guest never got ready (no ready marker): $(tail -n 3 "$P" "$S/touch.log" "$S/pad.log" 2>/dev/null | tr '\n' ' ')"
  tail -n 30 "$W/console.log"
  summary
fi

# ---- 3. devices --------------------------------------------------------------
KBD=$(node_of '[a-z0-9]+ "QEMU Virtio Keyboard" caps=keyboard ')
MOUSE=$(node_of '[a-z0-9]+ "QEMU Virtio Mouse" caps=pointer ')
TAB0=$(grep -E '^added [a-z0-9]+ "QEMU Virtio Tablet" caps=pointer ' "$P" | grep -v ' uniq=' | head -n 1 | cut -d' ' -f2)
TAB1=$(node_of '[a-z0-9]+ "QEMU Virtio Tablet" caps=pointer .* uniq=head1$')
TOUCH=$(node_of '[a-z0-9]+ "tessera-test-touch" caps=touch touchscreen=yes ')
TNODE=$(sed -n 's|^uinput_touch: ready /dev/input/||p' "$S/touch.log")
if [ -n "$KBD" ] && [ -n "$MOUSE" ] && [ -n "$TAB0" ] && [ -n "$TAB1" ] && [ -n "$TOUCH" ] &&
  [ "$TOUCH" = "$TNODE" ]; then
  ok "libinput devices: keyboard $KBD, mouse $MOUSE (pointer), tablets $TAB0 and $TAB1 (uniq=head1) as pointers (not tablet tools), touchscreen $TOUCH (touch, ID_INPUT_TOUCHSCREEN; uinput_touch said $TNODE)"
else
  bad "libinput devices (keyboard '$KBD' mouse '$MOUSE' tablets '$TAB0' '$TAB1' touch '$TOUCH' / uinput '$TNODE'):"
  grep '^added' "$P"
fi
# the touchpad: a touchpad to udev, pointer + gesture to libinput, 100 x 60 mm,
# two-finger scrolling, no tapping (it has a button), areas of a clickpad
PAD=$(node_of '[a-z0-9]+ "tessera-test-touchpad" caps=pointer,gesture touchscreen=no udev=[A-Z_,]*ID_INPUT_TOUCHPAD')
PNODE=$(sed -n 's|^uinput_touch: ready /dev/input/||p' "$S/pad.log")
pad_line=$(grep -E '^added [a-z0-9]+ "tessera-test-touchpad"' "$P")
if [ -n "$PAD" ] && [ "$PAD" = "$PNODE" ] && [[ $pad_line == *" size=100.0x60.0mm tp=tap:off/"*",scroll:2fg,click:areas,"* ]]; then
  ok "touchpad $PAD: caps=pointer,gesture, ID_INPUT_TOUCHPAD, ${pad_line##* size=}"
else
  bad "touchpad: expected caps=pointer,gesture, ID_INPUT_TOUCHPAD, 100x60 mm, 2fg scrolling, click areas on $PNODE; got: ${pad_line:-no device}"
fi

# ---- 4. QMP input --------------------------------------------------------------
if send "^$KBD KEYBOARD_KEY key=30 released" key a && lat "key a" &&
  has "^$KBD KEYBOARD_KEY key=30 pressed seat_count=1 "; then
  ok "key a: KEY_A (30) pressed and released on the virtio keyboard"
else
  bad "key a: no KEY_A press and release on $KBD"
fi
if send "^$KBD KEYBOARD_KEY key=42 released" key shift+b && sleep 0.2; then
  t42=$(sed -nE "s/^$KBD KEYBOARD_KEY key=42 pressed .* t=([0-9.]+) .*/\\1/p" "$P")
  t48=$(sed -nE "s/^$KBD KEYBOARD_KEY key=48 pressed .* t=([0-9.]+) .*/\\1/p" "$P")
  r42=$(sed -nE "s/^$KBD KEYBOARD_KEY key=42 released .* t=([0-9.]+) .*/\\1/p" "$P")
  r48=$(sed -nE "s/^$KBD KEYBOARD_KEY key=48 released .* t=([0-9.]+) .*/\\1/p" "$P")
  if [ -n "$t42" ] && [ "$t42" = "$t48" ] && [ -n "$r42" ] && [ "$r42" = "$r48" ]; then
    ok "key shift+b: KEY_LEFTSHIFT (42) and KEY_B (48) pressed in one frame (t=$t42), released in one (t=$r42)"
  else
    bad "key shift+b: presses at '$t42'/'$t48', releases at '$r42'/'$r48' (expected pairwise equal)"
  fi
else
  bad "key shift+b: no release of KEY_LEFTSHIFT on $KBD"
fi
if send "^$MOUSE POINTER_MOTION " rel 20 10 && lat "rel" &&
  grep -q " udx=20.00 udy=10.00 " "$W/line" && [ "$(grep -c "POINTER_MOTION " "$P")" = 1 ]; then
  ok "rel 20 10: one POINTER_MOTION on the virtio mouse, unaccelerated 20,10 ($(grep -oE 'dx=[^ ]+ dy=[^ ]+' "$W/line" | head -n 1) accelerated)"
else
  bad "rel 20 10: expected one POINTER_MOTION udx=20.00 udy=10.00 on $MOUSE: $(grep POINTER_MOTION "$P" | head -n 3)"
fi
# buttons: to the pointer qemu calls current (the tablet at boot), or as chosen
if send "^[a-z0-9]+ POINTER_BUTTON button=272 released" click && lat "click (release)" &&
  grep -q "^$TAB0 " "$W/line" && has "^$TAB0 POINTER_BUTTON button=272 pressed seat_count=1 "; then
  ok "click (at boot): BTN_LEFT pressed and released on the first virtio tablet ($TAB0), not the mouse"
else
  bad "click (at boot): expected BTN_LEFT on $TAB0: $(grep POINTER_BUTTON "$P" | head -n 2)"
fi
sel=$("${Q[@]}" mouse mouse 2>&1)
if send "^$MOUSE POINTER_BUTTON button=273 released" click right &&
  has "^$MOUSE POINTER_BUTTON button=273 pressed seat_count=1 "; then
  ok "qmp.py mouse mouse ($sel), click right: BTN_RIGHT pressed and released on the virtio mouse"
else
  bad "qmp.py mouse mouse ($sel), click right: no BTN_RIGHT on $MOUSE: $(grep 'button=273' "$P")"
fi
"${Q[@]}" mouse tablet >/dev/null 2>&1
: >"$W/line"
"${Q[@]}" click left down >/dev/null && sleep 0.3 &&
  send "^$TAB0 POINTER_BUTTON button=272 released" click left up && lat "slow click (release)"
slow_lag=$(sed -nE 's/.* lag=([0-9.]+)ms$/\1/p' "$W/line")
# absolute: 0..32767 of each tablet device -> 0..W-1 / 0..H-1 (libinput: v * W / 32768)
abs_ok=yes abs_seen=''
abs_case() { # NODE EXPECTED_XY ABS-ARGS...
  local node=$1 want=$2
  shift 2
  if send "^$node POINTER_MOTION_ABSOLUTE " abs "$@" && grep -q " $want " "$W/line"; then
    abs_seen="$abs_seen; abs $* -> $node $want"
  else
    abs_ok=no
    abs_seen="$abs_seen; abs $* -> expected $node $want, got: $(cat "$W/line" 2>/dev/null)"
  fi
}
abs_case "$TAB0" "x=320.00 y=120.00" 16384 8192 && lat "abs"
abs_case "$TAB0" "x=639.98 y=479.99" 32767 32767
abs_case "$TAB0" "x=0.00 y=0.00" 0 0
abs_case "$TAB0" "x=160.00 y=360.00" 8192 24576 0
abs_case "$TAB1" "x=480.00 y=240.00" 24576 16384 1
abs_case "$TAB1" "x=1.95 y=2.93" 100 200 1
if [ $abs_ok = yes ]; then
  ok "absolute positions (POINTER_MOTION_ABSOLUTE, transform 640x480)${abs_seen}"
else
  bad "absolute positions${abs_seen}"
fi
if send "^$TAB1 POINTER_BUTTON button=272 released" click left 1; then
  ok "click left 1: BTN_LEFT on head 1's tablet ($TAB1)"
else
  bad "click left 1: no BTN_LEFT on $TAB1: $(grep POINTER_BUTTON "$P" | tail -n 2)"
fi

# ---- 5. the touchscreen --------------------------------------------------------
if guest_step 'sh touch.sh "tap 100 200" "drag 10 20 110 70 5" "pinch 320 240 50 100 4"'; then
  ok "uinput_touch: tap, drag and pinch done ($(grep -c '^ok ' "$S/touch.log") commands acknowledged)"
else
  bad "uinput_touch commands failed: $(cat "$S/cmd-$STEP.log" 2>/dev/null)"
fi
sleep 0.5 # the last frame's events, from libinput to the share
grep "^$TOUCH TOUCH_" "$P" | sed -E 's/ t=.*//; s/^[a-z0-9]+ TOUCH_//' >"$W/touch.seq"
# what the three gestures must give, frame by frame (F = TOUCH_FRAME)
cat >"$W/touch.want" <<'EOF'
DOWN slot=0 seat_slot=0 x=100.00 y=200.00
FRAME
UP slot=0 seat_slot=0
FRAME
DOWN slot=0 seat_slot=0 x=10.00 y=20.00
FRAME
MOTION slot=0 seat_slot=0 x=30.00 y=30.00
FRAME
MOTION slot=0 seat_slot=0 x=50.00 y=40.00
FRAME
MOTION slot=0 seat_slot=0 x=70.00 y=50.00
FRAME
MOTION slot=0 seat_slot=0 x=90.00 y=60.00
FRAME
MOTION slot=0 seat_slot=0 x=110.00 y=70.00
FRAME
UP slot=0 seat_slot=0
FRAME
DOWN slot=0 seat_slot=0 x=270.00 y=240.00
DOWN slot=1 seat_slot=1 x=370.00 y=240.00
FRAME
MOTION slot=0 seat_slot=0 x=257.00 y=240.00
MOTION slot=1 seat_slot=1 x=383.00 y=240.00
FRAME
MOTION slot=0 seat_slot=0 x=245.00 y=240.00
MOTION slot=1 seat_slot=1 x=395.00 y=240.00
FRAME
MOTION slot=0 seat_slot=0 x=232.00 y=240.00
MOTION slot=1 seat_slot=1 x=408.00 y=240.00
FRAME
MOTION slot=0 seat_slot=0 x=220.00 y=240.00
MOTION slot=1 seat_slot=1 x=420.00 y=240.00
FRAME
UP slot=0 seat_slot=0
UP slot=1 seat_slot=1
FRAME
EOF
check_touch() { # FIRST LAST DESCRIPTION: lines FIRST..LAST of the wanted sequence
  if diff <(sed -n "$1,$2p" "$W/touch.want") <(sed -n "$1,$2p" "$W/touch.seq") >"$W/touch.diff"; then
    ok "touch $3"
  else
    bad "touch $3; want (<) / got (>): $(tr '\n' ' ' <"$W/touch.diff")"
  fi
}
check_touch 1 4 "tap 100 200: DOWN slot 0 at 100,200, FRAME, UP, FRAME"
check_touch 5 18 "drag 10 20 110 70 5: DOWN at 10,20, 5 MOTIONs of 20,10 px each in their own frames, UP"
check_touch 19 35 "pinch 320 240 50 100 4: slots 0 and 1 down together at 270/370, spread to 220/420 in 4 frames, up together"
if cmp -s "$W/touch.want" "$W/touch.seq"; then
  ok "touch: exactly the $(wc -l <"$W/touch.want") expected events, $(grep -c FRAME "$W/touch.want") frames (nothing else from the touchscreen)"
else
  bad "touch: the $(wc -l <"$W/touch.seq") events from $TOUCH are not the $(wc -l <"$W/touch.want") expected ones (see above)"
fi
touch_lag=$(grep -E "^$TOUCH TOUCH_" "$P" | sed -nE 's/.* lag=([0-9.]+)ms$/\1/p' | sort -n |
  awk '{ v[NR] = $1 } END { if (NR) printf "median %.1f ms, max %.1f ms", v[int((NR + 1) / 2)], v[NR] }')
frame_gap=$(grep -E "^$TOUCH TOUCH_FRAME" "$P" | sed -n '3,9p' | sed -E 's/.* t=([0-9.]+) .*/\1/' |
  awk 'NR > 1 { d = ($1 - p) * 1000; s += d; if (d > m) m = d } { p = $1 } END { if (NR > 1) printf "%.1f ms mean, %.1f ms max", s / (NR - 1), m }')

# ---- 5b. the touchpad: gestures ------------------------------------------------
# pad NAME END_REGEX CMD...: the guest sends the CMDs to the touchpad; the
# probe's lines of the touchpad from then on, until one matches
# "^eventN END_REGEX" (at most 3 s after the commands were done; an empty
# END_REGEX: 0.5 s), go to $W/NAME.seq
pad() {
  local name=$1 end=$2 from i=0 args=''
  shift 2
  from=$(wc -l <"$P")
  for c in "$@"; do args="$args \"$c\""; done
  if ! guest_step "FIFO=/tmp/pad.fifo LOG=pad.log sh touch.sh$args"; then
    echo "pad $name: $(cat "$S/cmd-$STEP.log" 2>/dev/null)" >"$W/$name.seq"
    return 1
  fi
  if [ -z "$end" ]; then sleep 0.5; fi
  until [ -z "$end" ] || tail -n +"$((from + 1))" "$P" | grep -qE "^$PAD $end"; do
    [ $i -lt 30 ] || break
    sleep 0.1; i=$((i + 1))
  done
  tail -n +"$((from + 1))" "$P" | grep -E "^$PAD " >"$W/$name.seq"
}
# gesture_check KIND FINGERS SEQ: KIND's (PINCH or SWIPE) events in SEQ must be
# BEGIN, UPDATE..., END cancelled=0, all with FINGERS fingers (HOLD_* before
# them is allowed: a hold begins when the fingers rest 40 ms); prints
# "ok UPDATES SUM_DX SUM_DY FIRST_SCALE LAST_SCALE MONOTONY" or "bad REASON"
gesture_check() {
  awk -v kind="$1" -v fingers="$2" '
    function val(key,   i, kv) {
      for (i = 3; i <= NF; i++) { split($i, kv, "="); if (kv[1] == key) return kv[2] }
      return ""
    }
    $2 !~ "^GESTURE_" kind "_" { next }
    { n++; type = substr($2, length("GESTURE_" kind "_") + 1) }
    val("fingers") != fingers { bad = bad " " $2 " with fingers=" val("fingers") }
    n == 1 && type != "BEGIN" { bad = bad " first is " $2 }
    type == "BEGIN" && n != 1 { bad = bad " a second BEGIN" }
    type == "END" { ends++; cancelled = val("cancelled"); endscale = val("scale") }
    type == "UPDATE" {
      if (ends) bad = bad " UPDATE after END"
      u++; dx += val("dx"); dy += val("dy"); s = val("scale") + 0
      if (u == 1) first = s
      if (u > 1 && s > prev) up++
      if (u > 1 && s < prev) down++
      prev = s
    }
    END {
      if (n == 0) { print "bad no GESTURE_" kind "_* event"; exit }
      if (type != "END") bad = bad " last is GESTURE_" kind "_" type
      if (ends != 1) bad = bad " " ends + 0 " ENDs"
      if (cancelled != "0") bad = bad " END cancelled=" cancelled
      if (u == 0) bad = bad " no UPDATE"
      if (bad != "") { print "bad" bad; exit }
      printf "ok %d %.2f %.2f %s %s %s\n", u, dx, dy, first, endscale,
        (down == 0 && up > 0) ? "growing" : (up == 0 && down > 0) ? "shrinking" : "mixed"
    }' "$3"
}
pad_seq() { tr '\n' '|' <"$W/$1.seq" | cut -c1-600; }

# pinch: fingers 15 mm apart spreading to 60 mm (and back) in 20 frames of 10 ms
pad pinch_out 'GESTURE_PINCH_END' "pinch 2000 1200 300 1200 20"
read -r res u dx dy first last mono <<<"$(gesture_check PINCH 2 "$W/pinch_out.seq")"
if [ "$res" = ok ] && [ "$mono" = growing ] && awk -v s="$last" 'BEGIN { exit !(s > 1.3) }'; then
  ok "touchpad pinch out (15 -> 60 mm): PINCH_BEGIN, $u PINCH_UPDATEs with the scale growing $first -> $last, PINCH_END (fingers=2)"
else
  bad "touchpad pinch out: want BEGIN, UPDATEs growing, END with scale > 1.3: $res $u $dx $dy $first $last $mono; $(pad_seq pinch_out)"
fi
pad pinch_in 'GESTURE_PINCH_END' "pinch 2000 1200 1200 300 20"
read -r res u dx dy first last mono <<<"$(gesture_check PINCH 2 "$W/pinch_in.seq")"
if [ "$res" = ok ] && [ "$mono" = shrinking ] && awk -v s="$last" 'BEGIN { exit !(s < 0.8) }'; then
  ok "touchpad pinch in (60 -> 15 mm): PINCH_BEGIN, $u PINCH_UPDATEs with the scale shrinking $first -> $last, PINCH_END"
else
  bad "touchpad pinch in: want BEGIN, UPDATEs shrinking, END with scale < 0.8: $res $u $dx $dy $first $last $mono; $(pad_seq pinch_in)"
fi
# three fingers 20 mm apart in a row, 20 mm to the right, then back
pad swipe_right 'GESTURE_SWIPE_END' "swipe3 1600 1200 2400 1200 20"
read -r res u dx dy _ <<<"$(gesture_check SWIPE 3 "$W/swipe_right.seq")"
pad swipe_left 'GESTURE_SWIPE_END' "swipe3 2400 1200 1600 1200 20"
read -r res2 u2 dx2 dy2 _ <<<"$(gesture_check SWIPE 3 "$W/swipe_left.seq")"
if [ "$res" = ok ] && [ "$res2" = ok ] &&
  awk -v a="$dx" -v b="$dy" -v c="$dx2" -v d="$dy2" \
    'BEGIN { exit !(a > 0 && c < 0 && 4 * (b < 0 ? -b : b) < a && 4 * (d < 0 ? -d : d) < -c) }'; then
  ok "touchpad swipe3 right / left: SWIPE_BEGIN, UPDATEs, SWIPE_END (fingers=3); dx sums $dx ($u updates) / $dx2 ($u2), dy $dy / $dy2"
else
  bad "touchpad swipe3: want BEGIN, UPDATEs, END, dx > 0 then < 0: right: $res $u dx=$dx dy=$dy; left: $res2 $u2 dx=$dx2 dy=$dy2; $(pad_seq swipe_right) $(pad_seq swipe_left)"
fi
# two fingers 20 mm apart dragged 20 mm down, then up: two-finger scrolling
# (POINTER_SCROLL_FINGER, and the legacy POINTER_AXIS source=finger); the
# scroll ends with an event of value 0
scroll_check() { # SEQ: "ok EVENTS SUM_V" or "bad REASON"
  awk '
    $2 ~ /^GESTURE_(PINCH|SWIPE)/ { bad = bad " " $2 }
    $2 != "POINTER_SCROLL_FINGER" { next }
    { n++; split($3, v, "="); split($4, h, "="); sum += v[2]; last = $3 " " $4 }
    h[2] != "0.00" { bad = bad " h=" h[2] }
    END {
      if (n < 3) bad = bad " " n + 0 " POINTER_SCROLL_FINGER events"
      else if (last != "v=0.00 h=0.00") bad = bad " no end of scroll (last " last ")"
      if (bad != "") print "bad" bad; else printf "ok %d %.2f\n", n, sum
    }' "$1"
}
pad scroll_down 'POINTER_SCROLL_FINGER v=0\.00 h=0\.00' "pan2 2000 600 2000 1400 20"
read -r res n v <<<"$(scroll_check "$W/scroll_down.seq")"
pad scroll_up 'POINTER_SCROLL_FINGER v=0\.00 h=0\.00' "pan2 2000 1400 2000 600 20"
read -r res2 n2 v2 <<<"$(scroll_check "$W/scroll_up.seq")"
if [ "$res" = ok ] && [ "$res2" = ok ] && awk -v a="$v" -v b="$v2" 'BEGIN { exit !(a > 0 && b < 0) }'; then
  ok "touchpad pan2 down / up: POINTER_SCROLL_FINGER, vertical only, v sums $v / $v2 ($n / $n2 events, the last v=0: the end)"
else
  bad "touchpad pan2: want POINTER_SCROLL_FINGER v > 0 (down) then < 0 (up), h=0, an end: down: $res $n $v; up: $res2 $n2 $v2; $(pad_seq scroll_down) $(pad_seq scroll_up)"
fi
# one finger: pointer motion (accelerated; unaccelerated in device units)
pad drag '' "drag 1000 1000 2000 1000 10"
read -r n udx udy other <<<"$(awk '$2 == "POINTER_MOTION" { n++; split($5, a, "="); split($6, b, "="); x += a[2]; y += b[2] }
  $2 != "POINTER_MOTION" && $2 !~ /^GESTURE_HOLD/ { o = o $2 "," } END { printf "%d %.2f %.2f %s\n", n, x, y, o "-" }' "$W/drag.seq")"
if [ "$n" -ge 5 ] && [ "$other" = - ] && awk -v x="$udx" -v y="$udy" 'BEGIN { exit !(x >= 500 && x <= 1000 && y == 0) }'; then
  ok "touchpad drag (1 finger, 25 mm right): $n POINTER_MOTIONs, unaccelerated $udx,$udy device units"
else
  bad "touchpad drag: want >= 5 POINTER_MOTION, unaccelerated x 500..1000, y 0, nothing else: $n $udx $udy $other; $(pad_seq drag)"
fi

# ---- 6. the end ----------------------------------------------------------------
touch "$S/done"
wait "$GPID"
RC=$?
GPID=
if [ "$RC" = 0 ] && has '^removed [a-z0-9]+ "tessera-test-touch"$' &&
  has '^removed [a-z0-9]+ "tessera-test-touchpad"$'; then
  ok "uinput_touch quit: libinput removed the touchscreen and the touchpad; guest status 0"
else
  bad "end of the run: guest status $RC (0 wanted), removals seen: touchscreen $(grep -c '^removed.*"tessera-test-touch"$' "$P"), touchpad $(grep -c '^removed.*"tessera-test-touchpad"$' "$P")"
fi
left=''
for p in /proc/[0-9]*; do
  c=$(tr '\0' ' ' 2>/dev/null <"$p/cmdline") || continue
  [[ $c == *qemu-system*"$W"* ]] && left="$left ${p#/proc/}"
done
if [ -z "$left" ]; then ok "no qemu left"; else bad "qemu left:$left"; fi

unknown=$(grep -vE '^(added|removed|probe:|log:|event[0-9]+ )' "$P" | head -n 3)
[ -z "$unknown" ] || bad "input_probe printed unexpected lines: $unknown"
echo "latency, QMP send -> probe line in the share (host): $LATS"
echo "latency, kernel event time -> input_probe (guest): keyboard $(sed -nE "s/^$KBD .* lag=([0-9.]+)ms$/\\1/p" "$P" | head -n 1) ms," \
  "fast click release $(grep -E 'POINTER_BUTTON button=272 released' "$P" | head -n 1 | sed -E 's/.* lag=//')" \
  "(libinput's button debounce), slow click release ${slow_lag:-?} ms, touch $touch_lag; drag frames $frame_gap apart"
if [ "$FAIL" != 0 ]; then
  echo "---- probe.log ----"; grep -v '^log:' "$P" 2>/dev/null | tail -n 60
  echo "---- run-guest stderr ----"; cat "$W/run-guest.err" 2>/dev/null
  echo "---- console (last 20 lines) ----"; tail -n 20 "$W/console.log" 2>/dev/null
fi
summary
