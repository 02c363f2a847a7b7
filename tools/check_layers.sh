#!/bin/sh
# check_layers.sh - the rooms of the tree and which rooms each may use (docs/layers.md).
#
#   sh tools/check_layers.sh [--root DIR]     includes: every #include "..." of every
#                                             room's .c/.h/.cpp goes to its own room or
#                                             to one the table below allows
#   sh tools/check_layers.sh [--root DIR] --objects O...
#                                             calls: every symbol an object file uses
#                                             from another of O... is defined in its own
#                                             room or in one the table allows (so a
#                                             header in a low room cannot hide a call
#                                             up into a higher one)
#
# Exit 0 when every use is allowed; else 1, with one line a use: the file, the
# include or symbol, and the two rooms. make check-layers runs both; make test
# runs make check-layers. --root: the tree to check (default: this script's),
# object paths relative to it; tests/test_check_layers.c plants bad uses in one.
#
# THE TABLE. One room a line: its path, then the rooms it may use besides itself.
# A file's room is the longest room path its path starts with; files in no room
# (tests/, the other tools/) are not checked. An entry ending in /* allows every
# room below that path. The engine's layers run lowest first: base, accel,
# geometry (its kinds are peers: none uses another), scene, render, load, frame.
set -eu

TABLE='
engine/base
engine/accel                 engine/base
engine/geometry/triangles    engine/accel engine/base
engine/geometry/spheres      engine/accel engine/base
engine/geometry/particles    engine/accel engine/base
engine/geometry/volume       engine/accel engine/base
engine/scene                 engine/geometry/* engine/accel engine/base
engine/render                engine/scene engine/geometry/* engine/accel engine/base
engine/load                  engine/render engine/scene engine/geometry/* engine/accel engine/base
engine/frame                 engine/load engine/render engine/scene engine/geometry/* engine/accel engine/base
metrics                      engine/*
seat                         engine/*
wall                         seat engine/*
input                        seat engine/*
remote                       input seat engine/*
cluster                      engine/*
tools/robust                 engine/*
app                          cluster remote input wall seat metrics tools/robust engine/*
'

root=$(dirname "$0")/..
if [ "${1:-}" = "--root" ]; then
    root=$2
    shift 2
fi
cd "$root"

# awk program shared by both modes: reads the table (TABLE), then "user used what" lines
# (file TAB target-file TAB what) and prints each use the table does not allow
CHECK='
BEGIN {
    n = split(table, lines, "\n")
    for (i = 1; i <= n; i++) {
        k = split(lines[i], w, " ")
        if (k == 0) continue
        rooms[w[1]] = 1
        allowed[w[1]] = ""
        for (j = 2; j <= k; j++) allowed[w[1]] = allowed[w[1]] " " w[j]
    }
    FS = "\t"
    bad = 0
}
# a/./b, a/x/../b -> a/b (an include may climb: "../engine/base/err.h")
function normal(path,    n, w, i, out, k) {
    n = split(path, w, "/")
    k = 0
    for (i = 1; i <= n; i++) {
        if (w[i] == "." || w[i] == "") continue
        if (w[i] == ".." && k > 0 && out[k] != "..") { k--; continue }
        out[++k] = w[i]
    }
    path = ""
    for (i = 1; i <= k; i++) path = path (i > 1 ? "/" : "") out[i]
    return path
}
function room_of(path,    r, best) {
    path = normal(path)
    best = ""
    for (r in rooms)
        if ((path == r || index(path, r "/") == 1) && length(r) > length(best)) best = r
    return best
}
function may_use(from, to,    k, w, j, p) {
    if (from == to) return 1
    k = split(allowed[from], w, " ")
    for (j = 1; j <= k; j++) {
        if (w[j] == to) return 1
        if (w[j] ~ /\/\*$/) {
            p = substr(w[j], 1, length(w[j]) - 1)
            if (index(to, p) == 1) return 1
        }
    }
    return 0
}
{
    from = room_of($1); to = room_of($2)
    if (from == "" || to == "") next
    if (!may_use(from, to)) {
        printf "check-layers: %s uses %s (%s): room %s may not use room %s\n", $1, $3, $2, from, to
        bad = 1
    }
}
END { exit bad }
'

if [ "${1:-}" = "--objects" ]; then
    shift
    # every object's defined and undefined symbols, as "object TAB D|U TAB symbol"
    for o in "$@"; do
        nm "$o" | awk -v o="$o" '$1 == "U" { print o "\tU\t" $2; next }
                                 NF == 3 && $2 ~ /^[TDBRC]$/ { print o "\tD\t" $3 }'
    done | awk -F'\t' '
        # back from build/<tree>/x/y.o to the source x/y.c (the room is the same for .cpp);
        # generated sources (build/gen/...) and the ISA kernels keep a path in their room
        function source_of(o,    s) {
            s = o
            sub(/^[^\/]+\//, "", s)       # the build tree
            sub(/\.o$/, ".c", s)
            return s
        }
        $2 == "D" { if (!($3 in def)) def[$3] = source_of($1); next }
        { use[NR] = source_of($1) "\t" $3 }
        END { for (i in use) { split(use[i], u, "\t"); if ((u[2] in def) && def[u[2]] != u[1])
                                   print u[1] "\t" def[u[2]] "\t" u[2] } }' |
        awk -v table="$TABLE" "$CHECK"
    exit $?
fi

# includes: "x.h" without a slash is the including file's own folder; one with a slash is
# from the root (-I.); an include that is no file of the tree (a library's, a generated one)
# is no room's
dirs=
for d in $(printf '%s\n' "$TABLE" | awk 'NF { print $1 }'); do
    [ -d "$d" ] && dirs="$dirs $d"
done
# (a room inside another is found twice: sort -u)
[ -n "$dirs" ] || exit 0
# shellcheck disable=SC2086
find $dirs -name '*.c' -o -name '*.h' -o -name '*.cpp' | sort -u |
while read -r f; do
    sed -n 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*"\([^"]*\)".*/\1/p' "$f" |
    while read -r inc; do
        case "$inc" in
            */*) target=$inc ;;
            *) target=$(dirname "$f")/$inc ;;
        esac
        [ -f "$target" ] && printf '%s\t%s\t#include "%s"\n' "$f" "$target" "$inc"
    done
done | awk -v table="$TABLE" "$CHECK"
