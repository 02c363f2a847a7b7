# tests/vm/smoke_lib.sh - what the harness's bash self-tests (smoke.sh,
# mpi_smoke.sh) share: `. "$HERE/smoke_lib.sh"` after setting W (the work
# folder), QMPY (the qmp.py command, an array) and SELF (the test's name for
# messages).

# users_of_w: the processes that still use the work folder, one per line
# (a /proc scan: minimal Debian images have no pgrep)
users_of_w() {
  local p c
  for p in /proc/[0-9]*; do
    c=$(tr '\0' ' ' <"$p/cmdline" 2>/dev/null) || continue
    [[ $c == *"$W"* ]] && echo "${p#/proc/}: $c"
  done
  return 0
}
# no_qemu_left: no process still uses the work folder, within 3 s
no_qemu_left() {
  local left
  for _ in $(seq 30); do
    left=$(users_of_w)
    [ -n "$left" ] || return 0
    sleep 0.1
  done
  echo "$SELF: left over: $left" >&2
  return 1
}
# size_and_colour IMAGE WxH RRGGBB: the image has that size and only that colour
size_and_colour() {
  local got
  got=$("${QMPY[@]}" colors "$1" 2) || return 1
  echo "  $1: $got"
  [ "$got" = "$2 $3:$(( ${2%x*} * ${2#*x} ))" ]
}
