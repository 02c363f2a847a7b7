/* record.c - the input record file (record.h). */
#include "record.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/json_read.h"
#include "engine/base/log.h"

#define RECORD_MAX_BYTES (256u << 20)

const char *input_txn_kind_name(input_txn_kind k) { return txn_kind_name(k); }

bool input_record_write(FILE *f, double time_s, const input_txn *t)
{
    char line[TXN_TEXT_MAX];
    if (txn_encode_text(t, line, sizeof line) == 0)
        return false; /* an invalid record: nothing a replay could read */
    if (fprintf(f, "%.6f %s\n", time_s, line) < 0)
        return false;
    return fflush(f) == 0;
}

void input_record_free(input_record *r)
{
    free(r->entries);
    free(r->name);
    *r = (input_record){0};
}

/* ---- reading ------------------------------------------------------------------ */

/* One line: the time, then a record in txn.h's text form of the file's version. */
static bool parse_line(const char *name, size_t line, const char *p, const char *end, txn_text_version version,
                       input_record_entry *e, tess_error *err)
{
    memset(e, 0, sizeof *e); /* padding too: entries compare byte for byte */
    while (p < end && (*p == ' ' || *p == '\t'))
        p++;
    const char *w = p;
    while (p < end && *p != ' ' && *p != '\t')
        p++;
    char buf[64];
    size_t n = (size_t)(p - w);
    if (n == 0)
        return tess_error_set(err, "%s:%zu: the time is missing", name, line);
    if (n >= sizeof buf)
        return tess_error_set(err, "%s:%zu: the time is too long", name, line);
    memcpy(buf, w, n);
    buf[n] = '\0';
    char *endp;
    errno = 0;
    double t = strtod(buf, &endp);
    if (*endp != '\0' || !isfinite(t) || errno == ERANGE) {
        for (char *c = buf; *c; c++)
            if ((unsigned char)*c < 32 || *c == 127)
                *c = '?';
        return tess_error_set(err, "%s:%zu: the time: expected a finite number, got '%s'", name, line, buf);
    }
    if (t < 0.0)
        return tess_error_set(err, "%s:%zu: the time is negative", name, line);
    e->time_s = t;
    if (!txn_decode_text(p, (size_t)(end - p), version, &e->txn, err)) {
        tess_error_prefix(err, "%s:%zu: ", name, line);
        return false;
    }
    return true;
}

bool input_record_parse(const char *name, const char *text, size_t len, input_record *out, tess_error *err)
{
    input_record rec = {0};
    const char *p = text, *end = text + len;
    size_t line = 0;
    bool header = false;
    txn_text_version version = TXN_TEXT_V2;
    double last_s = 0.0;
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        const char *line_end = eol ? eol : end;
        line++;
        const char *lp = p, *le = line_end;
        if (le > lp && le[-1] == '\r')
            le--;
        p = eol ? eol + 1 : end;
        while (lp < le && (*lp == ' ' || *lp == '\t'))
            lp++;
        if (lp == le || *lp == '#')
            continue;
        if (!eol && header) { /* see CUT OFF in record.h */
            rec.cut_line = line;
            tess_error_set(&rec.warning,
                           "%s:%zu: the last line has no newline at its end (the recording was cut off?): left out; "
                           "%zu transaction%s before it replay",
                           name, line, rec.count, rec.count == 1 ? "" : "s");
            break;
        }
        if (!header) {
            size_t n = (size_t)(le - lp);
            if (n == strlen(INPUT_RECORD_HEADER_V1) && memcmp(lp, INPUT_RECORD_HEADER_V1, n) == 0)
                version = TXN_TEXT_V1;
            else if (n != strlen(INPUT_RECORD_HEADER) || memcmp(lp, INPUT_RECORD_HEADER, n) != 0) {
                tess_error_set(err,
                               "%s:%zu: not an input record (the first line must be \"" INPUT_RECORD_HEADER
                               "\" or \"" INPUT_RECORD_HEADER_V1 "\")",
                               name, line);
                goto fail;
            }
            header = true;
            continue;
        }
        if (rec.count == rec.capacity) {
            size_t cap = rec.capacity ? rec.capacity * 2 : 64;
            input_record_entry *grown = realloc(rec.entries, cap * sizeof *grown);
            if (!grown) {
                tess_error_set(err, "%s: out of memory", name);
                goto fail;
            }
            rec.entries = grown;
            rec.capacity = cap;
        }
        input_record_entry *e = &rec.entries[rec.count];
        if (!parse_line(name, line, lp, le, version, e, err))
            goto fail;
        if (e->time_s < last_s) {
            tess_error_set(err, "%s:%zu: time %.6f is before the previous line's %.6f", name, line, e->time_s,
                           last_s);
            goto fail;
        }
        last_s = e->time_s;
        e->line = line;
        rec.count++;
    }
    if (!header) {
        tess_error_set(err, "%s: empty file (expected the line \"" INPUT_RECORD_HEADER "\")", name);
        goto fail;
    }
    rec.name = strdup(name);
    if (!rec.name) {
        tess_error_set(err, "%s: out of memory", name);
        goto fail;
    }
    *out = rec;
    return true;
fail:
    input_record_free(&rec);
    return false;
}

bool input_record_load(const char *file, input_record *out, tess_error *err)
{
    size_t len;
    char *text = jr_read_file(file, RECORD_MAX_BYTES, "an input record", &len, err);
    if (!text)
        return false;
    bool ok = input_record_parse(file, text, len, out, err);
    free(text);
    if (ok && out->cut_line)
        log_warn("%s", out->warning.msg);
    return ok;
}
