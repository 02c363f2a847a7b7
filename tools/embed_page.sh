#!/bin/sh
# embed_page.sh IN OUT - the remote view's page (remote/page.html) as C
# (remote/page.h: remote_page_html, remote_page_html_bytes), so the kiosk
# serves it from its binary. od, not xxd: od is in every Debian (coreutils).
set -eu
in=$1
out=$2
{
    echo "/* generated from $in by tools/embed_page.sh: do not edit */"
    echo '#include "remote/page.h"'
    echo 'const char remote_page_html[] = {'
    od -An -v -tx1 "$in" | sed -e 's/ \([0-9a-f][0-9a-f]\)/0x\1,/g'
    echo '0x00};'
    echo 'const size_t remote_page_html_bytes = sizeof remote_page_html - 1;'
} > "$out.tmp"
mv "$out.tmp" "$out"
