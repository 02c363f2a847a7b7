#!/bin/sh
# /init of the test guest (tests/vm/guest-init.sh, installed by build-guest.sh).
#
# 1. mounts proc, sys, devtmpfs, devpts, tmpfs on /run /tmp /dev/shm
#    (/dev/shm must be a tmpfs: OpenMPI's vader transport maps its segments there)
# 2. loads the modules listed in /etc/vm-modules (modprobe, dependencies too)
# 3. starts systemd-udevd, triggers the input/drm/misc devices (vm.udev=all:
#    every device), waits for udev to settle
# 4. mounts the 9p share (tag "share") on /mnt/share, and the read-only one
#    with the libraries of the binaries under test (tag "libs") if any
#    With OpenMPI in the guest (build-guest.sh VM_MPI=1, /etc/vm-mpi): brings
#    up the loopback interface (OpenMPI's out-of-band TCP channel needs an
#    interface) and exports OMPI_ALLOW_RUN_AS_ROOT=1 and
#    OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 (everything runs as root here)
# 5. runs the command run-guest.sh passed as vm.cmd=<base64 of a shell command
#    line> on the kernel command line, with /mnt/share as working directory
#    and /dev/null as stdin, then prints "VM-EXIT-CODE=<status>"
# 6. powers the machine off (qemu then exits)
#
# Kernel command line knobs: vm.udev=0 (no udevd), vm.udev=all, vm.shell=1 (a shell on
# the console after the command), vm.dmesg=1 (print the kernel log at the end).
export PATH=/usr/local/bin:/usr/sbin:/usr/bin HOME=/root LANG=C TERM=linux
set -f    # the command line is split below, never globbed

mount -t proc proc /proc
mount -t sysfs sysfs /sys
mount -t devtmpfs devtmpfs /dev
mkdir -p /dev/pts /dev/shm
mount -t devpts -o gid=5,mode=620 devpts /dev/pts
mount -t tmpfs -o mode=1777 tmpfs /dev/shm
mount -t tmpfs -o mode=755 tmpfs /run
mount -t tmpfs -o mode=1777 tmpfs /tmp
hostname -F /etc/hostname 2>/dev/null

# knob NAME: the value of vm.NAME=... on the kernel command line
knob() {
  for word in $(cat /proc/cmdline); do
    case $word in "vm.$1="*) echo "${word#*=}" ;; esac
  done
}
say() { echo "vm-init: $*"; }

for m in $(cat /etc/vm-modules); do
  modprobe "$m" || say "modprobe $m failed"
done

if [ "$(knob udev)" != 0 ]; then
  /usr/lib/systemd/systemd-udevd --daemon --resolve-names=never 2>/dev/null ||
    say "systemd-udevd did not start"
  if [ "$(knob udev)" = all ]; then
    udevadm trigger --type=subsystems --action=add
    udevadm trigger --type=devices --action=add
  else
    # only what libinput and KMS clients look at: 1 s instead of 2 under TCG
    udevadm trigger --action=add --subsystem-match=input --subsystem-match=drm \
      --subsystem-match=misc --subsystem-match=graphics
  fi
  udevadm settle --timeout=30 || say "udev did not settle in 30 s"
fi

SHARE_OK=0
set +f
if cat /sys/bus/virtio/drivers/9pnet_virtio/*/mount_tag 2>/dev/null | grep -q share; then
  if mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144 share /mnt/share; then
    SHARE_OK=1
  else
    say "cannot mount the 9p share"
  fi
fi
set -f

# the libraries of the binaries under test (build-guest.sh VM_LIBS=share)
if [ -e /etc/vm-libs ]; then
  mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144,cache=loose,ro libs /usr/local/lib/vm ||
    say "cannot mount the libs share: the binaries under test will not start"
fi

if [ -e /etc/vm-mpi ]; then
  ip link set lo up 2>/dev/null || ifconfig lo 127.0.0.1 up || say "cannot bring up lo"
  export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
fi

say "up after $(cut -d' ' -f1 /proc/uptime) s"
CMD64=$(knob cmd)
if [ -n "$CMD64" ]; then
  if echo "$CMD64" | base64 -d >/run/vm-cmd 2>/dev/null; then
    if [ "$SHARE_OK" = 1 ]; then
      (cd /mnt/share && exec sh /run/vm-cmd </dev/null)
      rc=$?
    else
      say "no share, command not run"
      rc=125
    fi
  else
    say "vm.cmd is not valid base64"
    rc=125
  fi
  [ "$(knob dmesg)" = 1 ] && dmesg
  echo "VM-EXIT-CODE=$rc"
fi
if [ -z "$CMD64" ] || [ "$(knob shell)" = 1 ]; then
  cd /mnt/share 2>/dev/null || cd /
  setsid cttyhack sh
fi

cd /
sync
umount /mnt/share 2>/dev/null
poweroff -f
echo o >/proc/sysrq-trigger
sleep 10
