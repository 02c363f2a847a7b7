/* record.c - the input record file (record.h). */
#include "input/record.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/json_read.h"
#include "engine/log.h"

#define RECORD_MAX_BYTES (256u << 20)

static const char *const kind_names[INPUT_TXN_KIND_COUNT] = {
    [INPUT_TXN_CAMERA] = "camera", [INPUT_TXN_CURSOR] = "cursor",         [INPUT_TXN_STATUS] = "status",
    [INPUT_TXN_HIDE] = "hide",     [INPUT_TXN_UNHIDE_ALL] = "unhide-all", [INPUT_TXN_TOUR] = "tour",
    [INPUT_TXN_QUIT] = "quit",     [INPUT_TXN_GOVERNOR_STATUS] = "governor-status",
};

const char *input_txn_kind_name(input_txn_kind k)
{
    return (unsigned)k < INPUT_TXN_KIND_COUNT ? kind_names[k] : "?";
}

bool input_record_write(FILE *f, double time_s, const input_txn *t)
{
    int n = fprintf(f, "%.6f %s", time_s, input_txn_kind_name(t->kind));
    const camera_desc *c = &t->camera;
    switch (t->kind) {
    case INPUT_TXN_CAMERA:
        n = fprintf(f, " %a %a %a %a %a %a %a %a %a %a", (double)c->eye.x, (double)c->eye.y, (double)c->eye.z,
                    (double)c->look_at.x, (double)c->look_at.y, (double)c->look_at.z, (double)c->up.x,
                    (double)c->up.y, (double)c->up.z, (double)c->fov_deg);
        break;
    case INPUT_TXN_CURSOR:
        n = fprintf(f, " %d %a %a", t->on ? 1 : 0, (double)t->sx, (double)t->sy);
        break;
    case INPUT_TXN_STATUS:
        n = fputs(" \"", f);
        for (const unsigned char *s = (const unsigned char *)t->text; *s && n >= 0; s++) {
            if (*s == '"' || *s == '\\')
                n = fprintf(f, "\\%c", *s);
            else if (*s < 32 || *s > 126)
                n = fprintf(f, "\\x%02x", *s);
            else
                n = fputc(*s, f);
        }
        if (n >= 0)
            n = fputc('"', f);
        break;
    case INPUT_TXN_HIDE:
        n = fprintf(f, " %u", (unsigned)t->geom_id);
        break;
    case INPUT_TXN_TOUR:
    case INPUT_TXN_GOVERNOR_STATUS:
        n = fprintf(f, " %d", t->on ? 1 : 0);
        break;
    default:
        break;
    }
    if (n < 0 || fputc('\n', f) == EOF)
        return false;
    return fflush(f) == 0;
}

void input_record_free(input_record *r)
{
    free(r->entries);
    *r = (input_record){0};
}

/* ---- reading ------------------------------------------------------------------ */

typedef struct line_reader {
    const char *name;
    size_t line;
    const char *p, *end; /* the rest of the line */
    tess_error *err;
} line_reader;

static bool fail(line_reader *r, const char *what)
{
    return tess_error_set(r->err, "%s:%zu: %s", r->name, r->line, what);
}

static void skip_spaces(line_reader *r)
{
    while (r->p < r->end && (*r->p == ' ' || *r->p == '\t'))
        r->p++;
}

/* The next space-separated word into buf. */
static bool word(line_reader *r, char *buf, size_t size, const char *what)
{
    skip_spaces(r);
    size_t n = 0;
    while (r->p < r->end && *r->p != ' ' && *r->p != '\t') {
        if (n + 1 >= size)
            return tess_error_set(r->err, "%s:%zu: %s is too long", r->name, r->line, what);
        buf[n++] = *r->p++;
    }
    buf[n] = '\0';
    if (n == 0)
        return tess_error_set(r->err, "%s:%zu: %s is missing", r->name, r->line, what);
    return true;
}

static bool number(line_reader *r, double *out, const char *what)
{
    char buf[64];
    if (!word(r, buf, sizeof buf, what))
        return false;
    char *endp;
    errno = 0;
    double v = strtod(buf, &endp);
    if (*endp != '\0' || !isfinite(v) || errno == ERANGE)
        return tess_error_set(r->err, "%s:%zu: %s: expected a finite number, got '%s'", r->name, r->line, what,
                              buf);
    *out = v;
    return true;
}

static bool float_value(line_reader *r, float *out, const char *what)
{
    double v;
    if (!number(r, &v, what))
        return false;
    if ((double)(float)v != v)
        return tess_error_set(r->err, "%s:%zu: %s: %.17g is not exactly a float (the file is written with %%a)",
                              r->name, r->line, what, v);
    *out = (float)v;
    return true;
}

static bool flag(line_reader *r, bool *out, const char *what)
{
    char buf[8];
    if (!word(r, buf, sizeof buf, what))
        return false;
    if (strcmp(buf, "0") && strcmp(buf, "1"))
        return tess_error_set(r->err, "%s:%zu: %s: expected 0 or 1, got '%s'", r->name, r->line, what, buf);
    *out = buf[0] == '1';
    return true;
}

static bool quoted(line_reader *r, char *out, size_t size)
{
    skip_spaces(r);
    if (r->p >= r->end || *r->p != '"')
        return fail(r, "status: expected a quoted text");
    r->p++;
    size_t n = 0;
    for (;;) {
        if (r->p >= r->end)
            return fail(r, "status: the text has no closing quote");
        unsigned char ch = (unsigned char)*r->p++;
        if (ch == '"')
            break;
        if (ch == '\\') {
            if (r->p >= r->end)
                return fail(r, "status: the text ends inside an escape");
            char e = *r->p++;
            if (e == 'x') {
                if (r->end - r->p < 2 || !isxdigit((unsigned char)r->p[0]) || !isxdigit((unsigned char)r->p[1]))
                    return fail(r, "status: \\x needs two hex digits");
                char hex[3] = {r->p[0], r->p[1], 0};
                ch = (unsigned char)strtol(hex, NULL, 16);
                r->p += 2;
            } else if (e == '"' || e == '\\') {
                ch = (unsigned char)e;
            } else {
                return fail(r, "status: unknown escape (expected \\\", \\\\ or \\xHH)");
            }
        }
        if (n + 1 >= size)
            return fail(r, "status: the text is longer than 127 bytes");
        out[n++] = (char)ch;
    }
    out[n] = '\0';
    return true;
}

static bool parse_line(line_reader *r, input_record_entry *e)
{
    *e = (input_record_entry){0};
    char kind[24];
    if (!number(r, &e->time_s, "the time") || !word(r, kind, sizeof kind, "the transaction kind"))
        return false;
    if (e->time_s < 0.0)
        return fail(r, "the time is negative");
    int k = 0;
    while (k < INPUT_TXN_KIND_COUNT && strcmp(kind, kind_names[k]) != 0)
        k++;
    if (k == INPUT_TXN_KIND_COUNT)
        return tess_error_set(r->err,
                              "%s:%zu: unknown transaction kind '%s' (expected one of: camera, cursor, status, hide, "
                              "unhide-all, tour, quit, governor-status)",
                              r->name, r->line, kind);
    input_txn *t = &e->txn;
    t->kind = (input_txn_kind)k;
    switch (t->kind) {
    case INPUT_TXN_CAMERA: {
        camera_desc *c = &t->camera;
        float *v[10] = {&c->eye.x, &c->eye.y, &c->eye.z, &c->look_at.x, &c->look_at.y, &c->look_at.z,
                        &c->up.x, &c->up.y, &c->up.z, &c->fov_deg};
        static const char *const names[10] = {"camera eye.x", "camera eye.y", "camera eye.z",
                                              "camera look_at.x", "camera look_at.y", "camera look_at.z",
                                              "camera up.x", "camera up.y", "camera up.z", "camera fov_deg"};
        for (int i = 0; i < 10; i++)
            if (!float_value(r, v[i], names[i]))
                return false;
        tess_error why = {{0}};
        if (!camera_validate(c, &why))
            return tess_error_set(r->err, "%s:%zu: %s", r->name, r->line, why.msg);
        break;
    }
    case INPUT_TXN_CURSOR:
        if (!flag(r, &t->on, "cursor visibility") || !float_value(r, &t->sx, "cursor x") ||
            !float_value(r, &t->sy, "cursor y"))
            return false;
        break;
    case INPUT_TXN_STATUS:
        if (!quoted(r, t->text, sizeof t->text))
            return false;
        break;
    case INPUT_TXN_HIDE: {
        double id;
        if (!number(r, &id, "hide geometry id"))
            return false;
        if (id < 0.0 || id > 4294967294.0 || id != floor(id))
            return fail(r, "hide: the geometry id must be a whole number >= 0");
        t->geom_id = (uint32_t)id;
        break;
    }
    case INPUT_TXN_TOUR:
        if (!flag(r, &t->on, "tour on/off"))
            return false;
        break;
    case INPUT_TXN_GOVERNOR_STATUS:
        if (!flag(r, &t->on, "governor status on/off"))
            return false;
        break;
    default:
        break;
    }
    skip_spaces(r);
    if (r->p < r->end)
        return fail(r, "unexpected text after the transaction");
    return true;
}

bool input_record_parse(const char *name, const char *text, size_t len, input_record *out, tess_error *err)
{
    input_record rec = {0};
    line_reader r = {.name = name, .line = 0, .err = err};
    const char *p = text, *end = text + len;
    bool header = false;
    double last_s = 0.0;
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        const char *line_end = eol ? eol : end;
        r.line++;
        r.p = p;
        r.end = line_end;
        if (r.end > r.p && r.end[-1] == '\r')
            r.end--;
        p = eol ? eol + 1 : end;
        skip_spaces(&r);
        if (r.p == r.end || *r.p == '#')
            continue;
        if (!eol && header) { /* see CUT OFF in record.h */
            rec.cut_line = r.line;
            tess_error_set(&rec.warning,
                           "%s:%zu: the last line has no newline at its end (the recording was cut off?): left out; "
                           "%zu transaction%s before it replay",
                           name, r.line, rec.count, rec.count == 1 ? "" : "s");
            break;
        }
        if (!header) {
            if ((size_t)(r.end - r.p) != strlen(INPUT_RECORD_HEADER) ||
                memcmp(r.p, INPUT_RECORD_HEADER, strlen(INPUT_RECORD_HEADER)) != 0) {
                fail(&r, "not an input record (the first line must be \"" INPUT_RECORD_HEADER "\")");
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
        if (!parse_line(&r, e))
            goto fail;
        if (e->time_s < last_s) {
            tess_error_set(err, "%s:%zu: time %.6f is before the previous line's %.6f", name, r.line, e->time_s,
                           last_s);
            goto fail;
        }
        last_s = e->time_s;
        rec.count++;
    }
    if (!header) {
        tess_error_set(err, "%s: empty file (expected the line \"" INPUT_RECORD_HEADER "\")", name);
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
