/* mesh_ply.c - a streaming PLY 1.0 reader: ascii, binary_little_endian and
 * binary_big_endian.
 *
 * The file is read in READ_CHUNK_BYTES pieces into one buffer. Header lines and
 * ascii body lines are cut out of that buffer in place; binary values are
 * assembled byte by byte in the file's byte order, so nothing depends on the
 * host's endianness or alignment.
 *
 * Kept: the vertex element's x y z (required), nx ny nz and red green blue
 * (each group only when all three are present), and the face element's
 * vertex_indices (or vertex_index) list, fan-split into triangles. Every other
 * property and element is read past. Element numbers in messages count from 0,
 * line numbers from 1.
 *
 * Nothing here is global: one ply_loader per call, so loads run in parallel. */
#include "mesh.h"

#include <errno.h>
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* fread size: big enough that system calls and the partial-record memmove
 * between chunks cost nothing measurable */
#define READ_CHUNK_BYTES ((size_t)1 << 20)
/* the first buffer of a file smaller than a chunk: its size, but at least this
 * (a 400-byte cube needs no megabyte; the buffer still grows for long lines) */
#define READ_MIN_BYTES ((size_t)4 << 10)
/* a header line longer than this means the file is not a PLY header */
#define HEADER_LINE_MAX_BYTES ((size_t)1 << 16)
/* an ascii record line longer than this is refused, so a file without
 * newlines cannot make the buffer grow without bound */
#define BODY_LINE_MAX_BYTES ((size_t)1 << 26)
/* element and property names are short words in every PLY writer we know */
#define PLY_NAME_BYTES 64
/* the longest header line we parse: "property list uchar int vertex_indices" */
#define HEADER_WORDS_MAX 5
/* longest token quoted back in a message */
#define QUOTE_CHARS 40

enum ply_format { PLY_ASCII, PLY_BINARY_LE, PLY_BINARY_BE };

enum ply_type {
    PLY_NONE, /* "no type": the count type of a scalar property */
    PLY_INT8,
    PLY_UINT8,
    PLY_INT16,
    PLY_UINT16,
    PLY_INT32,
    PLY_UINT32,
    PLY_FLOAT32,
    PLY_FLOAT64,
};

static const struct type_name {
    const char *name;   /* as written in the header */
    enum ply_type type; /* what it means */
} type_names[] = {
    {"char", PLY_INT8},     {"int8", PLY_INT8},       {"uchar", PLY_UINT8},   {"uint8", PLY_UINT8},
    {"short", PLY_INT16},   {"int16", PLY_INT16},     {"ushort", PLY_UINT16}, {"uint16", PLY_UINT16},
    {"int", PLY_INT32},     {"int32", PLY_INT32},     {"uint", PLY_UINT32},   {"uint32", PLY_UINT32},
    {"float", PLY_FLOAT32}, {"float32", PLY_FLOAT32}, {"double", PLY_FLOAT64}, {"float64", PLY_FLOAT64},
};

/* What the loader does with a property. ROLE_X..ROLE_BLUE are consecutive:
 * role - ROLE_X is the property's slot in a vertex (see vertex_slot_names). */
enum ply_role {
    ROLE_SKIP,
    ROLE_X,
    ROLE_Y,
    ROLE_Z,
    ROLE_NX,
    ROLE_NY,
    ROLE_NZ,
    ROLE_RED,
    ROLE_GREEN,
    ROLE_BLUE,
    ROLE_INDICES,
};

#define VERTEX_SLOTS 9
static const char *const vertex_slot_names[VERTEX_SLOTS] = {"x",  "y",  "z",     "nx",   "ny",
                                                            "nz", "red", "green", "blue"};

enum element_kind { ELEMENT_OTHER, ELEMENT_VERTEX, ELEMENT_FACE };

typedef struct ply_property {
    char name[PLY_NAME_BYTES]; /* as written in the header */
    enum ply_type type;        /* a scalar's type, or the item type of a list */
    enum ply_type count_type;  /* the type of a list's length prefix; PLY_NONE for a scalar */
    enum ply_role role;        /* what the loader does with the value(s) */
} ply_property;

typedef struct ply_element {
    char name[PLY_NAME_BYTES]; /* as written in the header */
    enum element_kind kind;    /* vertex and face are loaded, others read past */
    uint64_t count;            /* records declared by the header */
    ply_property *props;       /* prop_count properties in file order */
    size_t prop_count;         /* properties used in props */
    size_t prop_capacity;      /* properties allocated in props */
} ply_element;

/* A window onto the file: buf[pos, len) holds bytes not yet consumed. */
typedef struct ply_reader {
    FILE *file;          /* open for reading; owned by mesh_load_ply */
    unsigned char *buf;  /* capacity + 1 bytes: the spare one holds the NUL after a final line */
    size_t capacity;     /* bytes of file data buf can hold */
    size_t pos;          /* index in buf of the next unread byte */
    size_t len;          /* bytes of file data in buf */
    uint64_t base;       /* file offset of buf[0] */
    bool eof;            /* fread has reported the end of the file */
    int read_errno;      /* errno of a failed fread, 0 if none */
    bool out_of_memory;  /* growing buf failed */
    bool line_too_long;  /* a line did not fit the limit given to reader_line */
} ply_reader;

typedef struct ply_loader {
    const char *path;         /* names the file in every message */
    tess_error *err;          /* where the first failure goes; may be NULL */
    ply_reader in;            /* the file */
    enum ply_format format;   /* from the header's format line */
    bool have_format;         /* the header had a format line */
    uint64_t line;            /* lines read so far: the number of the current line */
    bool cite_line;           /* messages carry ":line" (header and ascii body, not binary data) */
    char *cursor;             /* ascii body: next unread character of the current line */
    ply_element *elements;    /* element_count elements in header order */
    size_t element_count;     /* elements used */
    size_t element_capacity;  /* elements allocated */
    ply_element *vertex;      /* the vertex element (in elements), set once the header is read */
    ply_element *face;        /* the face element (in elements), or NULL when there is none */
    bool has_normals;         /* nx ny nz are all present */
    bool has_colors;          /* red green blue are all present */
    float color_range[3];     /* red/green/blue value meaning full intensity (255, 65535 or 1) */
    mesh *m;                  /* the result, owned by the loader until returned */
    uint32_t vertex_total;    /* vertices declared by the header: face indices must be below it */
    uint32_t triangle_total;  /* triangles written to m->indices so far */
} ply_loader;

/* ---- messages ---------------------------------------------------------- */

static bool fail(ply_loader *ld, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Set "PATH:LINE: what" (or "PATH: what" for binary data); returns false. */
static bool fail(ply_loader *ld, const char *fmt, ...)
{
    char what[TESS_ERROR_MSG_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    if (ld->cite_line)
        return tess_error_set(ld->err, "%s:%" PRIu64 ": %s", ld->path, ld->line, what);
    return tess_error_set(ld->err, "%s: %s", ld->path, what);
}

static const char *errno_text(int code, char *buf, size_t size)
{
    if (strerror_r(code, buf, size) != 0)
        snprintf(buf, size, "error %d", code);
    return buf;
}

/* The end of input inside element e's record `index`: a read error, no
 * memory, an overlong line, or truncation. `before` says the record had not
 * started (ascii) rather than being cut in the middle (binary). */
static bool fail_input(ply_loader *ld, const ply_element *e, uint64_t index, bool before)
{
    const ply_reader *r = &ld->in;
    if (r->read_errno) {
        char text[128];
        return fail(ld, "read error: %s", errno_text(r->read_errno, text, sizeof text));
    }
    if (r->out_of_memory)
        return fail(ld, "out of memory");
    if (r->line_too_long)
        return fail(ld, "%s %" PRIu64 ": line longer than %zu bytes", e->name, index, (size_t)BODY_LINE_MAX_BYTES);
    bool one = e->count == 1;
    const char *noun = e->kind == ELEMENT_VERTEX ? (one ? "vertex" : "vertices")
                       : e->kind == ELEMENT_FACE ? (one ? "face" : "faces")
                                                 : (one ? "element" : "elements");
    return fail(ld, "truncated: expected %" PRIu64 " %s%s%s, file ends %s %s %" PRIu64, e->count,
                e->kind == ELEMENT_OTHER ? e->name : "", e->kind == ELEMENT_OTHER ? " " : "", noun,
                before ? "before" : "in", e->name, index);
}

/* ---- the buffered reader ------------------------------------------------- */

/* `file_bytes`: the file's size as fstat saw it (it may change while read). */
static bool reader_init(ply_reader *r, FILE *file, uint64_t file_bytes)
{
    r->file = file;
    r->capacity = file_bytes < READ_MIN_BYTES ? READ_MIN_BYTES
                  : file_bytes < READ_CHUNK_BYTES ? (size_t)file_bytes
                                                  : READ_CHUNK_BYTES;
    r->buf = malloc(r->capacity + 1);
    return r->buf != NULL;
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

/* Move the unread bytes to the front and append what fread gives; the buffer
 * grows (up to `limit` bytes) when unread bytes fill it. Returns false when
 * nothing was added: end of file, or one of the reader's failure flags. */
static bool reader_fill(ply_reader *r, size_t limit)
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
    return true;
}

/* The next n bytes of the file, contiguous; NULL when the file ends first. */
static inline const unsigned char *reader_take(ply_reader *r, size_t n)
{
    while (r->len - r->pos < n)
        if (!reader_fill(r, n > r->capacity ? n : r->capacity))
            return NULL;
    const unsigned char *p = r->buf + r->pos;
    r->pos += n;
    return p;
}

/* Consume up to n bytes; returns how many there were before the end. */
static uint64_t reader_skip(ply_reader *r, uint64_t n)
{
    uint64_t done = 0;
    while (done < n) {
        if (r->pos == r->len && !reader_fill(r, r->capacity))
            break;
        size_t avail = r->len - r->pos;
        size_t step = n - done < avail ? (size_t)(n - done) : avail;
        r->pos += step;
        done += step;
    }
    return done;
}

/* Cut the next line out of the buffer as a NUL-terminated string without its
 * "\n" or "\r\n". The last line needs no newline. Returns false at the end of
 * the file or on a failure (see the reader's flags). The string lives until
 * the next read. */
static bool reader_line(ply_reader *r, size_t limit, char **line)
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
            if (reader_fill(r, limit))
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

/* ---- values ------------------------------------------------------------ */

static unsigned type_bytes(enum ply_type t)
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

static bool type_is_integer(enum ply_type t) { return t >= PLY_INT8 && t <= PLY_UINT32; }

static const char *type_label(enum ply_type t)
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

static inline uint16_t load_u16(const unsigned char *p, bool big)
{
    return big ? (uint16_t)(p[0] << 8 | p[1]) : (uint16_t)(p[1] << 8 | p[0]);
}

static inline uint32_t load_u32(const unsigned char *p, bool big)
{
    if (big)
        return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
    return (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

static inline uint64_t load_u64(const unsigned char *p, bool big)
{
    uint64_t hi = load_u32(big ? p : p + 4, big), lo = load_u32(big ? p + 4 : p, big);
    return hi << 32 | lo;
}

/* An integer type's value; float types never reach here (the header check refuses them). */
static inline int64_t decode_integer(const unsigned char *p, enum ply_type t, bool big)
{
    switch (t) {
    case PLY_INT8: return (int8_t)p[0];
    case PLY_UINT8: return p[0];
    case PLY_INT16: return (int16_t)load_u16(p, big);
    case PLY_UINT16: return load_u16(p, big);
    case PLY_INT32: return (int32_t)load_u32(p, big);
    case PLY_UINT32: return load_u32(p, big);
    default: return 0;
    }
}

static inline double decode_number(const unsigned char *p, enum ply_type t, bool big)
{
    if (t == PLY_FLOAT32) {
        uint32_t bits = load_u32(p, big);
        float f;
        memcpy(&f, &bits, sizeof f);
        return f;
    }
    if (t == PLY_FLOAT64) {
        uint64_t bits = load_u64(p, big);
        double d;
        memcpy(&d, &bits, sizeof d);
        return d;
    }
    return (double)decode_integer(p, t, big);
}

/* double to float without undefined behaviour for values beyond FLT_MAX */
static inline float to_float(double v)
{
    if (v > FLT_MAX)
        return INFINITY;
    if (v < -FLT_MAX)
        return -INFINITY;
    return (float)v;
}

static uint32_t min_u32(uint64_t a, uint64_t b) { return (uint32_t)(a < b ? a : b); }

static inline bool is_blank_char(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* The next whitespace-separated token of the current ascii line, NUL-terminated
 * in place; false at the end of the line. */
static inline bool ascii_token(ply_loader *ld, char **token)
{
    char *p = ld->cursor;
    while (is_blank_char(*p))
        p++;
    if (*p == '\0') {
        ld->cursor = p;
        return false;
    }
    *token = p;
    while (*p != '\0' && !is_blank_char(*p))
        p++;
    if (*p != '\0')
        *p++ = '\0';
    ld->cursor = p;
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

/* One scalar of `type` named `name` in record `index` of e, as an integer. */
static bool read_integer(ply_loader *ld, const ply_element *e, uint64_t index, const char *name,
                         enum ply_type type, int64_t *out)
{
    if (ld->format != PLY_ASCII) {
        const unsigned char *p = reader_take(&ld->in, type_bytes(type));
        if (!p)
            return fail_input(ld, e, index, false);
        *out = decode_integer(p, type, ld->format == PLY_BINARY_BE);
        return true;
    }
    char *token;
    if (!ascii_token(ld, &token))
        return fail(ld, "%s %" PRIu64 ": expected an integer for '%s', got end of line", e->name, index, name);
    int64_t v, lo, hi;
    type_range(type, &lo, &hi);
    if (!parse_decimal(token, &v))
        return fail(ld, "%s %" PRIu64 ": expected an integer for '%s', got '%.*s'", e->name, index, name,
                    QUOTE_CHARS, token);
    if (v < lo || v > hi)
        return fail(ld, "%s %" PRIu64 ": value %.*s for '%s' does not fit its type %s", e->name, index, QUOTE_CHARS,
                    token, name, type_label(type));
    *out = v;
    return true;
}

/* One scalar of `type` named `name` in record `index` of e, as a double. */
static bool read_number(ply_loader *ld, const ply_element *e, uint64_t index, const char *name, enum ply_type type,
                        double *out)
{
    if (ld->format != PLY_ASCII) {
        const unsigned char *p = reader_take(&ld->in, type_bytes(type));
        if (!p)
            return fail_input(ld, e, index, false);
        *out = decode_number(p, type, ld->format == PLY_BINARY_BE);
        return true;
    }
    if (type_is_integer(type)) {
        int64_t v;
        if (!read_integer(ld, e, index, name, type, &v))
            return false;
        *out = (double)v;
        return true;
    }
    char *token;
    if (!ascii_token(ld, &token))
        return fail(ld, "%s %" PRIu64 ": expected a number for '%s', got end of line", e->name, index, name);
    /* strtof/strtod follow LC_NUMERIC: tessera never calls setlocale, so the
     * decimal point is '.'; a host program that does must keep LC_NUMERIC "C" */
    char *end;
    *out = type == PLY_FLOAT32 ? strtof(token, &end) : strtod(token, &end);
    if (end == token || *end != '\0')
        return fail(ld, "%s %" PRIu64 ": expected a number for '%s', got '%.*s'", e->name, index, name, QUOTE_CHARS,
                    token);
    return true;
}

/* Read past one property the loader does not keep. */
static bool skip_property(ply_loader *ld, const ply_element *e, uint64_t index, const ply_property *p)
{
    int64_t n = 1;
    if (p->count_type != PLY_NONE) {
        if (!read_integer(ld, e, index, p->name, p->count_type, &n))
            return false;
        if (n < 0)
            return fail(ld, "%s %" PRIu64 ": list '%s' has negative length %" PRId64, e->name, index, p->name, n);
    }
    if (ld->format != PLY_ASCII) {
        uint64_t bytes = (uint64_t)n * type_bytes(p->type);
        return reader_skip(&ld->in, bytes) == bytes || fail_input(ld, e, index, false);
    }
    char *token;
    for (int64_t i = 0; i < n; i++)
        if (!ascii_token(ld, &token))
            return fail(ld, "%s %" PRIu64 ": expected a value for '%s', got end of line", e->name, index, p->name);
    return true;
}

/* ---- records ----------------------------------------------------------- */

static bool line_is_blank(const char *s)
{
    while (is_blank_char(*s))
        s++;
    return *s == '\0';
}

/* ascii: make the next non-blank line current (one record per line) */
static bool record_begin(ply_loader *ld, const ply_element *e, uint64_t index)
{
    if (ld->format != PLY_ASCII)
        return true;
    char *line;
    do {
        if (!reader_line(&ld->in, BODY_LINE_MAX_BYTES, &line))
            return fail_input(ld, e, index, true);
        ld->line++;
    } while (line_is_blank(line));
    ld->cursor = line;
    return true;
}

/* ascii: the record must have used the whole line */
static bool record_end(ply_loader *ld, const ply_element *e, uint64_t index)
{
    char *token;
    if (ld->format == PLY_ASCII && ascii_token(ld, &token))
        return fail(ld, "%s %" PRIu64 ": unexpected extra value '%.*s' (the header declares %zu properties)", e->name,
                    index, QUOTE_CHARS, token, e->prop_count);
    return true;
}

static inline float clamp_unit(float v) { return v < 0.f ? 0.f : v > 1.f ? 1.f : v; } /* NaN passes through */

/* Storage was reserved for what the file size allows; a file that grew since
 * it was measured gets more, up to the header's count. */
static bool grow_vertices(ply_loader *ld)
{
    uint64_t capacity = ld->m->vertex_capacity;
    uint64_t wanted = capacity + capacity / 2 + 1024;
    if (!mesh_reserve_vertices(ld->m, min_u32(wanted, ld->vertex_total)))
        return fail(ld, "out of memory for %" PRIu64 " vertices", wanted);
    return true;
}

static bool store_vertex(ply_loader *ld, uint32_t index, const float slot[VERTEX_SLOTS])
{
    for (int k = 0; k < 3; k++)
        if (!isfinite(slot[k]))
            return fail(ld, "vertex %" PRIu32 ": coordinate '%s' is %g (must be finite)", index, vertex_slot_names[k],
                        (double)slot[k]);
    mesh *m = ld->m;
    if (index >= m->vertex_capacity && !grow_vertices(ld))
        return false;
    memcpy(m->positions + 3 * (size_t)index, slot, 3 * sizeof(float));
    if (ld->has_normals)
        memcpy(m->normals + 3 * (size_t)index, slot + 3, 3 * sizeof(float));
    if (ld->has_colors)
        for (int k = 0; k < 3; k++)
            m->colors[3 * (size_t)index + (size_t)k] = clamp_unit(slot[6 + k] / ld->color_range[k]);
    return true;
}

static bool read_vertex(ply_loader *ld, const ply_element *e, uint32_t index)
{
    float slot[VERTEX_SLOTS] = {0};
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (p->role == ROLE_SKIP) {
            if (!skip_property(ld, e, index, p))
                return false;
            continue;
        }
        double v = 0;
        if (!read_number(ld, e, index, p->name, p->type, &v))
            return false;
        slot[p->role - ROLE_X] = to_float(v);
    }
    return store_vertex(ld, index, slot);
}

/* Where a kept property sits in a fixed-size binary vertex record. */
typedef struct vertex_field {
    size_t offset;      /* bytes from the start of the record */
    enum ply_type type; /* its type */
    int slot;           /* index into a vertex's slots (role - ROLE_X) */
} vertex_field;

/* Binary vertices whose properties are all scalars: one block per record. */
static bool read_fixed_vertices(ply_loader *ld, const ply_element *e, size_t record)
{
    vertex_field fields[VERTEX_SLOTS];
    int field_count = 0;
    size_t offset = 0;
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (p->role != ROLE_SKIP)
            fields[field_count++] = (vertex_field){offset, p->type, (int)(p->role - ROLE_X)};
        offset += type_bytes(p->type);
    }
    bool big = ld->format == PLY_BINARY_BE;
    for (uint32_t v = 0; v < ld->vertex_total; v++) {
        const unsigned char *bytes = reader_take(&ld->in, record);
        if (!bytes)
            return fail_input(ld, e, v, false);
        float slot[VERTEX_SLOTS] = {0};
        for (int f = 0; f < field_count; f++)
            slot[fields[f].slot] = to_float(decode_number(bytes + fields[f].offset, fields[f].type, big));
        if (!store_vertex(ld, v, slot))
            return false;
    }
    return true;
}

static bool grow_triangles(ply_loader *ld)
{
    uint32_t capacity = ld->m->triangle_capacity;
    if (capacity == UINT32_MAX)
        return fail(ld, "more than %" PRIu32 " triangles", UINT32_MAX);
    uint64_t wanted = (uint64_t)capacity + capacity / 2 + 1024;
    if (!mesh_reserve_triangles(ld->m, wanted > UINT32_MAX ? UINT32_MAX : (uint32_t)wanted))
        return fail(ld, "out of memory for %" PRIu64 " triangles", wanted);
    return true;
}

static inline bool emit_triangle(ply_loader *ld, uint32_t a, uint32_t b, uint32_t c)
{
    if (ld->triangle_total == ld->m->triangle_capacity && !grow_triangles(ld))
        return false;
    uint32_t *t = ld->m->indices + 3 * (size_t)ld->triangle_total++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    return true;
}

static bool index_error(ply_loader *ld, uint32_t face, int64_t v)
{
    if (v < 0)
        return fail(ld, "face %" PRIu32 ": negative vertex index %" PRId64, face, v);
    return fail(ld, "face %" PRIu32 ": vertex index %" PRId64 " out of range (file has %" PRIu32 " vertices)", face,
                v, ld->vertex_total);
}

/* Fan-split state of one polygon: (v0, v1, v2), (v0, v2, v3), ... */
typedef struct polygon_fan {
    uint32_t first;  /* the polygon's first vertex */
    uint32_t prev;   /* the vertex before the current one */
    uint32_t corner; /* vertices seen so far */
} polygon_fan;

static inline bool fan_add(ply_loader *ld, polygon_fan *fan, uint32_t face, int64_t v)
{
    if ((uint64_t)v >= ld->vertex_total) /* a negative v wraps to a huge value */
        return index_error(ld, face, v);
    if (fan->corner == 0)
        fan->first = (uint32_t)v;
    else if (fan->corner >= 2 && !emit_triangle(ld, fan->first, fan->prev, (uint32_t)v))
        return false;
    fan->prev = (uint32_t)v;
    fan->corner++;
    return true;
}

/* Most polygons are this short; a binary one is then decoded from one block. */
#define POLYGON_BLOCK_MAX 64

/* One face's index list, fan-split into triangles. */
static bool read_polygon(ply_loader *ld, const ply_element *e, uint32_t face, const ply_property *p)
{
    int64_t n;
    if (!read_integer(ld, e, face, p->name, p->count_type, &n))
        return false;
    if (n < 3)
        return fail(ld, "face %" PRIu32 ": has %" PRId64 " vertices (a face needs at least 3)", face, n);
    polygon_fan fan = {0};
    if (ld->format != PLY_ASCII && n <= POLYGON_BLOCK_MAX) {
        unsigned size = type_bytes(p->type);
        const unsigned char *block = reader_take(&ld->in, (size_t)n * size);
        if (!block)
            return fail_input(ld, e, face, false);
        bool big = ld->format == PLY_BINARY_BE;
        for (int64_t i = 0; i < n; i++)
            if (!fan_add(ld, &fan, face, decode_integer(block + (size_t)i * size, p->type, big)))
                return false;
        return true;
    }
    for (int64_t i = 0; i < n; i++) {
        int64_t v;
        if (!read_integer(ld, e, face, p->name, p->type, &v) || !fan_add(ld, &fan, face, v))
            return false;
    }
    return true;
}

static bool read_face(ply_loader *ld, const ply_element *e, uint32_t index)
{
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (!(p->role == ROLE_INDICES ? read_polygon(ld, e, index, p) : skip_property(ld, e, index, p)))
            return false;
    }
    return true;
}

/* Bytes of one binary record when no property is a list, else 0. */
static uint64_t fixed_record_bytes(const ply_element *e)
{
    uint64_t bytes = 0;
    for (size_t i = 0; i < e->prop_count; i++) {
        if (e->props[i].count_type != PLY_NONE)
            return 0;
        bytes += type_bytes(e->props[i].type);
    }
    return bytes;
}

/* Read past an element the loader does not keep. */
static bool skip_element(ply_loader *ld, const ply_element *e)
{
    if (ld->format == PLY_ASCII) {
        for (uint64_t i = 0; i < e->count; i++)
            if (!record_begin(ld, e, i))
                return false;
        return true;
    }
    uint64_t record = fixed_record_bytes(e);
    if (record > 0) { /* an absurd count saturates; the skip then stops at the end of the file */
        uint64_t bytes = e->count > UINT64_MAX / record ? UINT64_MAX : e->count * record;
        uint64_t done = reader_skip(&ld->in, bytes);
        return done == bytes || fail_input(ld, e, done / record, false);
    }
    for (uint64_t i = 0; i < e->count; i++)
        for (size_t k = 0; k < e->prop_count; k++)
            if (!skip_property(ld, e, i, &e->props[k]))
                return false;
    return true;
}

static bool read_element(ply_loader *ld, const ply_element *e)
{
    if (e->prop_count == 0) /* records of nothing: no bytes, no lines */
        return true;
    if (e->kind == ELEMENT_OTHER)
        return skip_element(ld, e);
    uint64_t record = ld->format != PLY_ASCII ? fixed_record_bytes(e) : 0;
    if (e->kind == ELEMENT_VERTEX && record > 0)
        return read_fixed_vertices(ld, e, (size_t)record);
    /* vertex and face counts were checked to fit in uint32_t */
    for (uint32_t i = 0; i < (uint32_t)e->count; i++) {
        if (!record_begin(ld, e, i))
            return false;
        if (!(e->kind == ELEMENT_VERTEX ? read_vertex(ld, e, i) : read_face(ld, e, i)))
            return false;
        if (!record_end(ld, e, i))
            return false;
    }
    return true;
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

static bool parse_type(ply_loader *ld, const char *word, enum ply_type *type)
{
    for (size_t i = 0; i < sizeof type_names / sizeof type_names[0]; i++)
        if (strcmp(word, type_names[i].name) == 0) {
            *type = type_names[i].type;
            return true;
        }
    return fail(ld, "unknown property type '%.*s'", QUOTE_CHARS, word);
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

static bool copy_name(ply_loader *ld, char dst[PLY_NAME_BYTES], const char *name)
{
    size_t n = strlen(name);
    if (n >= PLY_NAME_BYTES)
        return fail(ld, "name '%.*s...' longer than %d characters", QUOTE_CHARS, name, PLY_NAME_BYTES - 1);
    memcpy(dst, name, n + 1);
    return true;
}

static bool header_format(ply_loader *ld, char *w[], size_t n)
{
    static const char *const formats[] = {"ascii", "binary_little_endian", "binary_big_endian"};
    if (n != 3)
        return fail(ld, "expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'");
    if (ld->have_format)
        return fail(ld, "second 'format' line");
    size_t f = 0;
    while (f < 3 && strcmp(w[1], formats[f]) != 0)
        f++;
    if (f == 3)
        return fail(ld, "unknown format '%.*s'", QUOTE_CHARS, w[1]);
    if (strcmp(w[2], "1.0") != 0 && strcmp(w[2], "1") != 0)
        return fail(ld, "unsupported PLY version '%.*s' (only 1.0)", QUOTE_CHARS, w[2]);
    ld->format = f == 0 ? PLY_ASCII : f == 1 ? PLY_BINARY_LE : PLY_BINARY_BE;
    ld->have_format = true;
    return true;
}

static bool header_element(ply_loader *ld, char *w[], size_t n)
{
    if (n != 3)
        return fail(ld, "expected 'element <name> <count>'");
    if (ld->element_count == ld->element_capacity) {
        size_t capacity = ld->element_capacity ? 2 * ld->element_capacity : 4;
        ply_element *grown = realloc(ld->elements, capacity * sizeof *grown);
        if (!grown)
            return fail(ld, "out of memory");
        ld->elements = grown;
        ld->element_capacity = capacity;
    }
    ply_element *e = &ld->elements[ld->element_count];
    *e = (ply_element){0};
    if (!copy_name(ld, e->name, w[1]))
        return false;
    if (!parse_count(w[2], &e->count))
        return fail(ld, "element '%s': bad count '%.*s'", e->name, QUOTE_CHARS, w[2]);
    if (strcmp(e->name, "vertex") == 0)
        e->kind = ELEMENT_VERTEX;
    else if (strcmp(e->name, "face") == 0)
        e->kind = ELEMENT_FACE;
    for (size_t i = 0; i < ld->element_count; i++)
        if (e->kind != ELEMENT_OTHER && ld->elements[i].kind == e->kind)
            return fail(ld, "second '%s' element", e->name);
    ld->element_count++;
    return true;
}

/* The role of property p of element e, checked against its shape. */
static bool assign_role(ply_loader *ld, const ply_element *e, ply_property *p)
{
    p->role = ROLE_SKIP;
    if (e->kind == ELEMENT_VERTEX) {
        for (int k = 0; k < VERTEX_SLOTS; k++)
            if (strcmp(p->name, vertex_slot_names[k]) == 0) {
                if (p->count_type != PLY_NONE)
                    return fail(ld, "vertex property '%s' must be a scalar, not a list", p->name);
                p->role = (enum ply_role)(ROLE_X + k);
            }
    } else if (e->kind == ELEMENT_FACE &&
               (strcmp(p->name, "vertex_indices") == 0 || strcmp(p->name, "vertex_index") == 0)) {
        if (p->count_type == PLY_NONE || !type_is_integer(p->type))
            return fail(ld, "face property '%s' must be a list of integers", p->name);
        p->role = ROLE_INDICES;
    }
    if (p->role == ROLE_SKIP)
        return true;
    for (size_t i = 0; i < e->prop_count; i++) /* only kept properties: linear, however long the header */
        if (e->props[i].role == p->role)
            return fail(ld, "%s element has two '%s' properties", e->name,
                        p->role == ROLE_INDICES ? "vertex_indices" : p->name);
    return true;
}

static bool header_property(ply_loader *ld, char *w[], size_t n)
{
    if (ld->element_count == 0)
        return fail(ld, "'property' before any 'element'");
    ply_element *e = &ld->elements[ld->element_count - 1];
    ply_property p = {.count_type = PLY_NONE};
    bool list = n >= 2 && strcmp(w[1], "list") == 0;
    if (list ? n != 5 : n != 3)
        return fail(ld, list ? "expected 'property list <count type> <item type> <name>'"
                             : "expected 'property <type> <name>'");
    if (list) {
        if (!parse_type(ld, w[2], &p.count_type) || !parse_type(ld, w[3], &p.type))
            return false;
        if (!type_is_integer(p.count_type))
            return fail(ld, "list '%.*s': count type '%s' must be an integer type", QUOTE_CHARS, w[4], w[2]);
    } else if (!parse_type(ld, w[1], &p.type)) {
        return false;
    }
    if (!copy_name(ld, p.name, w[list ? 4 : 2]) || !assign_role(ld, e, &p))
        return false;
    if (e->prop_count == e->prop_capacity) {
        size_t capacity = e->prop_capacity ? 2 * e->prop_capacity : 8;
        ply_property *grown = realloc(e->props, capacity * sizeof *grown);
        if (!grown)
            return fail(ld, "out of memory");
        e->props = grown;
        e->prop_capacity = capacity;
    }
    e->props[e->prop_count++] = p;
    return true;
}

static bool next_header_line(ply_loader *ld, char **line)
{
    if (reader_line(&ld->in, HEADER_LINE_MAX_BYTES, line)) {
        ld->line++;
        return true;
    }
    ld->line++;
    if (ld->in.line_too_long)
        return fail(ld, "header line longer than %zu bytes", (size_t)HEADER_LINE_MAX_BYTES);
    if (ld->in.read_errno || ld->in.out_of_memory)
        return fail_input(ld, &(ply_element){.name = "header"}, 0, false);
    return fail(ld, "file ends inside the header (no 'end_header')");
}

static bool parse_header_lines(ply_loader *ld)
{
    char *line;
    for (;;) {
        if (!next_header_line(ld, &line))
            return false;
        char *w[HEADER_WORDS_MAX];
        size_t n = split_words(line, w, HEADER_WORDS_MAX);
        if (n == 0)
            continue;
        /* n is HEADER_WORDS_MAX + 1 for a longer line: fine for a comment, an error otherwise */
        if (strcmp(w[0], "comment") == 0 || strcmp(w[0], "obj_info") == 0)
            continue;
        if (strcmp(w[0], "end_header") == 0)
            return n == 1 || fail(ld, "unexpected words after 'end_header'");
        bool ok;
        if (strcmp(w[0], "format") == 0)
            ok = header_format(ld, w, n);
        else if (strcmp(w[0], "element") == 0)
            ok = header_element(ld, w, n);
        else if (strcmp(w[0], "property") == 0)
            ok = header_property(ld, w, n);
        else
            ok = fail(ld, "unknown header keyword '%.*s'", QUOTE_CHARS, w[0]);
        if (!ok)
            return false;
    }
}

static const ply_property *find_role(const ply_element *e, enum ply_role role)
{
    for (size_t i = 0; i < e->prop_count; i++)
        if (e->props[i].role == role)
            return &e->props[i];
    return NULL;
}

/* Are the three roles first, first + 1, first + 2 all present? Their types go to types[]. */
static bool has_role_group(const ply_element *v, enum ply_role first, enum ply_type types[3])
{
    for (int k = 0; k < 3; k++) {
        const ply_property *p = find_role(v, (enum ply_role)(first + k));
        if (!p)
            return false;
        types[k] = p->type;
    }
    return true;
}

/* Kept only as a complete group: demote a partial one to skipped. */
static void drop_role_group(ply_element *v, enum ply_role first)
{
    for (size_t i = 0; i < v->prop_count; i++)
        if (v->props[i].role >= first && v->props[i].role < first + 3)
            v->props[i].role = ROLE_SKIP;
}

/* Integer colours are 0..255 (0..65535 for 16-bit types); float colours are
 * 0..1. Either way the value is taken as linear RGB: PLY does not say, and
 * scanners write raw sensor values, so no sRGB decoding is applied. */
static float color_range(enum ply_type t)
{
    if (t == PLY_FLOAT32 || t == PLY_FLOAT64)
        return 1.f;
    if (t == PLY_INT16 || t == PLY_UINT16)
        return 65535.f;
    return 255.f;
}

static bool check_header(ply_loader *ld)
{
    if (!ld->have_format)
        return fail(ld, "header has no 'format' line");
    ld->cite_line = false; /* what follows is about the file as a whole */
    for (size_t i = 0; i < ld->element_count; i++) {
        if (ld->elements[i].kind == ELEMENT_VERTEX)
            ld->vertex = &ld->elements[i];
        else if (ld->elements[i].kind == ELEMENT_FACE)
            ld->face = &ld->elements[i];
    }
    if (!ld->vertex)
        return fail(ld, "no 'vertex' element");
    for (int k = 0; k < 3; k++)
        if (!find_role(ld->vertex, (enum ply_role)(ROLE_X + k)))
            return fail(ld, "vertex element has no '%s' property", vertex_slot_names[k]);
    enum ply_type types[3];
    ld->has_normals = has_role_group(ld->vertex, ROLE_NX, types);
    if (!ld->has_normals)
        drop_role_group(ld->vertex, ROLE_NX);
    ld->has_colors = has_role_group(ld->vertex, ROLE_RED, types);
    if (ld->has_colors)
        for (int k = 0; k < 3; k++)
            ld->color_range[k] = color_range(types[k]);
    else
        drop_role_group(ld->vertex, ROLE_RED);
    if (ld->face && ld->face->count > 0) {
        if (!find_role(ld->face, ROLE_INDICES))
            return fail(ld, "face element has no 'vertex_indices' list");
    }
    return true;
}

/* The fewest bytes one record of e can take: binary, the scalars' sizes and
 * list prefixes (and three indices for a face); ascii, two characters (a digit
 * and a separator) per value. */
static uint64_t min_record_bytes(const ply_loader *ld, const ply_element *e)
{
    uint64_t bytes = 0;
    bool ascii = ld->format == PLY_ASCII;
    for (size_t i = 0; i < e->prop_count; i++) {
        const ply_property *p = &e->props[i];
        if (p->count_type == PLY_NONE) {
            bytes += ascii ? 2 : type_bytes(p->type);
            continue;
        }
        bytes += ascii ? 2 : type_bytes(p->count_type);
        if (p->role == ROLE_INDICES)
            bytes += 3 * (ascii ? 2 : type_bytes(p->type));
    }
    return bytes;
}

/* At most how many records of e the data after the header holds. Allocations
 * are capped by it, so a header claiming 4e9 vertices in a 100-byte file costs
 * nothing: the read stops where the data ends and says where. */
static uint64_t records_that_fit(const ply_loader *ld, const ply_element *e, uint64_t data_bytes)
{
    uint64_t each = min_record_bytes(ld, e);
    /* the last ascii value may end the file without a separator */
    uint64_t room = data_bytes + (ld->format == PLY_ASCII);
    return each > 0 ? room / each : e->count;
}

static bool prepare_mesh(ply_loader *ld, uint64_t data_bytes)
{
    if (ld->vertex->count > UINT32_MAX)
        return fail(ld, "%" PRIu64 " vertices: more than a mesh can hold (%" PRIu32 ")", ld->vertex->count,
                    UINT32_MAX);
    if (ld->face && ld->face->count > UINT32_MAX)
        return fail(ld, "%" PRIu64 " faces: more than a mesh can hold (%" PRIu32 " triangles)", ld->face->count,
                    UINT32_MAX);
    ld->vertex_total = (uint32_t)ld->vertex->count;
    uint32_t vertices = min_u32(ld->vertex_total, records_that_fit(ld, ld->vertex, data_bytes));
    uint32_t faces = ld->face ? min_u32(ld->face->count, records_that_fit(ld, ld->face, data_bytes)) : 0;
    ld->m = mesh_create();
    if (!ld->m || !mesh_reserve_vertices(ld->m, vertices) || !mesh_reserve_triangles(ld->m, faces) ||
        (ld->has_normals && !mesh_enable_normals(ld->m)) || (ld->has_colors && !mesh_enable_colors(ld->m)))
        return fail(ld, "out of memory for %" PRIu32 " vertices and %" PRIu32 " faces", vertices, faces);
    return true;
}

static bool load(ply_loader *ld, FILE *file)
{
    struct stat st;
    if (fstat(fileno(file), &st) != 0 || !S_ISREG(st.st_mode))
        return fail(ld, "cannot open: not a regular file");
    if (!reader_init(&ld->in, file, (uint64_t)st.st_size))
        return fail(ld, "out of memory");
    char *line;
    if (!reader_line(&ld->in, HEADER_LINE_MAX_BYTES, &line) || strcmp(line, "ply") != 0) {
        if (ld->in.read_errno)
            return fail_input(ld, &(ply_element){.name = "header"}, 0, false);
        return fail(ld, "not a PLY file (no 'ply' magic)");
    }
    ld->line = 1;
    ld->cite_line = true;
    if (!parse_header_lines(ld) || !check_header(ld))
        return false;
    uint64_t header_bytes = ld->in.base + ld->in.pos;
    uint64_t file_bytes = (uint64_t)st.st_size;
    if (!prepare_mesh(ld, file_bytes > header_bytes ? file_bytes - header_bytes : 0))
        return false;
    ld->cite_line = ld->format == PLY_ASCII;
    for (size_t i = 0; i < ld->element_count; i++)
        if (!read_element(ld, &ld->elements[i]))
            return false;
    ld->cite_line = false;
    ld->m->vertex_count = ld->vertex_total;
    ld->m->triangle_count = ld->triangle_total;
    return mesh_validate(ld->m, ld->path, ld->err);
}

mesh *mesh_load_ply(const char *path, tess_error *err)
{
    ply_loader ld = {.path = path, .err = err};
    FILE *file = fopen(path, "rb");
    if (!file) {
        char text[128];
        tess_error_set(err, "%s: cannot open: %s", path, errno_text(errno, text, sizeof text));
        return NULL;
    }
    mesh *result = NULL;
    if (load(&ld, file)) {
        result = ld.m;
        ld.m = NULL;
    }
    mesh_destroy(ld.m);
    for (size_t i = 0; i < ld.element_count; i++)
        free(ld.elements[i].props);
    free(ld.elements);
    free(ld.in.buf);
    fclose(file);
    return result;
}
