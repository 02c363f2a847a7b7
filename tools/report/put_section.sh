# put_section.sh - sourced by the scripts that write one section of REPORT.md
# on their own (tools/report_volumes.sh, tools/report_remote.sh).
# report_put_section OUT HEADING SECTION WORK: the file SECTION (starting with
# the line "## HEADING...") replaces OUT's section whose heading starts with
# "## HEADING" (up to the next "## "), else goes at OUT's end; WORK holds the
# temporary copy.
report_put_section() {
    [ -f "$1" ] || : > "$1"
    awk -v heading="## $2" -v section="$3" '
BEGIN { while ((getline l < section) > 0) text = text l "\n" }
index($0, heading) == 1 { skipping = 1; if (!done) { printf "%s\n", text; done = 1 }; next }
skipping && /^## / { skipping = 0 }
skipping { next }
{ print }
END { if (!done) printf "\n%s", text }
' "$1" > "$4/out.md" && cp "$4/out.md" "$1"
}
