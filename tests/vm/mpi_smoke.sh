#!/usr/bin/env bash
# tests/vm/mpi_smoke.sh CACHE
#
# Self-test of OpenMPI in the guest (build-guest.sh VM_MPI=1) and of two DRM
# cards (run-guest.sh -g 2), in one boot:
#   1. builds tests/vm/mpi_hello.c (mpicc) and tests/vm/kms_fill.c, and a
#      guest with OpenMPI and both (in $VM_OUT, default CACHE/mpi; the
#      downloads stay in CACHE)
#   2. boots 2 cards x 2 heads: gpu0 640x480 + 800x600, gpu1 800x600 +
#      640x480, with a QMP socket; in the guest: records which PCI function
#      each /dev/dri/cardN is, that lo is up and /dev/shm a tmpfs; runs
#      `mpirun --oversubscribe --bind-to none -np 2 mpi_hello` twice (timed
#      with the guest's clock); then `mpirun -np 2 sh kms_rank.sh`: rank R
#      lights /dev/dri/cardR with kms_fill (card0 c81e3c,1eb464; card1
#      3c50dc,f0c814), the pattern of the multi-card wall test
#   3. host: screendumps both heads of gpu0 and of gpu1 (qmp.py screendump
#      FILE HEAD DEVICE) and checks each one's size and every pixel, checks a
#      screendump without DEVICE is gpu0's, that card0/card1 are the PCI
#      functions QMP query-pci gives for gpu0/gpu1; acks
#   4. checks both ranks' lines and the Allreduce sum of mpi_hello (both
#      runs), the KMS ranks' status, lo and /dev/shm, run-guest's status, and
#      that no qemu is left
# Prints PASS/FAIL lines, the timings, and "N passed, M failed"; exit status
# 0 only if nothing failed. VM_KEEP=1 keeps the work folder (logs, dumps).
# shellcheck disable=SC2317  # (functions called through check)
set -uo pipefail

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
[ $# -eq 1 ] || { sed -n '2,24p' "$0" >&2; exit 2; }
mkdir -p "$1" || exit 2
CACHE=$(cd "$1" && pwd)
GUEST=${VM_OUT:-$CACHE/mpi}
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
T0=$(now)

W=$(mktemp -d /tmp/vm-mpi.XXXXXX) # short: the QMP socket lives in it
S=$W/share
mkdir -p "$S"
GPID=
# shellcheck disable=SC2317  # (called through the trap)
finish() {
  if [ -n "$GPID" ] && kill -0 "$GPID" 2>/dev/null; then
    kill -TERM "$GPID" 2>/dev/null # run-guest.sh stops its qemu
    wait "$GPID" 2>/dev/null
  fi
  if [ "${VM_KEEP:-}" = 1 ]; then echo "mpi_smoke: kept $W"; else rm -rf "$W"; fi
}
trap finish EXIT
trap 'exit 130' INT; trap 'exit 143' TERM
summary() {
  if [ "$FAIL" != 0 ]; then
    echo "---- run-guest stderr ----"; cat "$W/run-guest.err" 2>/dev/null
    echo "---- console (last 40 lines) ----"; tail -n 40 "$W/console.log" 2>/dev/null
  fi
  echo "mpi_smoke: total $(since "$T0") s"
  echo "$PASS passed, $FAIL failed"
  [ "$FAIL" = 0 ]
  exit
}

# wait_files SECS FILE...: until every FILE exists, the guest is gone, or SECS passed
wait_files() {
  local end=$((SECONDS + $1)) f
  shift
  for f in "$@"; do
    while [ ! -e "$f" ]; do
      kill -0 "$GPID" 2>/dev/null || return 1
      [ "$SECONDS" -lt "$end" ] || return 1
      sleep 0.1
    done
  done
}
SELF=mpi_smoke
. "$HERE/smoke_lib.sh" # users_of_w, no_qemu_left, size_and_colour
# has_line FILE REGEX: FILE in the share has a line matching REGEX (grep -E)
has_line() { grep -qE "$2" "$S/$1" 2>/dev/null; }

# ---- 1. the programs and the guest ------------------------------------------
if ! command -v mpicc >/dev/null; then
  bad "mpicc missing (apt-get install libopenmpi-dev)"; summary
fi
if ! pkg-config --exists libdrm 2>/dev/null; then
  bad "libdrm development files missing (run tools/deps.sh)"; summary
fi
# shellcheck disable=SC2046
if mpicc -std=c11 -O2 -Wall -Wextra -Werror -o "$S/mpi_hello" "$HERE/mpi_hello.c" 2>"$W/cc.log" &&
  gcc -std=c11 -O2 -Wall -Wextra -Werror -o "$S/kms_fill" "$HERE/kms_fill.c" \
    $(pkg-config --cflags --libs libdrm) 2>>"$W/cc.log"; then
  ok "mpi_hello (mpicc) and kms_fill build"
else
  bad "the programs do not build:"; cat "$W/cc.log"; summary
fi

T=$(now)
if VM_MPI=1 VM_OUT=$GUEST "$HERE/build-guest.sh" "$CACHE" "$S/mpi_hello" "$S/kms_fill" \
  >"$W/build.log" 2>&1; then
  ok "build-guest.sh with VM_MPI=1 ($(since "$T") s): $(tail -n 1 "$W/build.log")"
else
  bad "build-guest.sh VM_MPI=1 failed:"; tail -n 30 "$W/build.log"; summary
fi

# ---- 2. the guest's side ----------------------------------------------------
# rank R of the launch lights card R (mpirun sets OMPI_COMM_WORLD_RANK for
# any program, MPI or not)
cat >"$S/kms_rank.sh" <<'EOF'
r=$OMPI_COMM_WORLD_RANK
case $r in
  0) modes=640x480,800x600 colours=c81e3c,1eb464 ;;
  1) modes=800x600,640x480 colours=3c50dc,f0c814 ;;
  *) echo "kms_rank: no card for rank $r" >&2; exit 1 ;;
esac
exec ./kms_fill -d /dev/dri/card$r -r $modes -c $colours -m ready$r -a ack -w 150
EOF
cat >"$S/guest.sh" <<'EOF'
up() { cut -d' ' -f1 /proc/uptime; }
echo "boot $(up)" > times.txt
# which PCI function each card node is (the DRM device's parent, skipping a
# virtioN level should a kernel put one in between)
for c in /sys/class/drm/card[0-9]; do
  p=$(readlink -f "$c/device")
  case ${p##*/} in virtio*) p=${p%/*} ;; esac
  echo "${c##*/} ${p##*/}"
done > cards.txt
ip addr show lo > lo.txt 2>&1
grep ' /dev/shm ' /proc/mounts > shm.txt
t=$(up)
timeout 150 mpirun --oversubscribe --bind-to none -np 2 ./mpi_hello > hello1.log 2>&1
echo $? > hello1.rc
echo "mpirun1 $t $(up)" >> times.txt
t=$(up)
timeout 150 mpirun --oversubscribe --bind-to none -np 2 ./mpi_hello > hello2.log 2>&1
echo $? > hello2.rc
echo "mpirun2 $t $(up)" >> times.txt
t=$(up)
# the host waits for ready0 and ready1, screendumps, then creates ack
timeout 200 mpirun --oversubscribe --bind-to none -np 2 sh kms_rank.sh > kms.log 2>&1
echo $? > kms.rc
echo "kms-incl-host-checks $t $(up)" >> times.txt
exit 0
EOF

T=$(now)
"$HERE/run-guest.sh" -c "$GUEST" -s "$S" -q "$W/qmp.sock" -g 2 -n 2 \
  -r 640x480,800x600,800x600,640x480 -t 420 -l "$W/console.log" -- sh guest.sh \
  >/dev/null 2>"$W/run-guest.err" &
GPID=$!

if wait_files 360 "$S/ready0" "$S/ready1"; then
  ok "guest booted, ran mpi_hello twice, and both ranks lit their card ($(since "$T") s after start)"
  Q=(timeout 60 "${QMPY[@]}" "$W/qmp.sock")
  check "screendump gpu0 head 0" "${Q[@]}" screendump "$W/gpu0-0.ppm" 0 gpu0
  check "screendump gpu0 head 1" "${Q[@]}" screendump "$W/gpu0-1.ppm" 1 gpu0
  check "screendump gpu1 head 0" "${Q[@]}" screendump "$W/gpu1-0.ppm" 0 gpu1
  check "screendump gpu1 head 1" "${Q[@]}" screendump "$W/gpu1-1.ppm" 1 gpu1
  check "screendump without DEVICE (head 1)" "${Q[@]}" screendump "$W/default-1.ppm" 1
  check "gpu0 head 0 (card0, rank 0) is 640x480, every pixel c81e3c" size_and_colour "$W/gpu0-0.ppm" 640x480 c81e3c
  check "gpu0 head 1 (card0, rank 0) is 800x600, every pixel 1eb464" size_and_colour "$W/gpu0-1.ppm" 800x600 1eb464
  check "gpu1 head 0 (card1, rank 1) is 800x600, every pixel 3c50dc" size_and_colour "$W/gpu1-0.ppm" 800x600 3c50dc
  check "gpu1 head 1 (card1, rank 1) is 640x480, every pixel f0c814" size_and_colour "$W/gpu1-1.ppm" 640x480 f0c814
  check "a screendump without DEVICE is gpu0's" "${QMPY[@]}" compare "$W/default-1.ppm" "$W/gpu0-1.ppm"
  # "gpu0 0000:00:01.0" per virtio-gpu, from QEMU's view of the PCI bus
  if "${Q[@]}" raw '{"execute": "query-pci"}' >"$W/pci.json"; then
    python3 -c '
import json, sys
for bus in json.load(open(sys.argv[1])):
    for d in bus["devices"]:
        if d.get("qdev_id", "").startswith("gpu"):
            print(d["qdev_id"], "0000:%02x:%02x.%x" % (d["bus"], d["slot"], d["function"]))
' "$W/pci.json" >"$W/pci.txt"
  fi
  touch "$S/ack"
else
  bad "the ranks never lit both cards (no ready0 + ready1 in the share)"
fi

wait "$GPID"
RC=$?
GPID=
check "guest script status 0 came back through run-guest.sh (got $RC)" test "$RC" = 0
check "no qemu left after the run" no_qemu_left

# ---- 3. what the guest recorded ---------------------------------------------
both_ranks() { # LOG: both ranks of 2 said hello
  has_line "$1" '^mpi_hello: rank 0 of 2 on tessera-vm ' && has_line "$1" '^mpi_hello: rank 1 of 2 on tessera-vm '
}
sum_ok() { # LOG: both ranks got the sum 0 + 1, rank 0 finished
  has_line "$1" '^mpi_hello: rank 0 sum 1 ok$' && has_line "$1" '^mpi_hello: rank 1 sum 1 ok$' &&
    has_line "$1" '^mpi_hello: done 2$'
}
lo_up() { has_line lo.txt '[<,]UP[,>]' && has_line lo.txt 'inet 127\.0\.0\.1/8'; }
for run in 1 2; do
  f=hello$run.log
  echo "  $f: $(tr '\n' '|' <"$S/$f" 2>/dev/null)"
  check "mpirun #$run: status 0" test "$(cat "$S/hello$run.rc" 2>/dev/null)" = 0
  check "mpirun #$run: rank 0 and rank 1 of 2 on tessera-vm" both_ranks "$f"
  check "mpirun #$run: Allreduce sum 1 on both ranks, rank 0 done" sum_ok "$f"
done
check "mpirun of kms_fill on card0 and card1: status 0 (got $(cat "$S/kms.rc" 2>/dev/null))" \
  test "$(cat "$S/kms.rc" 2>/dev/null)" = 0
check "lo is up with 127.0.0.1" lo_up
check "/dev/shm is a tmpfs" has_line shm.txt '^tmpfs /dev/shm tmpfs '
echo "  guest: $(tr '\n' ',' <"$S/cards.txt" 2>/dev/null) QEMU: $(tr '\n' ',' <"$W/pci.txt" 2>/dev/null)"
card_is() { # CARD GPU: the guest's CARD is QEMU's GPU (same PCI function)
  local a b
  a=$(awk -v c="$1" '$1 == c { print $2 }' "$S/cards.txt" 2>/dev/null)
  b=$(awk -v g="$2" '$1 == g { print $2 }' "$W/pci.txt" 2>/dev/null)
  [ -n "$a" ] && [ "$a" = "$b" ]
}
check "/dev/dri/card0 is gpu0 (PCI)" card_is card0 gpu0
check "/dev/dri/card1 is gpu1 (PCI)" card_is card1 gpu1

# the guest's clock: boot to the command, each mpirun, the KMS launch
if [ -s "$S/times.txt" ]; then
  awk '$1 == "boot" { printf "mpi_smoke: guest up to the command after %.1f s", $2 }
       $1 != "boot" { printf ", %s %.1f s", $1, $3 - $2 } END { print "" }' "$S/times.txt"
fi
summary
