# tests/vm/host_lib.sh - what the end-to-end tests (tests/vm_*.sh) share on the
# host; `. tests/vm/host_lib.sh` from the repository root after setting NAME
# (the test's name for messages) and W (the work folder, shared with the
# guest). It sets CACHE, GPID (empty; the test stores run-guest.sh's pid
# there), the counters and clock behind ok / bad / elapsed, and the traps that
# stop the guest and remove W on exit (VM_KEEP=1 keeps it).
CACHE=${TESSERA_VM_CACHE:-/tmp/tessera-vm-cache}
GPID=
cleanup() {
    [ -n "$GPID" ] && kill "$GPID" 2>/dev/null
    if [ -n "${VM_KEEP:-}" ]; then echo "$NAME: kept $W"; else rm -rf "$W"; fi
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM
PASS=0 FAIL=0
ok() { echo "$NAME: PASS: $*"; PASS=$((PASS + 1)); }
bad() { echo "$NAME: FAIL: $*"; FAIL=$((FAIL + 1)); }
T0=$(date +%s)
elapsed() { echo $(($(date +%s) - T0)); }
mkdir -p "$CACHE"

# copy_tessera: the binary under test ($TESSERA_BIN, default ./tessera), copied to
# $W/bin/tessera once, so that the guest and the host's native renders run the same
# one even when ./tessera is rebuilt while the test runs
copy_tessera() {
    if ! cp "${TESSERA_BIN:-./tessera}" "$W/bin/tessera"; then
        echo "$NAME: FAIL: no ${TESSERA_BIN:-./tessera} to test (make tessera)"
        exit 1
    fi
}

# vm_build OUT FILE...: the guest with FILEs in OUT (VM_OUT; downloads in
# CACHE). On failure: SKIPPED (exit 0) when qemu or the packages cannot be
# installed here, said in the last line, never silently; else FAIL (exit 1).
vm_build() {
    _out=$1
    shift
    if ! VM_OUT="$_out" tests/vm/build-guest.sh "$CACHE" "$@" > "$W/build.log" 2>&1; then
        if ! command -v qemu-system-x86_64 > /dev/null 2>&1 ||
            grep -q "cannot download\|Unable to locate\|Could not resolve" "$W/build.log"; then
            tail -n 3 "$W/build.log"
            echo "$NAME: SKIPPED: qemu or the guest packages cannot be installed here (see above)"
            exit 0
        fi
        tail -n 20 "$W/build.log"
        echo "$NAME: FAIL: building the guest failed"
        exit 1
    fi
}

# vm_guest: the one guest the three VM tests boot, into GUEST: the binary under test
# ($W/bin/tessera, copy_tessera), tests/vm/uinput_touch.c built here ($W/bin/uinput_touch)
# and OpenMPI (VM_MPI=1). It lives in $CACHE/guest-KEY, KEY a hash of everything that goes
# into it (those two binaries, the build and init scripts, their settings, the host's
# installed packages: the libraries shipped with them), so it is built once and the next
# test (make test runs three in a row) finds it made and boots it as is; a different
# binary gets its own folder (folders unused for a day are removed).
guest_key() {
    { cat tests/vm/build-guest.sh tests/vm/guest-init.sh "$W/bin/tessera" "$W/bin/uinput_touch"
      echo "${VM_COMPRESS:-} ${VM_LIBS:-} ${VM_EXTRA_MODULES:-}"
      stat -c '%Y %s' /var/lib/dpkg/status 2>/dev/null; } | sha256sum | cut -c1-16
}
vm_guest() {
    if ! gcc -std=c11 -O2 -Wall -Wextra -o "$W/bin/uinput_touch" tests/vm/uinput_touch.c > "$W/cc.log" 2>&1; then
        cat "$W/cc.log"
        echo "$NAME: FAIL: tests/vm/uinput_touch.c does not build"
        exit 1
    fi
    GUEST=$CACHE/guest-$(guest_key)
    find "$CACHE" -maxdepth 1 -name 'guest-*' -mtime +0 -exec rm -rf {} + 2>/dev/null
    if [ -f "$GUEST/ready" ]; then
        touch "$GUEST"
        echo "$NAME: guest $GUEST already built, reused"
        return 0
    fi
    _t=$(date +%s)
    rm -rf "$GUEST.tmp.$$"
    _tmp=$GUEST.tmp.$$
    VM_MPI=1 vm_build "$_tmp" "$W/bin/tessera" "$W/bin/uinput_touch"
    : > "$_tmp/ready"
    # filed under the key as it is now: the build may have installed qemu & co. on the host
    GUEST=$CACHE/guest-$(guest_key)
    # another test building the same guest at the same time: the first one stays
    mv -T "$_tmp" "$GUEST" 2>/dev/null || rm -rf "$_tmp"
    echo "$NAME: guest $GUEST built in $(($(date +%s) - _t)) s"
}

# wait_for FILE SECS: until FILE is in the share; 1 when the guest is gone or time ran out
wait_for() {
    _n=0
    while [ ! -e "$W/$1" ]; do
        kill -0 "$GPID" 2>/dev/null && [ $_n -lt $(($2 * 10)) ] || return 1
        sleep 0.1
        _n=$((_n + 1))
    done
}

# guest_step N 'COMMAND' [SECS]: the guest runs COMMAND (sh; guest_lib.sh's
# run_steps) while the program runs; waits for it (default: 4 frames' time, frames_s
# below: the guest's CPUs are busy rendering). Its output is in $W/cmd-N.log, its exit
# status in $W/cmd-N.done.
guest_step() {
    printf '%s\n' "$2" > "$W/cmd-$1.tmp" && mv "$W/cmd-$1.tmp" "$W/cmd-$1.sh" && wait_for "cmd-$1.done" "${3:-$(frames_s 4)}"
}

# ---- frames: the tests wait for frames the guest's tessera reports, never for
# seconds. Run tessera in the guest with TESSERA_LOG=debug: the DRM display then
# logs "CARD: frame N on screen" when the flips to frame N completed (every output
# shows frame N or a later one from then on). Under TCG a frame takes 0.3-8 s
# depending on the host's CPU model, so every time-out below is a number of
# frames times FRAME_MS, the slowest frame time seen so far.
FRAME_MS=1000
now_ms() { date +%s%3N; }
# last_frame LOG: the newest frame on screen in $W/LOG; -1 before the first
last_frame() {
    _lf=$(grep -o 'frame [0-9]* on screen' "$W/$1" 2>/dev/null | tail -n 1 | cut -d' ' -f2)
    echo "${_lf:--1}"
}
# frames_s K: seconds to allow for K frames: 4 times the slowest frame time, plus 30 s
frames_s() { echo $((30 + 4 * $1 * FRAME_MS / 1000)); }
# wait_frame LOG N [K]: until frame N or a later one is on screen (time-out: K frames'
# worth, default N - the frame on screen now); 1 when the guest is gone or time ran
# out. Updates FRAME_MS from the frames it saw go by.
wait_frame() {
    _wf0=$(last_frame "$1")
    _wft0=$(now_ms)
    _wfk=${3:-$(($2 - _wf0))}
    [ "$_wfk" -ge 1 ] || _wfk=1
    _wfmax=$(frames_s "$_wfk")
    _wft=$(elapsed)
    while :; do
        _wf=$(last_frame "$1")
        [ "$_wf" -ge "$2" ] && break
        kill -0 "$GPID" 2>/dev/null && [ $(($(elapsed) - _wft)) -lt "$_wfmax" ] || return 1
        sleep 0.2
    done
    if [ "$_wf0" -ge 0 ] && [ "$_wf" -gt "$_wf0" ]; then
        _wfms=$((($(now_ms) - _wft0) / (_wf - _wf0)))
        [ "$_wfms" -gt "$FRAME_MS" ] && FRAME_MS=$_wfms
    fi
    return 0
}
# log_count LOG TEXT: how many lines of $W/LOG have TEXT (fixed string)
log_count() {
    _lc=$(grep -cF "$2" "$W/$1" 2>/dev/null)
    echo "${_lc:-0}"
}
# log_wait LOG TEXT SECS [N]: until $W/LOG has more than N (default 0) lines with TEXT
log_wait() {
    _lwt=$(elapsed)
    while [ "$(log_count "$1" "$2")" -le "${4:-0}" ]; do
        kill -0 "$GPID" 2>/dev/null && [ $(($(elapsed) - _lwt)) -lt "$3" ] || return 1
        sleep 0.2
    done
}
