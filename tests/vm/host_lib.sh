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
# run_steps) while the program runs; waits for it (default 30 s). Its output
# is in $W/cmd-N.log, its exit status in $W/cmd-N.done.
guest_step() {
    printf '%s\n' "$2" > "$W/cmd-$1.tmp" && mv "$W/cmd-$1.tmp" "$W/cmd-$1.sh" && wait_for "cmd-$1.done" "${3:-30}"
}
