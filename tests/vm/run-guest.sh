#!/usr/bin/env bash
# tests/vm/run-guest.sh [options] [--] CMD...
#
# Boots the guest of build-guest.sh in qemu, runs the shell command line CMD
# in it (working directory: the shared folder, mounted at /mnt/share), and
# exits with CMD's exit status; 124 if the time limit ran out, 125 if the
# guest ended without reporting a status (crash, panic) or this script could
# not start it (bad option, no guest, no qemu).
# Without CMD: an interactive busybox shell on the console (Ctrl-a x quits;
# no time limit then).
#
#   -c DIR     guest made by build-guest.sh     (default: $VM_CACHE)
#   -s DIR     host folder shared read-write    (default: .)
#   -q SOCK    create a QMP socket there (tests/vm/qmp.py: screendump, input)
#   -n N       heads (outputs) of the virtio-gpu, 1..4        (default 2)
#   -r WxH[,WxH...]  mode of each head; the last one repeats  (default 1024x768)
#   -g CARDS   virtio-gpus (DRM cards), 1 or 2: the second one, id=gpu1,
#              has -n heads too. Guest: gpu0 = /dev/dri/card0 (connectors
#              Virtual-1..N), gpu1 = card1 (connectors Virtual-N+1..2N: the
#              kernel numbers connectors across cards). Modes: with more
#              than N modes in -r, gpu1's heads take the modes after the
#              first N (-n 2 -r A,B,C,D: gpu0 A,B, gpu1 C,D); else head i of
#              either card gets mode i. gpu1's PCI slot comes after this
#              script's other devices, which keep theirs; -x ones follow.
#                                                                 (default 1)
#   -m MEM     guest memory                                   (default 1G)
#   -j CPUS    guest CPUs                        (default: host's, at most 2)
#   -t SECS    time limit for the whole run, then exit 124    (default 300)
#   -l FILE    also write the console output to FILE
#   -a ARGS    more kernel command line (vm.udev=0, vm.shell=1, vm.dmesg=1, ...)
#   -x ARGS    more qemu arguments (split at blanks)
#   -K / -T    force KVM / TCG (default: KVM only when /dev/kvm is usable AND
#              the CPU has vmx/svm; otherwise TCG software emulation)
#
# Guest devices: virtio-gpu-pci id=gpu0 (head i = connector Virtual-(i+1) =
# screendump head i), virtio-keyboard-pci id=kbd, virtio-mouse-pci id=mouse,
# virtio-tablet-pci id=tablet, 9p share "share" (and "libs", read-only, when
# build-guest.sh put libraries in CACHE/libs), with -g 2 virtio-gpu-pci
# id=gpu1 (screendump: qmp.py SOCK screendump FILE HEAD gpu1). The console
# goes to stdout.
# shellcheck disable=SC2054  # commas inside qemu option values are meant
set -uo pipefail

usage() { sed -n '2,40p' "$0" >&2; exit 125; }
die() { echo "run-guest: $*" >&2; exit 125; }

CACHE=${VM_CACHE:-} SHARE=. QMP='' HEADS=2 RES=1024x768 MEM=1G TMO=300
LOG='' KARGS='' XARGS='' ACCEL=${VM_ACCEL:-} CARDS=1
CPUS=$(nproc 2>/dev/null || echo 1); [ "$CPUS" -le 2 ] || CPUS=2
while getopts c:s:q:n:r:m:j:t:l:a:x:g:KTh opt; do
  case $opt in
    c) CACHE=$OPTARG ;; s) SHARE=$OPTARG ;; q) QMP=$OPTARG ;; n) HEADS=$OPTARG ;;
    r) RES=$OPTARG ;; m) MEM=$OPTARG ;; j) CPUS=$OPTARG ;; t) TMO=$OPTARG ;;
    l) LOG=$OPTARG ;; a) KARGS=$OPTARG ;; x) XARGS=$OPTARG ;;
    g) CARDS=$OPTARG ;;
    K) ACCEL=kvm ;; T) ACCEL=tcg ;; h) sed -n '2,40p' "$0"; exit 0 ;; *) usage ;;
  esac
done
shift $((OPTIND - 1))

[ -n "$CACHE" ] || die "no guest: pass -c CACHE (made by tests/vm/build-guest.sh)"
if [ ! -r "$CACHE/vmlinuz" ] || [ ! -r "$CACHE/initrd.img" ]; then
  die "no guest in $CACHE: run tests/vm/build-guest.sh $CACHE first"
fi
[ -d "$SHARE" ] || die "share folder $SHARE does not exist"
case $HEADS in [1-4]) ;; *) die "-n: heads must be 1..4" ;; esac
case $CARDS in [12]) ;; *) die "-g: cards must be 1 or 2" ;; esac
case $TMO in ''|*[!0-9]*) die "-t: seconds expected" ;; esac
command -v qemu-system-x86_64 >/dev/null || die "qemu-system-x86_64 missing (build-guest.sh installs it)"
SHARE=$(cd "$SHARE" && pwd)

# mode of head I (0-based) from the -r list
IFS=, read -r -a MODES <<<"$RES"
mode_of() { local i=$1; [ "$i" -lt ${#MODES[@]} ] || i=$((${#MODES[@]} - 1)); echo "${MODES[$i]}"; }
# mode of head I of card C (see -g): the list goes on with gpu1's heads only
# when it has more than HEADS modes, else gpu1 repeats gpu0's modes
card_mode_of() {
  if [ "$1" = 1 ] && [ ${#MODES[@]} -gt "$HEADS" ]; then mode_of $((HEADS + $2)); else mode_of "$2"; fi
}
for m in "${MODES[@]}"; do
  [[ $m =~ ^[1-9][0-9]*x[1-9][0-9]*$ ]] || die "-r: WxH expected, got '$m'"
done
M0=$(mode_of 0) M1=$(card_mode_of 1 0)

TMP=$(mktemp -d "${TMPDIR:-/tmp}/run-guest.XXXXXX")
QPID='' WPID=''
# shellcheck disable=SC2317  # (called through the trap)
cleanup() {
  trap - EXIT INT TERM HUP
  [ -n "$WPID" ] && kill "$WPID" 2>/dev/null
  if [ -n "$QPID" ] && kill -0 "$QPID" 2>/dev/null; then
    kill -TERM "$QPID" 2>/dev/null
    for _ in $(seq 50); do kill -0 "$QPID" 2>/dev/null || break; sleep 0.1; done
    kill -KILL "$QPID" 2>/dev/null
  fi
  wait 2>/dev/null
  [ -n "$QMP" ] && rm -f "$QMP"
  rm -rf "$TMP"
}
trap cleanup EXIT
trap 'exit 130' INT; trap 'exit 143' TERM; trap 'exit 129' HUP
[ -n "$LOG" ] || LOG=$TMP/console.log
: >"$LOG" || die "cannot write $LOG"
LOG=$(cd "$(dirname "$LOG")" && pwd)/$(basename "$LOG")

# KVM only where it really works: the kvm_pvm /dev/kvm of some cloud hosts
# opens fine but cannot run a stock kernel (hangs after "Probing EDD").
if [ -z "$ACCEL" ]; then
  ACCEL=tcg
  if [ -r /dev/kvm ] && [ -w /dev/kvm ] && grep -qwE 'vmx|svm' /proc/cpuinfo; then ACCEL=kvm; fi
fi
if [ "$ACCEL" = kvm ]; then
  ACC=(-accel kvm -cpu host)
else
  ACC=(-accel tcg,thread=multi -cpu max)
fi

# qemu option values: a comma is written as two
q() { echo "${1//,/,,}"; }

# Kernel command line. QEMU 7.2 without a display UI reports only head 0 as
# connected; video=Virtual-N:WxHe forces each head on and adds WxH as a
# "userdef" mode (heads >= 1 otherwise offer 5120x2160 as their first mode).
APPEND="console=ttyS0 quiet loglevel=3 panic=-1"
# With -g 2 the kernel names gpu1's connectors Virtual-(HEADS+1)... (its
# connector numbers count on across cards, in probe order: card0 first).
for c in $(seq 0 $((CARDS - 1))); do
  for i in $(seq 0 $((HEADS - 1))); do
    APPEND+=" video=Virtual-$((c * HEADS + i + 1)):$(card_mode_of "$c" "$i")e"
  done
done
if [ $# -gt 0 ]; then
  CMD64=$(printf '%s' "$*" | base64 -w0)
  [ ${#CMD64} -le 1500 ] ||
    die "command too long for the kernel command line (${#CMD64} base64 chars > 1500): put it in a script in the share and run 'sh script'"
  APPEND+=" vm.cmd=$CMD64"
fi
[ -z "$KARGS" ] || APPEND+=" $KARGS"

QARGS=(-machine q35 "${ACC[@]}" -smp "$CPUS" -m "$MEM"
  -nodefaults -no-user-config -no-reboot -display none
  -kernel "$CACHE/vmlinuz" -initrd "$CACHE/initrd.img" -append "$APPEND"
  -device "virtio-gpu-pci,id=gpu0,max_outputs=$HEADS,xres=${M0%x*},yres=${M0#*x}"
  -device virtio-keyboard-pci,id=kbd
  -device virtio-mouse-pci,id=mouse
  -device virtio-tablet-pci,id=tablet
  -fsdev "local,id=share,path=$(q "$SHARE"),security_model=none"
  -device virtio-9p-pci,fsdev=share,mount_tag=share)
if [ -d "$CACHE/libs" ]; then   # libraries of the binaries under test
  QARGS+=(-fsdev "local,id=libs,path=$(q "$(cd "$CACHE/libs" && pwd)"),security_model=none,readonly=on"
    -device virtio-9p-pci,fsdev=libs,mount_tag=libs)
fi
# The second card last: its PCI slot comes after every other device's, so
# with -g 2 the other devices keep the slots (udev ID_PATHs) they have with
# -g 1, and the guest's virtio_gpu, binding in PCI order, makes it card1.
if [ "$CARDS" = 2 ]; then
  QARGS+=(-device "virtio-gpu-pci,id=gpu1,max_outputs=$HEADS,xres=${M1%x*},yres=${M1#*x}")
fi
if [ -n "$QMP" ]; then
  case $QMP in /*) ;; *) QMP=$PWD/$QMP ;; esac
  [ ${#QMP} -lt 100 ] || die "QMP socket path too long for a unix socket: $QMP"
  rm -f "$QMP"
  QARGS+=(-qmp "unix:$(q "$QMP"),server=on,wait=off")
fi
# shellcheck disable=SC2206
[ -z "$XARGS" ] || QARGS+=($XARGS)

# qemu dies with this script even on SIGKILL (parent-death signal)
GUARD=()
setpriv --help 2>/dev/null | grep -q pdeathsig && GUARD=(setpriv --pdeathsig KILL)

if [ $# -eq 0 ]; then
  # interactive: console and monitor multiplexed on the terminal
  "${GUARD[@]}" qemu-system-x86_64 "${QARGS[@]}" \
    -chardev "stdio,id=con,mux=on,signal=off,logfile=$(q "$LOG")" \
    -serial chardev:con -mon chardev=con,mode=readline
  exit $?
fi

echo "run-guest: $ACCEL, $([ "$CARDS" = 1 ] || echo "$CARDS cards x ")$HEADS head(s) $RES, share $SHARE" >&2
T0=$(date +%s.%N)
"${GUARD[@]}" qemu-system-x86_64 "${QARGS[@]}" \
  -chardev "stdio,id=con,signal=off,logfile=$(q "$LOG")" -serial chardev:con </dev/null &
QPID=$!
"${GUARD[@]}" sleep "$TMO" &
WPID=$!
DONE=
wait -n -p DONE "$QPID" "$WPID"
QRC=$?
if [ "$DONE" != "$QPID" ]; then
  echo "run-guest: time limit of $TMO s reached, stopping qemu" >&2
  exit 124                       # cleanup (EXIT trap) stops qemu
fi
QPID=
ELAPSED=$(awk -v a="$T0" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
RC=$(tr -d '\r' <"$LOG" | sed -n 's/^VM-EXIT-CODE=\([0-9][0-9]*\)$/\1/p' | tail -n 1)
if [ -z "$RC" ]; then
  echo "run-guest: guest ended without an exit status after $ELAPSED s (qemu status $QRC)" >&2
  exit 125
fi
echo "run-guest: guest command exited with $RC after $ELAPSED s" >&2
exit "$RC"
