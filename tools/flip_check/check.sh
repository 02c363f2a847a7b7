#!/bin/sh
# check.sh - `tessera compare` against NVlabs' FLIP tool, pair by pair
# (metrics/README.md: "Checked against NVlabs' FLIP").
#
# usage: sh tools/flip_check/check.sh NVFLIP_SRC [WORK_DIR]
#   NVFLIP_SRC  a copy of github.com/NVlabs/flip (BSD-3): its C++ tool is
#               built from it into WORK_DIR with g++, outside this tree, as
#               the peer harness for Embree is; nothing of it enters tessera
#   WORK_DIR    default /tmp/tessera-flip-check
# The pairs: tools/flip_check/pairs.c from a base image (NVlabs'
# images/reference.png when the copy has it, else a 1920x1080 tessera render
# of the built-in scene), a tessera render at 1 sample per pixel against 16
# (jittered:4), and the unit tests' own pair (tests/flip_pair.h); each at
# FLIP's default 67.02 pixels per degree, some also at 10, 30 and 150.
# Prints a Markdown table (ours, theirs, |difference|) and `flip_check: N of M
# pairs within 1e-4`; exit 1 when one is not. NVlabs' tool sums its map in
# float, which moves a 1920x1080 mean by up to ~6e-5 (metrics/README.md).
set -eu
[ $# -ge 1 ] || { echo "usage: sh tools/flip_check/check.sh NVFLIP_SRC [WORK_DIR]" >&2; exit 2; }
SRC=$1
W=${2:-/tmp/tessera-flip-check}
TOL=0.0001
[ -f "$SRC/src/cpp/tool/FLIP-tool.cpp" ] || { echo "check.sh: $SRC: no src/cpp/tool/FLIP-tool.cpp (is it NVlabs/flip?)" >&2; exit 2; }
mkdir -p "$W"
make -s tessera build/flip_pairs build/tessera_tests >&2
if [ ! -x "$W/nvflip" ]; then
    echo "check.sh: building NVlabs' tool into $W/nvflip" >&2
    (cd "$SRC/src/cpp/tool" && g++ -std=c++17 -O2 -I.. -o "$W/nvflip" FLIP-tool.cpp)
fi
base=$SRC/images/reference.png
if [ ! -f "$base" ]; then
    base=$W/base.png
    ./tessera render --size 1920x1080 --out "$base" --threads 2 >&2
fi
build/flip_pairs "$W" "$base"
./tessera render --size 640x360 --out "$W/render_1spp.png" --threads 2 >&2
./tessera render --size 640x360 --sampler jittered:4 --out "$W/render_16spp.png" --threads 2 >&2
(cd tests && TESSERA_FLIP_WRITE_PAIR="$W" ../build/tessera_tests --filter 'flip/known_pair*' >&2)

within=0
total=0
row() { # label reference test [ppd]
    if [ $# -ge 4 ]; then ours=$(./tessera compare "$2" "$3" --ppd "$4"); theirs=$("$W/nvflip" -r "$2" -t "$3" -ppd "$4" -nerm -v 1)
    else ours=$(./tessera compare "$2" "$3"); theirs=$("$W/nvflip" -r "$2" -t "$3" -nerm -v 1); fi
    ours=$(echo "$ours" | sed -n 's/.*flip_mean=\([0-9.e-]*\).*/\1/p')
    theirs=$(echo "$theirs" | sed -n 's/.*Mean: *\([0-9.e-]*\).*/\1/p')
    set -- "$1" "${4:-67.02}" "$ours" "$theirs"
    ok=$(awk -v a="$3" -v b="$4" -v t=$TOL 'BEGIN { d = a - b; if (d < 0) d = -d; printf "%.6f %d", d, d <= t }')
    total=$((total + 1))
    [ "${ok#* }" = 1 ] && within=$((within + 1))
    echo "| $1 | $2 | $3 | $4 | ${ok% *} |"
}
echo "| pair | ppd | tessera | NVlabs tool | difference |"
echo "| --- | ---: | ---: | ---: | ---: |"
row "noise (Gaussian, sigma 0.05)" "$W/ref.png" "$W/noise.png"
row "blur (binomial 5x5)" "$W/ref.png" "$W/blur.png"
row "colour shift (R x0.92, B +0.06)" "$W/ref.png" "$W/shift.png"
row "aliasing: 1 vs 16x16 samples" "$W/aa_ref.png" "$W/aa_1spp.png"
row "tessera render 1 vs 16 spp" "$W/render_16spp.png" "$W/render_1spp.png"
row "tests/flip_pair.h pair" "$W/flip_pair_ref.png" "$W/flip_pair_test.png"
row "noise" "$W/ref.png" "$W/noise.png" 30
row "noise" "$W/ref.png" "$W/noise.png" 150
row "aliasing" "$W/aa_ref.png" "$W/aa_1spp.png" 10
echo "flip_check: $within of $total pairs within $TOL (base image: $base; CPU: $(lscpu | sed -n 's/^Model name: *//p'))"
[ "$within" -eq "$total" ]
