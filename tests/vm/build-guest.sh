#!/usr/bin/env bash
# tests/vm/build-guest.sh CACHE [FILE...]
#
# Builds the qemu guest used by the VM tests, from Debian bookworm packages:
#   CACHE/vmlinuz       the stock Debian kernel (linux-image-amd64)
#   CACHE/initrd.img    busybox, systemd-udevd, kmod, the kernel modules for
#                       virtio-gpu / virtio-input / uinput / 9p, and /init
#                       (tests/vm/guest-init.sh)
#   CACHE/libs/         the shared libraries of the FILEs (see VM_LIBS)
# Every FILE (e.g. ./tessera) is copied to /usr/local/bin/<name> in the guest
# and all the shared libraries ldd says it needs are made available, so a
# binary built on the host runs unchanged in the guest (also a newer build of
# it, run from the shared folder, as long as it links the same libraries).
#
# Host side (as root, only what is missing, says so):
#   apt-get install qemu-system-x86 cpio kmod zstd python3
# Guest side: the kernel, udev and busybox-static .debs are fetched with
# 'apt-get download' into CACHE/debs and only unpacked (dpkg -x), never
# installed on the host. A second run reuses CACHE/debs and the unpacked
# kernel subset in CACHE/kernel-*, so it needs no network.
#
# Environment:
#   VM_OUT=DIR           write vmlinuz and initrd.img to DIR instead of CACHE
#                        (several guests sharing one download cache)
#   VM_NO_APT=1          never run apt-get install (fail if a host tool is missing)
#   VM_COMPRESS=zstd     initrd compression: zstd (default), gzip, none
#   VM_LIBS=share        the FILEs' libraries go to CACHE/libs, which
#                        run-guest.sh shares read-only (mounted on
#                        /usr/local/lib/vm): no boot time for big binaries.
#                        VM_LIBS=initrd puts them into the initrd instead.
#   VM_EXTRA_MODULES=".."  more kernel modules to put in and load at boot
#   VM_MPI=1             also ship the host's OpenMPI (openmpi-bin, installed
#                        on the host if missing): mpirun/mpiexec (orterun),
#                        orted, ompi_info, the MCA and PMIx plugins at their
#                        compiled-in paths (in the libs share like the FILEs'
#                        libraries, reached through symlinks in the initrd;
#                        with VM_LIBS=initrd in the initrd), the help files,
#                        /etc/openmpi and every library all of them need.
#                        /init then brings up lo and exports
#                        OMPI_ALLOW_RUN_AS_ROOT(_CONFIRM)=1. Default: 0
set -euo pipefail

die() { echo "build-guest: $*" >&2; exit 1; }
trap 'echo "build-guest: failed (line $LINENO: $BASH_COMMAND)" >&2' ERR
[ $# -ge 1 ] || { sed -n '2,39p' "$0" >&2; exit 2; }

CACHE=$1; shift
FILES=()
for f in "$@"; do
  [ -f "$f" ] || die "no such file: $f"
  FILES+=("$(cd "$(dirname "$f")" && pwd)/$(basename "$f")")
done
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
START=$(date +%s.%N)
PATH=$PATH:/usr/sbin:/sbin

# Modules /init loads, in this order (their dependencies come along).
MODULES="virtio_pci virtio_gpu virtio_input evdev uinput 9p 9pnet_virtio ${VM_EXTRA_MODULES:-}"
read -r -a MODLIST <<<"$MODULES"
MODULES=${MODLIST[*]}

APT=(apt-get -q -y -o DPkg::Lock::Timeout=300 -o APT::Sandbox::User=root)
export DEBIAN_FRONTEND=noninteractive

apt_update_once() {
  [ -z "${APT_UPDATED:-}" ] || return 0
  APT_UPDATED=1
  echo "build-guest: apt-get update" >&2
  "${APT[@]}" update >/dev/null 2>&1 || die "apt-get update failed (no network or no apt source?)"
}

# ---- 1. host tools ---------------------------------------------------------
need=()
command -v qemu-system-x86_64 >/dev/null || need+=(qemu-system-x86)
command -v cpio >/dev/null || need+=(cpio)
{ command -v depmod && command -v modprobe; } >/dev/null 2>&1 || need+=(kmod)
command -v python3 >/dev/null || need+=(python3)
COMPRESS=${VM_COMPRESS:-zstd}
[ "$COMPRESS" != zstd ] || command -v zstd >/dev/null || need+=(zstd)
command -v apt-get >/dev/null || die "needs apt-get (Debian host)"
case ${VM_MPI:-0} in
  0) MPI=0 ;;
  1) MPI=1; command -v orterun >/dev/null || need+=(openmpi-bin) ;;
  *) die "VM_MPI must be 0 or 1" ;;
esac
if [ ${#need[@]} -gt 0 ]; then
  if [ "${VM_NO_APT:-}" = 1 ] || [ "$(id -u)" != 0 ]; then
    die "missing host packages: ${need[*]} (as root: apt-get install ${need[*]})"
  fi
  echo "build-guest: installing on the host: ${need[*]}" >&2
  apt-cache show "${need[0]}" >/dev/null 2>&1 || apt_update_once
  if ! "${APT[@]}" install --no-install-recommends "${need[@]}" >/dev/null 2>&1; then
    apt_update_once
    "${APT[@]}" install --no-install-recommends "${need[@]}" >/dev/null ||
      die "apt-get install ${need[*]} failed"
  fi
fi

# ---- 2. guest packages (downloaded, unpacked, never installed) -------------
mkdir -p "$CACHE/debs" "${VM_OUT:-$CACHE}"
CACHE=$(cd "$CACHE" && pwd)
OUT=$(cd "${VM_OUT:-$CACHE}" && pwd)
DEBS=$CACHE/debs
# scratch space of this run (runs sharing a CACHE do not collide)
WORK=$(mktemp -d "$CACHE/tmp.XXXXXX")
trap 'rm -rf "$WORK"' EXIT

# The kernel behind the meta package (e.g. linux-image-6.1.0-56-amd64). Not
# the -cloud- flavour: it has no DRM drivers.
kernel_pkg() {
  apt-cache depends linux-image-amd64 2>/dev/null |
    sed -n 's/^ *Depends: \(linux-image-[0-9].*-amd64\)$/\1/p' | head -n 1
}
KPKG=$(kernel_pkg)
if [ -z "$KPKG" ]; then
  apt_update_once
  KPKG=$(kernel_pkg)
fi
if [ -z "$KPKG" ]; then
  # no package lists at all: fall back to a kernel already in the cache
  KPKG=$(cd "$DEBS" && ls -t linux-image-*-amd64_*.deb 2>/dev/null | head -n 1 | sed 's/_.*//')
  [ -n "$KPKG" ] || die "cannot resolve linux-image-amd64 (apt lists missing, no network?)"
  echo "build-guest: apt cannot resolve linux-image-amd64, using cached $KPKG" >&2
fi

# deb_of PKG: path of the cached .deb of PKG, downloading it if needed
deb_of() {
  local p=$1 d
  d=$(ls -t "$DEBS/${p}"_*.deb 2>/dev/null | head -n 1 || true)
  if [ -z "$d" ]; then
    mkdir -p "$WORK/dl"
    if ! (cd "$WORK/dl" && "${APT[@]}" download "$p" >/dev/null 2>&1); then
      apt_update_once
      (cd "$WORK/dl" && "${APT[@]}" download "$p" >/dev/null 2>&1) ||
        die "cannot download package $p (no network or no apt source?)"
    fi
    mv "$WORK/dl/"*.deb "$DEBS/"
    d=$(ls -t "$DEBS/${p}"_*.deb | head -n 1)
    echo "build-guest: downloaded $(basename "$d")" >&2
  fi
  echo "$d"
}
KDEB=$(deb_of "$KPKG")
UDEB=$(deb_of udev)
BDEB=$(deb_of busybox-static)

# ---- 3. kernel: vmlinuz + the module closure, kept unpacked in the cache ----
KDIR=$CACHE/kernel-$(basename "$KDEB" .deb)
KSTAMP="$(basename "$KDEB") $MODULES"
if [ "$(cat "$KDIR/stamp" 2>/dev/null)" != "$KSTAMP" ]; then
  echo "build-guest: unpacking $(basename "$KDEB")" >&2
  KX=$WORK/kx NEW=$WORK/kernel
  mkdir -p "$KX" "$NEW"
  dpkg -x "$KDEB" "$KX"
  KVER=$(ls "$KX/lib/modules")
  [ -f "$KX/boot/vmlinuz-$KVER" ] || die "no vmlinuz in $KDEB"
  depmod -b "$KX" "$KVER"
  mods=$(for m in $MODULES; do
           modprobe -d "$KX" -S "$KVER" --show-depends "$m" ||
             die "kernel $KVER has no module $m"
         done | awk '$1 == "insmod" { print $2 }' | sort -u)
  mkdir -p "$NEW/lib/modules/$KVER"
  for ko in $mods; do
    rel=${ko#"$KX/"}
    mkdir -p "$NEW/$(dirname "$rel")"
    cp "$ko" "$NEW/$rel"
  done
  cp "$KX/lib/modules/$KVER/"modules.{order,builtin,builtin.modinfo} "$NEW/lib/modules/$KVER/"
  cp "$KX/boot/vmlinuz-$KVER" "$NEW/vmlinuz"
  echo "$KVER" >"$NEW/version"
  echo "$KSTAMP" >"$NEW/stamp"
  rm -rf "$KX" "$KDIR.old"
  [ ! -e "$KDIR" ] || mv "$KDIR" "$KDIR.old"
  mv "$NEW" "$KDIR"
  rm -rf "$KDIR.old"
fi
KVER=$(cat "$KDIR/version")

# ---- 4. the initramfs tree --------------------------------------------------
X=$WORK/x ROOT=$WORK/root
mkdir -p "$X" "$ROOT"
dpkg -x "$UDEB" "$X"
dpkg -x "$BDEB" "$X"

cd "$ROOT"
# usr-merged like bookworm, so host library paths (/lib/..., /usr/lib/...) work as is
mkdir -p usr/bin usr/sbin usr/lib/x86_64-linux-gnu usr/lib64 usr/local/bin \
  dev proc sys run tmp root mnt/share etc/udev var
ln -s usr/bin bin; ln -s usr/sbin sbin; ln -s usr/lib lib; ln -s usr/lib64 lib64
ln -s ../run var/run

# put SRC DST: copy a file (following links) unless DST exists
put() {
  [ -e "$ROOT$2" ] && return 0
  mkdir -p "$ROOT$(dirname "$2")"
  cp -L "$1" "$ROOT$2"
}
# put_elf SRC DST [LIBDIR]: the file and every shared library it needs; with
# LIBDIR, libraries not in the tree yet go there (flat) instead of their path
put_elf() {
  local out lib libdir=${3:-}
  put "$1" "$2"
  out=$(ldd "$1" 2>&1) || return 0          # static or not ELF: nothing more
  if grep -q 'not found' <<<"$out"; then
    die "$1 needs libraries that are not on this host:
$(grep 'not found' <<<"$out")"
  fi
  # "libx.so => /path (0x..)" and "/lib64/ld-linux-x86-64.so.2 (0x..)"
  for lib in $(awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// { print $1 }' <<<"$out"); do
    if [ -n "$libdir" ] && [ ! -e "$ROOT$lib" ]; then
      put "$lib" "$libdir/$(basename "$lib")"
    else
      put "$lib" "$lib"
    fi
  done
}

# busybox (static) and its applets, without shadowing the real tools below
put "$X/bin/busybox" /usr/bin/busybox
for a in $("$X/bin/busybox" --list); do
  case $a in busybox|modprobe|insmod|rmmod|lsmod|modinfo|depmod) continue ;; esac
  ln -s busybox "usr/bin/$a"
done

# kmod (modprobe with real index files, as udevd's libkmod expects them)
put_elf "$(readlink -f "$(command -v modprobe)")" /usr/bin/kmod
for a in modprobe insmod rmmod lsmod modinfo depmod; do ln -s ../bin/kmod "usr/sbin/$a"; done

# udev: systemd-udevd is udevadm under another name
put_elf "$X/bin/udevadm" /usr/bin/udevadm
mkdir -p usr/lib/systemd
ln -s ../../bin/udevadm usr/lib/systemd/systemd-udevd
mkdir -p usr/lib/udev
cp -a "$X/lib/udev/rules.d" usr/lib/udev/
# libinput's rules and helpers (device groups, fuzz) from the host, if it has them
for f in /lib/udev/rules.d/*libinput*.rules /lib/udev/rules.d/*libwacom*.rules; do
  if [ -f "$f" ]; then cp "$f" usr/lib/udev/rules.d/; fi
done
for f in /lib/udev/libinput-*; do
  if [ -x "$f" ]; then put_elf "$f" "/usr/lib/udev/$(basename "$f")"; fi
done
cp "$X/etc/udev/udev.conf" etc/udev/
# hwdb: only the input entries (the full hwdb.bin is ~10 MB)
mkdir -p usr/lib/udev/hwdb.d
for f in 60-evdev 60-input-id 60-keyboard 60-sensor 70-mouse 70-pointingstick 70-touchpad; do
  if [ -f "$X/lib/udev/hwdb.d/$f.hwdb" ]; then cp "$X/lib/udev/hwdb.d/$f.hwdb" usr/lib/udev/hwdb.d/; fi
done
"$X/bin/systemd-hwdb" update --root="$ROOT" --usr >/dev/null 2>&1 ||
  echo "build-guest: warning: systemd-hwdb update failed (no input hwdb in the guest)" >&2

# data files that libinput / libwacom read at run time, from the host
for d in /usr/share/libinput /usr/share/libwacom; do
  if [ -d "$d" ]; then mkdir -p usr/share; cp -a "$d" usr/share/; fi
done

# the files under test, with their libraries: by default those libraries stay
# out of the initrd, in OUT/libs, which run-guest.sh shares read-only and the
# guest mounts on /usr/local/lib/vm (a big binary then costs no boot time)
case ${VM_LIBS:-share} in
  share) LIBDIR=/usr/local/lib/vm ;;
  initrd) LIBDIR= ;;
  *) die "VM_LIBS must be share or initrd" ;;
esac
mkdir -p usr/local/lib/vm
for f in ${FILES[@]+"${FILES[@]}"}; do
  put_elf "$f" "/usr/local/bin/$(basename "$f")" "$LIBDIR"
done

# ---- OpenMPI (VM_MPI=1) ----------------------------------------------------
# What `mpirun -np N PROG` needs on this one node, taken from the host's
# installed runtime packages (dpkg -L; not the -dev ones: no headers, no .a):
#   - orterun (as mpirun and mpiexec), orted, ompi_info in /usr/bin;
#   - the plugin trees, /usr/lib/<triplet>/openmpi (MCA components in
#     lib/openmpi3) and /usr/lib/<triplet>/pmix2 (libpmix, its plugins and
#     help files). OpenMPI and PMIx dlopen them from compiled-in absolute
#     paths, so the guest must see them at those very paths: by default the
#     trees go to the libs share (LIBDIR/mpi/<absolute path>) and the initrd
#     holds a relative symlink at each tree's path (resolves in the build tree
#     and in the guest alike); with VM_LIBS=initrd they are copied in place;
#   - /usr/share/openmpi (help texts, read at run time) and /etc/openmpi
#     (openmpi-mca-params.conf: the host's defaults) into the initrd;
#   - every library any of these ELF files needs (ldd of each plugin), like
#     the FILEs' libraries (LIBDIR or in place). A plugin whose libraries are
#     missing on the host could not load there either: shipped, with a warning.
# The guest's openmpi-mca-params.conf gets "plm = isolated" (see below).
# /etc/vm-mpi tells /init to bring up lo (OpenMPI's out-of-band TCP channel
# needs an interface) and to export OMPI_ALLOW_RUN_AS_ROOT(_CONFIRM)=1.
if [ "$MPI" = 1 ]; then
  mapfile -t MPI_PKGS < <(dpkg-query -W -f='${db:Status-Abbrev} ${Package}\n' \
    openmpi-bin openmpi-common 'libopenmpi[0-9]*' 'libpmix[0-9]*' 2>/dev/null |
    awk '$1 == "ii" { print $2 }')
  [ ${#MPI_PKGS[@]} -ge 3 ] ||
    die "VM_MPI=1: OpenMPI is not installed on the host (apt-get install openmpi-bin)"
  # sort the packages' files (and symlinks, kept as they are: libpmix.so.2 ->
  # libpmix.so.2.6.2) into plugin trees and data; paths without the leading /
  mpi_trees=() mpi_tree_files=() mpi_data=() mpi_elves=()
  while IFS= read -r p; do
    { [ -f "$p" ] || [ -L "$p" ]; } || continue   # directories come with their files
    case $p in
      /usr/share/doc/*|/usr/share/man/*|/usr/share/lintian/*) ;;
      /usr/lib/*/*/*)            # in a plugin tree: /usr/lib/<triplet>/<tree>/...
        t=${p#/usr/lib/*/}; t=${p%"/${t#*/}"}
        [[ " ${mpi_trees[*]-} " == *" $t "* ]] || mpi_trees+=("$t")
        mpi_tree_files+=("${p#/}")
        if [ ! -L "$p" ]; then case $p in *.so|*.so.*) mpi_elves+=("$p") ;; esac; fi ;;
      /usr/share/*|/etc/*) mpi_data+=("${p#/}") ;;
    esac
  done < <(dpkg -L "${MPI_PKGS[@]}" | LC_ALL=C sort -u)
  [ ${#mpi_trees[@]} -gt 0 ] || die "VM_MPI=1: no OpenMPI plugin tree in: ${MPI_PKGS[*]}"
  # copy_list DIR PATH...: each PATH of the host's / to DIR/PATH, in one pass
  copy_list() {
    local dir=$1; shift
    mkdir -p "$dir"
    printf '%s\n' "$@" | tar -C / --no-recursion -cf - -T - | tar -C "$dir" -xf -
  }
  if [ -z "$LIBDIR" ]; then
    copy_list "$ROOT" "${mpi_tree_files[@]}"
  else
    copy_list "$ROOT$LIBDIR/mpi" "${mpi_tree_files[@]}"
    for t in "${mpi_trees[@]}"; do
      mkdir -p "$ROOT$(dirname "$t")"
      ln -s "$(realpath -m --relative-to="$ROOT$(dirname "$t")" "$ROOT$LIBDIR/mpi$t")" "$ROOT$t"
    done
  fi
  copy_list "$ROOT" "${mpi_data[@]}"
  for b in orterun orted ompi_info; do
    put_elf "$(command -v "$b")" "/usr/bin/$b" "$LIBDIR"
  done
  ln -sf orterun usr/bin/mpirun; ln -sf orterun usr/bin/mpiexec
  # the plugins' libraries: one ldd over all of them (~4 s), each library once
  ldd "${mpi_elves[@]}" >"$WORK/mpi-ldd" 2>&1 || true
  awk '/:$/ { f = $1 } / => not found/ { print "build-guest: warning: " f " cannot load here (" $1 " missing), shipped as is" }' \
    "$WORK/mpi-ldd" >&2
  for lib in $(awk '$2 == "=>" && $3 ~ /^\// { print $3 } $1 ~ /^\// && $2 ~ /^\(/ { print $1 }' \
                 "$WORK/mpi-ldd" | LC_ALL=C sort -u); do
    if [ -n "$LIBDIR" ] && [ ! -e "$ROOT$lib" ]; then
      put "$lib" "$LIBDIR/${lib##*/}"
    else
      put "$lib" "$lib"
    fi
  done
  # The guest has no ssh or rsh, and orterun's default launcher (plm rsh)
  # then refuses to start at all, even for ranks on this node ("plm_rsh_agent:
  # ssh : rsh ... could not be found"): the guest's MCA defaults launch
  # locally (plm isolated: this node only, which is all a guest has).
  conf=/etc/openmpi/openmpi-mca-params.conf
  [ -f "$ROOT$conf" ] || die "VM_MPI=1: no $conf in ${MPI_PKGS[*]}"
  printf '\n# tests/vm/build-guest.sh VM_MPI=1: no ssh in the guest, one node only\nplm = isolated\n' >>"$ROOT$conf"
  # name lookups of the host name stay local (no DNS in the guest); the name
  # is the one etc/hostname gets below
  printf '127.0.0.1 localhost\n127.0.1.1 tessera-vm\n' >etc/hosts
  echo "${MPI_PKGS[*]}" >etc/vm-mpi
fi

# a loader cache (built while the shared libraries are in the tree), so that
# they and libraries in sub-directories are found without LD_LIBRARY_PATH
printf '/usr/local/lib/vm\n/usr/local/lib\n/usr/lib/x86_64-linux-gnu\n' >etc/ld.so.conf
ldconfig -X -r "$ROOT" 2>/dev/null || echo "build-guest: warning: ldconfig failed" >&2
rm -rf "$WORK/libs"
mv usr/local/lib/vm "$WORK/libs"
mkdir usr/local/lib/vm
if [ -n "$(ls -A "$WORK/libs")" ]; then : >etc/vm-libs; fi   # /init: mount the "libs" share

# kernel modules + index files for the guest's kmod
cp -a "$KDIR/lib/modules" usr/lib/
depmod -b "$ROOT" "$KVER"
echo "$MODULES" >etc/vm-modules

printf 'root:x:0:0:root:/root:/bin/sh\n' >etc/passwd
printf '%s\n' root:x:0: tty:x:5: disk:x:6: kmem:x:15: audio:x:29: video:x:44: \
  input:x:104: render:x:105: kvm:x:106: sgx:x:107: >etc/group
printf 'tessera-vm\n' >etc/hostname
install -m 755 "$HERE/guest-init.sh" init

# ---- 5. pack ----------------------------------------------------------------
case $COMPRESS in
  zstd) PACK=(zstd -q -T0 -6) ;;
  gzip) PACK=(gzip -1) ;;
  none) PACK=(cat) ;;
  *) die "VM_COMPRESS must be zstd, gzip or none" ;;
esac
find . -mindepth 1 | LC_ALL=C sort | cpio --quiet -o -H newc -R 0:0 |
  "${PACK[@]}" >"$WORK/initrd.img"
cp "$KDIR/vmlinuz" "$WORK/vmlinuz"
mv "$WORK/vmlinuz" "$OUT/vmlinuz"
mv "$WORK/initrd.img" "$OUT/initrd.img"
rm -rf "$OUT/libs"
LIBS=''
if [ -e etc/vm-libs ]; then
  mv "$WORK/libs" "$OUT/libs"
  LIBS=$(du -sh "$OUT/libs" | cut -f1)
fi
echo "$KVER" >"$OUT/kernel-version"
TREE=$(du -sh "$ROOT" | cut -f1)
cd "$CACHE"

echo "build-guest: kernel $KVER; $OUT/initrd.img $(du -h "$OUT/initrd.img" | cut -f1) ($TREE unpacked)${LIBS:+, libs $LIBS};" \
  "$(awk -v a="$START" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }') s"
