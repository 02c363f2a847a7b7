# tests/vm/guest_lib.sh - what a test's guest script (busybox sh, run in the
# share) uses: copy it into the share and `. ./guest_lib.sh`. The host side of
# the step protocol is host_lib.sh.

# alive PID: a process that has not ended (a zombie has)
alive() {
    [ -r "/proc/$1/stat" ] && read -r st < "/proc/$1/stat" 2>/dev/null || return 1
    st=${st##*") "}
    [ "${st%% *}" != Z ]
}

# wait_for FILE SECS: until FILE exists
wait_for() {
    i=0
    while [ ! -e "$1" ] && [ $i -lt $(($2 * 10)) ]; do sleep 0.1; i=$((i + 1)); done
    [ -e "$1" ]
}

# run_steps PID SECS [STOP]: while PID runs, run each cmd-N.sh (N = 1, 2, ...
# in order, going on from an earlier run_steps) the host drops in, output to
# cmd-N.log, exit status to cmd-N.done (fd 3 closed for them); until the host
# creates `done` (or the file STOP), PID ends, or SECS pass without a step.
run_steps() {
    n=${n:-1} i=0
    while [ ! -e done ] && [ ! -e "${3:-done}" ] && [ $i -lt $(($2 * 10)) ] && alive "$1"; do
        if [ -e cmd-$n.sh ]; then
            sh cmd-$n.sh > cmd-$n.log 2>&1 3<&-
            echo $? > cmd-$n.tmp
            mv cmd-$n.tmp cmd-$n.done
            n=$((n + 1))
            i=0
        else
            sleep 0.1
            i=$((i + 1))
        fi
    done
}

# stop_program PID [RCFILE]: SIGTERM if it still runs, SIGKILL 30 s later; its
# exit status (or why there is none) to RCFILE (default tessera.rc)
stop_program() {
    alive "$1" && kill -TERM "$1" 2>/dev/null
    i=0
    while alive "$1" && [ $i -lt 300 ]; do sleep 0.1; i=$((i + 1)); done
    if alive "$1"; then
        kill -KILL "$1"
        wait "$1"
        echo "none (still running 30 s after SIGTERM; killed)" > "${2:-tessera.rc}"
    else
        wait "$1"
        echo $? > "${2:-tessera.rc}"
    fi
}
