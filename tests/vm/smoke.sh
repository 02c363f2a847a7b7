#!/usr/bin/env bash
# tests/vm/smoke.sh CACHE
#
# Self-test of the VM harness (build-guest.sh, guest-init.sh, run-guest.sh,
# qmp.py), in one boot plus one short one:
#   1. builds tests/vm/kms_fill.c and a guest with it (CACHE/smoke; the
#      downloads in CACHE are shared with other guests, CACHE/initrd.img is
#      left alone)
#   2. boots it with 2 heads (640x480 and 800x600) and a QMP socket; in the
#      guest kms_fill lights head 0 c81e3c and head 1 1eb464 while raw readers
#      record the virtio keyboard, mouse and tablet
#   3. host: screendumps both heads (PPM, and PNG once) and checks size and
#      every pixel; sends a key, mouse motion, an absolute position and a
#      click over QMP; acks; checks the guest saw the input events and that
#      the guest script's status (3) came back as run-guest's status
#   4. a boot with a 3 s limit must end with 124 and leave no qemu behind
# Prints "N passed, M failed"; exit status 0 only if nothing failed.
# VM_KEEP=1 keeps the work folder (screendumps, console logs).
set -uo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
[ $# -eq 1 ] || { sed -n '2,20p' "$0" >&2; exit 2; }
mkdir -p "$1" || exit 2
CACHE=$(cd "$1" && pwd)
QMPY=(python3 "$HERE/qmp.py")

PASS=0 FAIL=0
ok() { echo "PASS: $*"; PASS=$((PASS + 1)); }
bad() { echo "FAIL: $*"; FAIL=$((FAIL + 1)); }
check() { # DESCRIPTION COMMAND...: pass if COMMAND succeeds
  local what=$1; shift
  if "$@"; then ok "$what"; else bad "$what"; fi
}
now() { date +%s.%N; }
since() { awk -v a="$1" -v b="$(now)" 'BEGIN { printf "%.1f", b - a }'; }

# short path: the QMP socket lives in it (unix socket paths are < 108 bytes)
W=$(mktemp -d /tmp/vm-smoke.XXXXXX)
S=$W/share
mkdir -p "$S"
GPID=
finish() {
  if [ -n "$GPID" ] && kill -0 "$GPID" 2>/dev/null; then
    kill -TERM "$GPID" 2>/dev/null   # run-guest.sh stops its qemu
    wait "$GPID" 2>/dev/null
  fi
  if [ "${VM_KEEP:-}" = 1 ]; then echo "smoke: kept $W"; else rm -rf "$W"; fi
}
trap finish EXIT
trap 'exit 130' INT; trap 'exit 143' TERM

# wait_file FILE SECS: until FILE exists, the guest is gone, or SECS passed
wait_file() {
  local end=$((SECONDS + $2))
  while [ ! -e "$1" ]; do
    kill -0 "$GPID" 2>/dev/null || return 1
    [ "$SECONDS" -lt "$end" ] || return 1
    sleep 0.1
  done
}
SELF=smoke
. "$HERE/smoke_lib.sh" # users_of_w, no_qemu_left, size_and_colour
differ() { ! "${QMPY[@]}" compare "$1" "$2" >/dev/null; }
send_input() {
  "${Q[@]}" key h && "${Q[@]}" rel 20 10 && "${Q[@]}" abs 16384 8192 && "${Q[@]}" click left
}
# has_events FILE "TYPE CODE VALUE"...: the guest's evdev record has all of them
has_events() {
  local f=$S/$1 e events
  shift
  [ -s "$f" ] || return 1
  events=$("${QMPY[@]}" evdev "$f") || return 1
  for e in "$@"; do grep -qx "$e" <<<"$events" || return 1; done
}

T0=$(now)

# ---- 1. kms_fill and the guest -------------------------------------------
if ! pkg-config --exists libdrm 2>/dev/null; then
  bad "libdrm development files missing (run tools/deps.sh)"
  echo "$PASS passed, $FAIL failed"; exit 1
fi
# shellcheck disable=SC2046
check "kms_fill builds" gcc -std=c11 -O2 -Wall -Wextra -Werror -o "$S/kms_fill" \
  "$HERE/kms_fill.c" $(pkg-config --cflags --libs libdrm)
[ -x "$S/kms_fill" ] || { echo "$PASS passed, $FAIL failed"; exit 1; }

GUEST=$CACHE/smoke
T=$(now)
if VM_OUT=$GUEST "$HERE/build-guest.sh" "$CACHE" "$S/kms_fill" >"$W/build.log" 2>&1; then
  ok "build-guest.sh ($(since "$T") s): $(tail -n 1 "$W/build.log")"
else
  bad "build-guest.sh failed:"; cat "$W/build.log"
  echo "$PASS passed, $FAIL failed"; exit 1
fi

# ---- 2. the guest's side --------------------------------------------------
cat >"$S/guest.sh" <<'EOF'
# raw readers of the virtio input devices, started before the host sends
readers=
for d in /sys/class/input/event*; do
  case $(cat "$d/device/name") in
    "QEMU Virtio Keyboard") out=kbd.ev ;;
    "QEMU Virtio Mouse") out=mouse.ev ;;
    "QEMU Virtio Tablet") out=tablet.ev ;;
    *) continue ;;
  esac
  cat "/dev/input/${d##*/}" >"$out" &
  readers="$readers $!"
done
./kms_fill -r 640x480,800x600 -c c81e3c,1eb464 -m ready -a ack -w 120 || exit 1
# the host sent its input before the ack: give the readers time to write it
i=0
while [ $i -lt 50 ] && ! { [ -s kbd.ev ] && [ -s mouse.ev ] && [ -s tablet.ev ]; }; do
  sleep 0.1; i=$((i + 1))
done
sleep 0.3
kill $readers
# a distinctive status: the host checks that it comes back unchanged
exit 3
EOF

T=$(now)
"$HERE/run-guest.sh" -c "$GUEST" -s "$S" -q "$W/qmp.sock" -n 2 -r 640x480,800x600 \
  -t 240 -l "$W/console.log" -- sh guest.sh >/dev/null 2>"$W/run-guest.err" &
GPID=$!

if wait_file "$S/ready" 180; then
  ok "guest booted and lit both heads ($(since "$T") s after start)"
  Q=(timeout 60 "${QMPY[@]}" "$W/qmp.sock")
  check "screendump head 0 (PPM)" "${Q[@]}" screendump "$W/head0.ppm" 0
  check "screendump head 1 (PPM)" "${Q[@]}" screendump "$W/head1.ppm" 1
  check "screendump head 1 (PNG)" "${Q[@]}" screendump "$W/head1.png" 1
  check "head 0 is 640x480, every pixel c81e3c" size_and_colour "$W/head0.ppm" 640x480 c81e3c
  check "head 1 is 800x600, every pixel 1eb464" size_and_colour "$W/head1.ppm" 800x600 1eb464
  check "PNG screendump equals the PPM one" "${QMPY[@]}" compare "$W/head1.png" "$W/head1.ppm"
  check "qmp.py compare tells the heads apart" differ "$W/head0.ppm" "$W/head1.ppm"
  check "QMP input: key, rel, abs, click" send_input
  touch "$S/ack"
else
  bad "guest never lit the heads (no ready marker)"
fi

wait "$GPID"
RC=$?
GPID=
check "guest script status 3 came back through run-guest.sh (got $RC)" test "$RC" = 3
check "no qemu left after the run" no_qemu_left

# input as the guest's evdev saw it (type code value; EV_KEY 1, EV_REL 2, EV_ABS 3)
check "guest keyboard saw KEY_H down and up" has_events kbd.ev "1 35 1" "1 35 0"
check "guest mouse saw REL_X 20, REL_Y 10" has_events mouse.ev "2 0 20" "2 1 10"
check "guest tablet saw ABS_X 16384, ABS_Y 8192" has_events tablet.ev "3 0 16384" "3 1 8192"
left_click() { has_events tablet.ev "1 272 1" "1 272 0" || has_events mouse.ev "1 272 1" "1 272 0"; }
check "guest saw BTN_LEFT down and up (tablet or mouse)" left_click

# ---- 4. time limit ---------------------------------------------------------
T=$(now)
"$HERE/run-guest.sh" -c "$GUEST" -s "$S" -q "$W/qmp2.sock" -n 1 -t 3 \
  -l "$W/console-timeout.log" -- sleep 100 >/dev/null 2>&1 &
GPID=$!
wait "$GPID"
RC=$?
GPID=
E=$(since "$T")
check "a run over its time limit exits 124 (got $RC after $E s)" test "$RC" = 124
check "no qemu left after the time limit" no_qemu_left

if [ "$FAIL" != 0 ]; then
  echo "---- run-guest stderr ----"; cat "$W/run-guest.err" 2>/dev/null
  echo "---- console (last 40 lines) ----"; tail -n 40 "$W/console.log" 2>/dev/null
fi
echo "smoke: total $(since "$T0") s"
echo "$PASS passed, $FAIL failed"
[ "$FAIL" = 0 ]
