/* ply_read.c - the PLY format level (ply_read.h): the chunked reader, the
 * header, values in either encoding, and the messages that cite them. */
#include "ply_read.h"

#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "engine/base/progress.h"

/* fread size: big enough that system calls and the partial-record memmove
 * between chunks cost nothing measurable */
#define READ_CHUNK_BYTES ((size_t)1 << 20)
/* the first buffer of a file smaller than a chunk: its size, but at least this
 * (a 400-byte cube needs no megabyte; the buffer still grows for long lines) */
#define READ_MIN_BYTES ((size_t)4 << 10)
/* the longest header line we parse: "property list uchar int vertex_indices" */
#define HEADER_WORDS_MAX 5

static const struct type_name {
    const char *name;   /* as written in the header */
    enum ply_type type; /* what it means */
} type_names[] = {
    {"char", PLY_INT8},     {"int8", PLY_INT8},       {"uchar", PLY_UINT8},   {"uint8", PLY_UINT8},
    {"short", PLY_INT16},   {"int16", PLY_INT16},     {"ushort", PLY_UINT16}, {"uint16", PLY_UINT16},
    {"int", PLY_INT32},     {"int32", PLY_INT32},     {"uint", PLY_UINT32},   {"uint32", PLY_UINT32},
    {"float", PLY_FLOAT32}, {"float32", PLY_FLOAT32}, {"double", PLY_FLOAT64}, {"float64", PLY_FLOAT64},
};

/* ---- messages ---------------------------------------------------------- */

bool ply_fail(ply_file *f, const char *fmt, ...)
{
    char what[TESS_ERROR_MSG_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    if (f->cite_line)
        return tess_error_set(f->err, "%s:%" PRIu64 ": %s", f->path, f->line, what);
    return tess_error_set(f->err, "%s: %s", f->path, what);
}

static const char *errno_text(int code, char *buf, size_t size)
{
    if (strerror_r(code, buf, size) != 0)
        snprintf(buf, size, "error %d", code);
    return buf;
}

bool ply_fail_input(ply_file *f, const ply_element *e, uint64_t index, bool before)
{
    const ply_reader *r = &f->in;
    if (r->read_errno) {
        char text[128];
        return ply_fail(f, "read error: %s", errno_text(r->read_errno, text, sizeof text));
    }
    if (r->out_of_memory)
        return ply_fail(f, "out of memory");
    if (r->line_too_long)
        return ply_fail(f, "%s %" PRIu64 ": line longer than %zu bytes", e->name, index,
                        (size_t)PLY_BODY_LINE_MAX_BYTES);
    bool one = e->count == 1;
    const char *noun = e->kind == PLY_ELEMENT_VERTEX ? (one ? "vertex" : "vertices")
                       : e->kind == PLY_ELEMENT_FACE ? (one ? "face" : "faces")
                                                     : (one ? "element" : "elements");
    return ply_fail(f, "truncated: expected %" PRIu64 " %s%s%s, file ends %s %s %" PRIu64, e->count,
                    e->kind == PLY_ELEMENT_OTHER ? e->name : "", e->kind == PLY_ELEMENT_OTHER ? " " : "", noun,
                    before ? "before" : "in", e->name, index);
}

/* ---- the chunked reader ------------------------------------------------- */

bool ply_reader_init(ply_reader *r, FILE *file, uint64_t file_bytes)
{
    *r = (ply_reader){.file = file};
    r->capacity = file_bytes < READ_MIN_BYTES ? READ_MIN_BYTES
                  : file_bytes < READ_CHUNK_BYTES ? (size_t)file_bytes
                                                  : READ_CHUNK_BYTES;
    r->buf = malloc(r->capacity + 1);
    return r->buf != NULL;
}

void ply_reader_finish(ply_reader *r)
{
    free(r->buf);
    r->buf = NULL;
    r->capacity = r->len = r->pos = 0;
}

static bool reader_grow(ply_reader *r, size_t limit)
{
    if (r->capacity >= limit) {
        r->line_too_long = true;
        return false;
    }
    size_t capacity = r->capacity > limit / 2 ? limit : 2 * r->capacity;
    unsigned char *buf = realloc(r->buf, capacity + 1);
    if (!buf) {
        r->out_of_memory = true;
        return false;
    }
    r->buf = buf;
    r->capacity = capacity;
    return true;
}

bool ply_reader_fill(ply_reader *r, size_t limit)
{
    if (r->eof || r->read_errno)
        return false;
    if (r->pos > 0) {
        memmove(r->buf, r->buf + r->pos, r->len - r->pos);
        r->base += r->pos;
        r->len -= r->pos;
        r->pos = 0;
    }
    if (r->len == r->capacity && !reader_grow(r, limit))
        return false;
    size_t got = fread(r->buf + r->len, 1, r->capacity - r->len, r->file);
    if (got == 0) {
        if (ferror(r->file))
            r->read_errno = errno ? errno : EIO;
        else
            r->eof = true;
        return false;
    }
    r->len += got;
    progress_set(r->progress, r->base + r->len);
    return true;
}

uint64_t ply_reader_skip(ply_reader *r, uint64_t n)
{
    uint64_t done = 0;
    while (done < n) {
        if (r->pos == r->len && !ply_reader_fill(r, r->capacity))
            break;
        size_t avail = r->len - r->pos;
        size_t step = n - done < avail ? (size_t)(n - done) : avail;
        r->pos += step;
        done += step;
    }
    return done;
}

bool ply_reader_line(ply_reader *r, size_t limit, char **line)
{
    size_t scanned = 0; /* unread bytes already searched for '\n' */
    for (;;) {
        char *start = (char *)r->buf + r->pos;
        size_t avail = r->len - r->pos;
        char *end = memchr(start + scanned, '\n', avail - scanned);
        if (end) {
            r->pos += (size_t)(end - start) + 1;
        } else {
            scanned = avail;
            if (avail >= limit) {
                r->line_too_long = true;
                return false;
            }
            if (ply_reader_fill(r, limit))
                continue;
            if (!r->eof || avail == 0)
                return false;
            start = (char *)r->buf + r->pos; /* the last line, without a newline */
            end = start + avail;
            r->pos = r->len;
        }
        if (end > start && end[-1] == '\r')
            end--;
        *end = '\0';
        *line = start;
        return true;
    }
}

/* ---- types ------------------------------------------------------------- */

unsigned ply_type_bytes(enum ply_type t)
{
    switch (t) {
    case PLY_INT8:
    case PLY_UINT8:
        return 1;
    case PLY_INT16:
    case PLY_UINT16:
        return 2;
    case PLY_INT32:
    case PLY_UINT32:
    case PLY_FLOAT32:
        return 4;
    case PLY_FLOAT64:
        return 8;
    case PLY_NONE:
        break;
    }
    return 0;
}

bool ply_type_is_integer(enum ply_type t) { return t >= PLY_INT8 && t <= PLY_UINT32; }

const char *ply_type_label(enum ply_type t)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++)
        if (type_names[i].type == t)
            return type_names[i].name;
    return "?";
}

/* The values an integer type holds; an empty range for the float types. */
static void type_range(enum ply_type t, int64_t *lo, int64_t *hi)
{
    *lo = 0, *hi = -1;
    switch (t) {
    case PLY_INT8: *lo = INT8_MIN, *hi = INT8_MAX; break;
    case PLY_UINT8: *lo = 0, *hi = UINT8_MAX; break;
    case PLY_INT16: *lo = INT16_MIN, *hi = INT16_MAX; break;
    case PLY_UINT16: *lo = 0, *hi = UINT16_MAX; break;
    case PLY_INT32: *lo = INT32_MIN, *hi = INT32_MAX; break;
    case PLY_UINT32: *lo = 0, *hi = UINT32_MAX; break;
    default: break;
    }
}

/* ---- ascii values ------------------------------------------------------ */

static inline bool is_blank_char(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* The next whitespace-separated token of the current ascii line, NUL-terminated
 * in place; false at the end of the line. */
static inline bool ascii_token(ply_file *f, char **token)
{
    char *p = f->cursor;
    while (is_blank_char(*p))
        p++;
    if (*p == '\0') {
        f->cursor = p;
        return false;
    }
    *token = p;
    while (*p != '\0' && !is_blank_char(*p))
        p++;
    if (*p != '\0')
        *p++ = '\0';
    f->cursor = p;
    return true;
}

/* A whole token as a decimal integer with an optional sign (what strtoll
 * does, at a third of its cost, and without locale). Magnitudes beyond
 * INT64_MAX saturate, so the caller's range check reports them. */
static inline bool parse_decimal(const char *s, int64_t *out)
{
    bool negative = *s == '-';
    if (*s == '-' || *s == '+')
        s++;
    if (*s == '\0')
        return false;
    int64_t v = 0;
    for (; *s != '\0'; s++) {
        unsigned digit = (unsigned)(*s - '0');
        if (digit > 9)
            return false;
        v = v > (INT64_MAX - 9) / 10 ? INT64_MAX : 10 * v + (int64_t)digit;
    }
    *out = negative ? -v : v;
    return true;
}

bool ply_read_integer(ply_file *f, const ply_element *e, uint64_t index, const char *name, enum ply_type type,
                      int64_t *out)
{
    if (f->format != PLY_ASCII) {
        const unsigned char *p = ply_take(&f->in, ply_type_bytes(type));
        if (!p)
            return ply_fail_input(f, e, index, false);
        *out = ply_decode_integer(p, type, f->format == PLY_BINARY_BE);
        return true;
    }
    char *token;
    if (!ascii_token(f, &token))
        return ply_fail(f, "%s %" PRIu64 ": expected an integer for '%s', got end of line", e->name, index, name);
    int64_t v, lo, hi;
    type_range(type, &lo, &hi);
    if (!parse_decimal(token, &v))
        return ply_fail(f, "%s %" PRIu64 ": expected an integer for '%s', got '%.*s'", e->name, index, name,
                        PLY_QUOTE_CHARS, token);
    if (v < lo || v > hi)
        return ply_fail(f, "%s %" PRIu64 ": value %.*s for '%s' does not fit its type %s", e->name, index,
                        PLY_QUOTE_CHARS, token, name, ply_type_label(type));
    *out = v;
    return true;
}

bool ply_read_number(ply_file *f, const ply_element *e, uint64_t index, const char *name, enum ply_type type,
                     double *out)
{
    if (f->format != PLY_ASCII) {
        const unsigned char *p = ply_take(&f->in, ply_type_bytes(type));
        if (!p)
            return ply_fail_input(f, e, index, false);
        *out = ply_decode_number(p, type, f->format == PLY_BINARY_BE);
        return true;
    }
    if (ply_type_is_integer(type)) {
        int64_t v;
        if (!ply_read_integer(f, e, index, name, type, &v))
            return false;
        *out = (double)v;
        return true;
    }
    char *token;
    if (!ascii_token(f, &token))
        return ply_fail(f, "%s %" PRIu64 ": expected a number for '%s', got end of line", e->name, index, name);
    /* strtof/strtod follow LC_NUMERIC: tessera never calls setlocale, so the
     * decimal point is '.'; a host program that does must keep LC_NUMERIC "C" */
    char *end;
    *out = type == PLY_FLOAT32 ? strtof(token, &end) : strtod(token, &end);
    if (end == token || *end != '\0')
        return ply_fail(f, "%s %" PRIu64 ": expected a number for '%s', got '%.*s'", e->name, index, name,
                        PLY_QUOTE_CHARS, token);
    return true;
}

bool ply_skip_property(ply_file *f, const ply_element *e, uint64_t index, const ply_property *p)
{
    int64_t n = 1;
    if (p->count_type != PLY_NONE) {
        if (!ply_read_integer(f, e, index, p->name, p->count_type, &n))
            return false;
        if (n < 0)
            return ply_fail(f, "%s %" PRIu64 ": list '%s' has negative length %" PRId64, e->name, index, p->name,
                            n);
    }
    if (f->format != PLY_ASCII) {
        uint64_t bytes = (uint64_t)n * ply_type_bytes(p->type);
        return ply_reader_skip(&f->in, bytes) == bytes || ply_fail_input(f, e, index, false);
    }
    char *token;
    for (int64_t i = 0; i < n; i++)
        if (!ascii_token(f, &token))
            return ply_fail(f, "%s %" PRIu64 ": expected a value for '%s', got end of line", e->name, index,
                            p->name);
    return true;
}

/* ---- records ----------------------------------------------------------- */

static bool line_is_blank(const char *s)
{
    while (is_blank_char(*s))
        s++;
    return *s == '\0';
}

bool ply_record_begin(ply_file *f, const ply_element *e, uint64_t index)
{
    if (f->format != PLY_ASCII)
        return true;
    char *line;
    do {
        if (!ply_reader_line(&f->in, PLY_BODY_LINE_MAX_BYTES, &line))
            return ply_fail_input(f, e, index, true);
        f->line++;
    } while (line_is_blank(line));
    f->cursor = line;
    return true;
}

bool ply_record_end(ply_file *f, const ply_element *e, uint64_t index)
{
    char *token;
    if (f->format == PLY_ASCII && ascii_token(f, &token))
        return ply_fail(f, "%s %" PRIu64 ": unexpected extra value '%.*s' (the header declares %zu properties)",
                        e->name, index, PLY_QUOTE_CHARS, token, e->prop_count);
    return true;
}

uint64_t ply_fixed_record_bytes(const ply_element *e)
{
    uint64_t bytes = 0;
    for (size_t i = 0; i < e->prop_count; i++) {
        if (e->props[i].count_type != PLY_NONE)
            return 0;
        bytes += ply_type_bytes(e->props[i].type);
    }
    return bytes;
}

bool ply_skip_element(ply_file *f, const ply_element *e)
{
    if (e->prop_count == 0) /* records of nothing: no bytes, no lines */
        return true;
    if (f->format == PLY_ASCII) {
        for (uint64_t i = 0; i < e->count; i++)
            if (!ply_record_begin(f, e, i))
                return false;
        return true;
    }
    uint64_t record = ply_fixed_record_bytes(e);
    if (record > 0) { /* an absurd count saturates; the skip then stops at the end of the file */
        uint64_t bytes = e->count > UINT64_MAX / record ? UINT64_MAX : e->count * record;
        uint64_t done = ply_reader_skip(&f->in, bytes);
        return done == bytes || ply_fail_input(f, e, done / record, false);
    }
    for (uint64_t i = 0; i < e->count; i++)
        for (size_t k = 0; k < e->prop_count; k++)
            if (!ply_skip_property(f, e, i, &e->props[k]))
                return false;
    return true;
}

/* The fewest bytes one record of e can take: binary, the scalars' sizes and
 * list prefixes (and min_items items); ascii, two characters (a digit and a
 * separator) per value. */
static uint64_t min_record_bytes(const ply_file *f, const ply_element *e)
{
    uint64_t bytes = 0;
    bool ascii = f->format == PLY_ASCII;
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (p->count_type == PLY_NONE) {
            bytes += ascii ? 2 : ply_type_bytes(p->type);
            continue;
        }
        bytes += ascii ? 2 : ply_type_bytes(p->count_type);
        bytes += (uint64_t)p->min_items * (ascii ? 2 : ply_type_bytes(p->type));
    }
    return bytes;
}

uint64_t ply_records_that_fit(const ply_file *f, const ply_element *e)
{
    uint64_t each = min_record_bytes(f, e);
    /* the last ascii value may end the file without a separator */
    uint64_t room = f->data_bytes + (f->format == PLY_ASCII);
    return each > 0 ? room / each : e->count;
}

ply_element *ply_find_element(ply_file *f, enum ply_element_kind kind)
{
    for (size_t i = 0; i < f->element_count; i++)
        if (f->elements[i].kind == kind)
            return &f->elements[i];
    return NULL;
}

bool ply_probe_counts(const char *path, uint64_t *vertices, int64_t *faces, tess_error *err)
{
    ply_file f;
    bool ok = ply_open(&f, path, err, NULL, NULL);
    if (ok) {
        const ply_element *v = ply_find_element(&f, PLY_ELEMENT_VERTEX), *fe = ply_find_element(&f, PLY_ELEMENT_FACE);
        *vertices = v ? v->count : 0;
        *faces = !fe ? -1 : fe->count > INT64_MAX ? INT64_MAX : (int64_t)fe->count;
    }
    ply_close(&f);
    return ok;
}

/* ---- header ------------------------------------------------------------ */

/* Split a header line into at most max whitespace-separated words (in place);
 * returns the number of words, max + 1 when there are more. */
static size_t split_words(char *line, char *words[], size_t max)
{
    size_t n = 0;
    char *p = line;
    for (;;) {
        while (is_blank_char(*p))
            p++;
        if (*p == '\0')
            return n;
        if (n == max)
            return max + 1;
        words[n++] = p;
        while (*p != '\0' && !is_blank_char(*p))
            p++;
        if (*p != '\0')
            *p++ = '\0';
    }
}

static bool parse_type(ply_file *f, const char *word, enum ply_type *type)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++)
        if (strcmp(word, type_names[i].name) == 0) {
            *type = type_names[i].type;
            return true;
        }
    return ply_fail(f, "unknown property type '%.*s'", PLY_QUOTE_CHARS, word);
}

/* A count: decimal digits only (strtoull would take "-1"). */
static bool parse_count(const char *s, uint64_t *out)
{
    uint64_t v = 0;
    if (*s == '\0')
        return false;
    for (; *s; s++) {
        unsigned digit = (unsigned)(*s - '0');
        if (digit > 9 || v > (UINT64_MAX - digit) / 10)
            return false;
        v = 10 * v + digit;
    }
    *out = v;
    return true;
}

static bool copy_name(ply_file *f, char dst[PLY_NAME_BYTES], const char *name)
{
    size_t n = strlen(name);
    if (n >= PLY_NAME_BYTES)
        return ply_fail(f, "name '%.*s...' longer than %d characters", PLY_QUOTE_CHARS, name, PLY_NAME_BYTES - 1);
    memcpy(dst, name, n + 1);
    return true;
}

static bool header_format(ply_file *f, char *w[], size_t n)
{
    static const char *const formats[] = {"ascii", "binary_little_endian", "binary_big_endian"};
    if (n != 3)
        return ply_fail(f, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    if (f->have_format)
        return ply_fail(f, "second 'format' line");
    size_t k = 0;
    while (k < 3 && strcmp(w[1], formats[k]) != 0)
        k++;
    if (k == 3)
        return ply_fail(f, "unknown format '%.*s'", PLY_QUOTE_CHARS, w[1]);
    if (strcmp(w[2], "1.0") != 0 && strcmp(w[2], "1") != 0)
        return ply_fail(f, "unsupported PLY version '%.*s' (only 1.0)", PLY_QUOTE_CHARS, w[2]);
    f->format = k == 0 ? PLY_ASCII : k == 1 ? PLY_BINARY_LE : PLY_BINARY_BE;
    f->have_format = true;
    return true;
}

static bool header_element(ply_file *f, char *w[], size_t n)
{
    if (n != 3)
        return ply_fail(f, "expected 'element <name> <count>'");
    if (f->element_count == f->element_capacity) {
        size_t capacity = f->element_capacity ? 2 * f->element_capacity : 4;
        ply_element *grown = realloc(f->elements, capacity * sizeof *grown);
        if (!grown)
            return ply_fail(f, "out of memory");
        f->elements = grown;
        f->element_capacity = capacity;
    }
    ply_element *e = &f->elements[f->element_count];
    *e = (ply_element){0};
    if (!copy_name(f, e->name, w[1]))
        return false;
    if (!parse_count(w[2], &e->count))
        return ply_fail(f, "element '%s': bad count '%.*s'", e->name, PLY_QUOTE_CHARS, w[2]);
    if (strcmp(e->name, "vertex") == 0)
        e->kind = PLY_ELEMENT_VERTEX;
    else if (strcmp(e->name, "face") == 0)
        e->kind = PLY_ELEMENT_FACE;
    for (size_t i = 0; i < f->element_count; i++)
        if (e->kind != PLY_ELEMENT_OTHER && f->elements[i].kind == e->kind)
            return ply_fail(f, "second '%s' element", e->name);
    f->element_count++;
    return true;
}

static bool header_property(ply_file *f, char *w[], size_t n, ply_property_hook hook, void *ctx)
{
    if (f->element_count == 0)
        return ply_fail(f, "'property' before any 'element'");
    ply_element *e = &f->elements[f->element_count - 1];
    ply_property p = {.count_type = PLY_NONE, .role = PLY_ROLE_SKIP};
    bool list = n >= 2 && strcmp(w[1], "list") == 0;
    if (list ? n != 5 : n != 3)
        return ply_fail(f, list ? "expected 'property list <count type> <item type> <name>'"
                                : "expected 'property <type> <name>'");
    if (list) {
        if (!parse_type(f, w[2], &p.count_type) || !parse_type(f, w[3], &p.type))
            return false;
        if (!ply_type_is_integer(p.count_type))
            return ply_fail(f, "list '%.*s': count type '%s' must be an integer type", PLY_QUOTE_CHARS, w[4],
                            w[2]);
    } else if (!parse_type(f, w[1], &p.type)) {
        return false;
    }
    if (!copy_name(f, p.name, w[list ? 4 : 2]) || (hook && !hook(f, e, &p, ctx)))
        return false;
    if (e->prop_count == e->prop_capacity) {
        size_t capacity = e->prop_capacity ? 2 * e->prop_capacity : 8;
        ply_property *grown = realloc(e->props, capacity * sizeof *grown);
        if (!grown)
            return ply_fail(f, "out of memory");
        e->props = grown;
        e->prop_capacity = capacity;
    }
    e->props[e->prop_count++] = p;
    return true;
}

static bool next_header_line(ply_file *f, char **line)
{
    if (ply_reader_line(&f->in, PLY_HEADER_LINE_MAX_BYTES, line)) {
        f->line++;
        return true;
    }
    f->line++;
    if (f->in.line_too_long)
        return ply_fail(f, "header line longer than %zu bytes", (size_t)PLY_HEADER_LINE_MAX_BYTES);
    if (f->in.read_errno || f->in.out_of_memory)
        return ply_fail_input(f, &(ply_element){.name = "header"}, 0, false);
    return ply_fail(f, "file ends inside the header (no 'end_header')");
}

static bool parse_header_lines(ply_file *f, ply_property_hook hook, void *ctx)
{
    char *line;
    for (;;) {
        if (!next_header_line(f, &line))
            return false;
        char *w[HEADER_WORDS_MAX];
        size_t n = split_words(line, w, HEADER_WORDS_MAX);
        if (n == 0)
            continue;
        /* n is HEADER_WORDS_MAX + 1 for a longer line: fine for a comment, an error otherwise */
        if (strcmp(w[0], "comment") == 0 || strcmp(w[0], "obj_info") == 0)
            continue;
        if (strcmp(w[0], "end_header") == 0)
            return n == 1 || ply_fail(f, "unexpected words after 'end_header'");
        bool ok;
        if (strcmp(w[0], "format") == 0)
            ok = header_format(f, w, n);
        else if (strcmp(w[0], "element") == 0)
            ok = header_element(f, w, n);
        else if (strcmp(w[0], "property") == 0)
            ok = header_property(f, w, n, hook, ctx);
        else
            ok = ply_fail(f, "unknown header keyword '%.*s'", PLY_QUOTE_CHARS, w[0]);
        if (!ok)
            return false;
    }
}

static bool read_header(ply_file *f, ply_property_hook hook, void *ctx)
{
    struct stat st;
    if (fstat(fileno(f->file), &st) != 0 || !S_ISREG(st.st_mode))
        return ply_fail(f, "cannot open: not a regular file");
    f->file_bytes = (uint64_t)st.st_size;
    if (!ply_reader_init(&f->in, f->file, f->file_bytes))
        return ply_fail(f, "out of memory");
    char *line;
    if (!ply_reader_line(&f->in, PLY_HEADER_LINE_MAX_BYTES, &line) || strcmp(line, "ply") != 0) {
        if (f->in.read_errno)
            return ply_fail_input(f, &(ply_element){.name = "header"}, 0, false);
        return ply_fail(f, "not a PLY file (no 'ply' magic)");
    }
    f->line = 1;
    f->cite_line = true;
    if (!parse_header_lines(f, hook, ctx))
        return false;
    if (!f->have_format)
        return ply_fail(f, "header has no 'format' line");
    f->cite_line = false; /* what follows is about the file as a whole */
    uint64_t header_bytes = f->in.base + f->in.pos;
    f->data_bytes = f->file_bytes > header_bytes ? f->file_bytes - header_bytes : 0;
    return true;
}

bool ply_open(ply_file *f, const char *path, tess_error *err, ply_property_hook hook, void *ctx)
{
    *f = (ply_file){.path = path, .err = err};
    /* a FIFO or device would block fopen or fread: refuse it before opening
     * (a failed stat is left to fopen, whose errno the message gives) */
    struct stat st;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode))
        return ply_fail(f, "cannot open: not a regular file");
    f->file = fopen(path, "rb");
    if (!f->file) {
        char text[128];
        return tess_error_set(err, "%s: cannot open: %s", path, errno_text(errno, text, sizeof text));
    }
    return read_header(f, hook, ctx);
}

void ply_close(ply_file *f)
{
    for (size_t i = 0; i < f->element_count; i++)
        free(f->elements[i].props);
    free(f->elements);
    f->elements = NULL;
    f->element_count = f->element_capacity = 0;
    ply_reader_finish(&f->in);
    if (f->file)
        fclose(f->file);
    f->file = NULL;
}
