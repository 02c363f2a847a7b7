#!/bin/sh
# deps.sh - make sure the Debian packages tessera builds against are installed.
# As root: installs what is missing with apt-get (and says so).
# Otherwise: prints the exact apt-get line and fails.
# Usage: tools/deps.sh [--test | --bench | --fuzz | --report]   (--test adds Chromium, which the
#        remote view's browser tests drive headless; --bench adds Embree, for the peer
#        comparison; --fuzz adds clang and its libFuzzer runtime, for make fuzz:
#        tests/fuzz/README.md; --report adds gnuplot, for make report's plots)
set -eu

PACKAGES="gcc g++ make pkg-config libdrm-dev libudev-dev libseat-dev libinput-dev libevdev-dev \
libsystemd-dev libopenimageio-dev libjson-c-dev libcriterion-dev libassimp-dev libxxhash-dev \
libwebsockets-dev libturbojpeg0-dev libopenmpi-dev openmpi-bin"
# test-only: systemd-analyze verifies configs/systemd/ (tests/test_service.c)
PACKAGES="$PACKAGES systemd"
if [ "${1:-}" = "--test" ]; then
    PACKAGES="$PACKAGES chromium"
fi
# time: GNU time -v, the peak resident memory of tools/bench_massive.sh's runs
if [ "${1:-}" = "--bench" ]; then
    PACKAGES="$PACKAGES libembree-dev time"
fi
# bookworm's clang is clang-14; libclang_rt.fuzzer*.a comes with libclang-rt-14-dev
if [ "${1:-}" = "--fuzz" ]; then
    PACKAGES="$PACKAGES clang libclang-rt-14-dev"
fi

# gnuplot without X (its png/pngcairo terminals): the plots of make report (tools/report/)
if [ "${1:-}" = "--report" ]; then
    PACKAGES="$PACKAGES gnuplot-nox"
fi

missing=""
for p in $PACKAGES; do
    status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
    [ "$status" = "installed" ] || missing="$missing $p"
done
[ -z "$missing" ] && exit 0

if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null 2>&1; then
    echo "deps: installing missing Debian packages:$missing"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    # shellcheck disable=SC2086
    apt-get install -y -qq --no-install-recommends $missing >/dev/null
    echo "deps: installed."
    exit 0
fi
echo "deps: missing Debian packages:$missing" >&2
echo "deps: install them with:" >&2
echo "  sudo apt-get install -y$missing" >&2
exit 1
