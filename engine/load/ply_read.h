/* ply_read.h - the format level of PLY 1.0 (ascii, binary_little_endian,
 * binary_big_endian), shared by the loaders that read PLY files: meshes
 * (engine/load/mesh_ply.c) and particle sets (engine/load/particle_load.c).
 *
 * WHAT IT DOES. ply_open opens a file, reads the header into elements and
 * their properties, and leaves the file positioned at the first record. The
 * loader then walks the elements in header order, reading each record's
 * values with ply_read_number / ply_read_integer (either encoding), reading
 * past what it does not keep (ply_skip_property, ply_skip_element), or, for a
 * binary record of scalars only, taking the whole record with ply_take and
 * decoding values from it (ply_decode_number).
 *
 * WHAT THE LOADER DECIDES. A property hook, called for every property as the
 * header declares it, gives each property a role (0: read past; any other
 * value is the loader's own) and may refuse it; its message then cites the
 * header line. Which elements and properties must exist, and what a record
 * means, are the loader's business.
 *
 * MESSAGES. ply_fail formats "PATH:LINE: what" while cite_line is set (the
 * header and ascii bodies, where lines mean something) and "PATH: what"
 * otherwise (binary data: the message names the element and record index
 * instead). Element and record numbers count from 0, lines from 1. Tokens
 * quoted back are cut to PLY_QUOTE_CHARS.
 *
 * MEMORY. The file is read through one buffer of at most READ_CHUNK_BYTES
 * (more only for a longer ascii line, up to PLY_BODY_LINE_MAX_BYTES), so a
 * broken file cannot make the reader allocate without bound; ply_records_that_fit
 * bounds what a loader reserves by the bytes the file really has.
 *
 * Nothing here is global: one ply_file per load, so loads run in parallel.
 * Binary values are assembled byte by byte in the file's byte order, so
 * nothing depends on the host's endianness or alignment. */
#ifndef TESSERA_PLY_READ_H
#define TESSERA_PLY_READ_H

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "engine/base/err.h"

/* element and property names are short words in every PLY writer we know */
#define PLY_NAME_BYTES 64
/* longest token quoted back in a message */
#define PLY_QUOTE_CHARS 40
/* a header line longer than this means the file is not a PLY header */
#define PLY_HEADER_LINE_MAX_BYTES ((size_t)1 << 16)
/* an ascii record line longer than this is refused, so a file without
 * newlines cannot make the buffer grow without bound */
#define PLY_BODY_LINE_MAX_BYTES ((size_t)1 << 26)

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

/* The two elements PLY itself names; a header may declare each at most once. */
enum ply_element_kind { PLY_ELEMENT_OTHER, PLY_ELEMENT_VERTEX, PLY_ELEMENT_FACE };

/* role 0: the loader reads the property past */
#define PLY_ROLE_SKIP 0

typedef struct ply_property {
    char name[PLY_NAME_BYTES]; /* as written in the header */
    enum ply_type type;        /* a scalar's type, or the item type of a list */
    enum ply_type count_type;  /* the type of a list's length prefix; PLY_NONE for a scalar */
    int role;                  /* set by the loader's hook: PLY_ROLE_SKIP or the loader's own meaning */
    uint32_t min_items;        /* a list: the fewest items the loader accepts (bounds ply_records_that_fit) */
} ply_property;

typedef struct ply_element {
    char name[PLY_NAME_BYTES];  /* as written in the header */
    enum ply_element_kind kind; /* vertex, face, or any other name */
    uint64_t count;             /* records declared by the header (not checked against the file) */
    ply_property *props;        /* prop_count properties in file order */
    size_t prop_count;          /* properties used in props */
    size_t prop_capacity;       /* properties allocated in props */
} ply_element;

struct progress; /* engine/base/progress.h */

/* A window onto a file: buf[pos, len) holds bytes not yet consumed. Used by
 * ply_file, and on its own by any loader that wants chunked lines
 * (the LAMMPS reader). */
typedef struct ply_reader {
    FILE *file;         /* open for reading; owned by whoever opened it */
    unsigned char *buf; /* capacity + 1 bytes: the spare one holds the NUL after a final line */
    size_t capacity;    /* bytes of file data buf can hold */
    size_t pos;         /* index in buf of the next unread byte */
    size_t len;         /* bytes of file data in buf */
    uint64_t base;      /* file offset of buf[0] */
    bool eof;           /* fread has reported the end of the file */
    int read_errno;     /* errno of a failed fread, 0 if none */
    bool out_of_memory; /* growing buf failed */
    bool line_too_long; /* a line did not fit the limit given to ply_reader_line */
    struct progress *progress; /* NULL, or told the file offset reached after every read (engine/base/progress.h) */
} ply_reader;

/* An open PLY file. Every field is the reader's; a loader reads format,
 * elements and data_bytes, and may set cite_line. */
typedef struct ply_file {
    const char *path;         /* names the file in every message (not owned) */
    tess_error *err;          /* where the first failure goes; may be NULL */
    FILE *file;               /* owned; closed by ply_close */
    ply_reader in;            /* the file's bytes */
    enum ply_format format;   /* from the header's format line */
    bool have_format;         /* the header had a format line */
    uint64_t line;            /* lines read so far: the number of the current line */
    bool cite_line;           /* messages carry ":line" (header and ascii body, not binary data) */
    char *cursor;             /* ascii body: next unread character of the current line */
    ply_element *elements;    /* element_count elements in header order */
    size_t element_count;     /* elements used */
    size_t element_capacity;  /* elements allocated */
    uint64_t file_bytes;      /* the file's size when opened */
    uint64_t data_bytes;      /* bytes after the header (file_bytes when opened, minus the header) */
} ply_file;

/* Called for every property as the header declares it, before it joins e
 * (e->props holds the ones before it). Sets p->role (it arrives as
 * PLY_ROLE_SKIP) and p->min_items; returns false after ply_fail to refuse
 * the property (the message cites its header line). */
typedef bool (*ply_property_hook)(ply_file *f, const ply_element *e, ply_property *p, void *ctx);

/* Open `path` and read its header up to end_header. Whatever the result,
 * the caller calls ply_close(f) afterwards. On success f->cite_line is
 * false (messages about the whole file); a loader sets it to
 * (format == PLY_ASCII) before reading records. */
bool ply_open(ply_file *f, const char *path, tess_error *err, ply_property_hook hook, void *ctx);
void ply_close(ply_file *f);

/* The element of `kind` (vertex or face), or NULL. */
ply_element *ply_find_element(ply_file *f, enum ply_element_kind kind);

/* Read only the header of `path`: the counts its vertex and face elements
 * declare (0 without a vertex element; -1 without a face element: a point
 * set). False with err when the header cannot be read. */
bool ply_probe_counts(const char *path, uint64_t *vertices, int64_t *faces, tess_error *err);

/* Set "PATH:LINE: what" (or "PATH: what"); returns false. */
bool ply_fail(ply_file *f, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* The end of input inside element e's record `index`: a read error, no
 * memory, an overlong line, or truncation ("truncated: expected 8 vertices,
 * file ends in vertex 5"). `before` says the record had not started (ascii)
 * rather than being cut in the middle (binary). Returns false. */
bool ply_fail_input(ply_file *f, const ply_element *e, uint64_t index, bool before);

/* ascii: make the next non-blank line current (one record per line); binary: nothing. */
bool ply_record_begin(ply_file *f, const ply_element *e, uint64_t index);
/* ascii: the record must have used the whole line; binary: nothing. */
bool ply_record_end(ply_file *f, const ply_element *e, uint64_t index);

/* One scalar of `type` named `name` in record `index` of e: as an integer
 * (an ascii value must be a decimal integer in the type's range), or as a
 * double (any number for the float types). */
bool ply_read_integer(ply_file *f, const ply_element *e, uint64_t index, const char *name, enum ply_type type,
                      int64_t *out);
bool ply_read_number(ply_file *f, const ply_element *e, uint64_t index, const char *name, enum ply_type type,
                     double *out);

/* Read past one property (a scalar, or a list with its length) of record `index`. */
bool ply_skip_property(ply_file *f, const ply_element *e, uint64_t index, const ply_property *p);
/* Read past every record of e. */
bool ply_skip_element(ply_file *f, const ply_element *e);

/* Bytes of one binary record of e when no property is a list, else 0. */
uint64_t ply_fixed_record_bytes(const ply_element *e);
/* At most how many records of e the data after the header holds (binary:
 * the scalars' sizes, list prefixes and min_items; ascii: two characters a
 * value). Allocations are capped by it, so a header claiming 4e9 vertices
 * in a 100-byte file costs nothing. */
uint64_t ply_records_that_fit(const ply_file *f, const ply_element *e);

unsigned ply_type_bytes(enum ply_type t);
bool ply_type_is_integer(enum ply_type t);
const char *ply_type_label(enum ply_type t); /* "float", "uchar", ... */

/* ---- the chunked reader ------------------------------------------------- */

/* A buffer for `file` of `file_bytes` (its size as fstat saw it: the buffer
 * is the file's size, at least 4 KiB, at most a 1 MiB chunk). False on no memory. */
bool ply_reader_init(ply_reader *r, FILE *file, uint64_t file_bytes);
void ply_reader_finish(ply_reader *r); /* frees the buffer; the file is the caller's */

/* Move the unread bytes to the front and append what fread gives; the buffer
 * grows (up to `limit` bytes) when unread bytes fill it. Returns false when
 * nothing was added: end of file, or one of the reader's failure flags. */
bool ply_reader_fill(ply_reader *r, size_t limit);

/* Cut the next line out of the buffer as a NUL-terminated string without its
 * "\n" or "\r\n" (the last line needs no newline), at most `limit` bytes.
 * False at the end of the file or on a failure (see the reader's flags). The
 * string is writable and lives until the next read. */
bool ply_reader_line(ply_reader *r, size_t limit, char **line);

/* Consume up to n bytes; returns how many there were before the end. */
uint64_t ply_reader_skip(ply_reader *r, uint64_t n);

/* The next n bytes of the file, contiguous; NULL when the file ends first. */
static inline const unsigned char *ply_take(ply_reader *r, size_t n)
{
    while (r->len - r->pos < n)
        if (!ply_reader_fill(r, n > r->capacity ? n : r->capacity))
            return NULL;
    const unsigned char *p = r->buf + r->pos;
    r->pos += n;
    return p;
}

/* ---- binary values ------------------------------------------------------- */

static inline uint16_t ply_load_u16(const unsigned char *p, bool big)
{
    return big ? (uint16_t)(p[0] << 8 | p[1]) : (uint16_t)(p[1] << 8 | p[0]);
}

static inline uint32_t ply_load_u32(const unsigned char *p, bool big)
{
    if (big)
        return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
    return (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
}

static inline uint64_t ply_load_u64(const unsigned char *p, bool big)
{
    uint64_t hi = ply_load_u32(big ? p : p + 4, big), lo = ply_load_u32(big ? p + 4 : p, big);
    return hi << 32 | lo;
}

/* An integer type's value at p (0 for the float types). */
static inline int64_t ply_decode_integer(const unsigned char *p, enum ply_type t, bool big)
{
    switch (t) {
    case PLY_INT8: return (int8_t)p[0];
    case PLY_UINT8: return p[0];
    case PLY_INT16: return (int16_t)ply_load_u16(p, big);
    case PLY_UINT16: return ply_load_u16(p, big);
    case PLY_INT32: return (int32_t)ply_load_u32(p, big);
    case PLY_UINT32: return ply_load_u32(p, big);
    default: return 0;
    }
}

/* Any type's value at p, exactly (every PLY type fits a double). */
static inline double ply_decode_number(const unsigned char *p, enum ply_type t, bool big)
{
    if (t == PLY_FLOAT32) {
        uint32_t bits = ply_load_u32(p, big);
        float v;
        memcpy(&v, &bits, sizeof v);
        return v;
    }
    if (t == PLY_FLOAT64) {
        uint64_t bits = ply_load_u64(p, big);
        double v;
        memcpy(&v, &bits, sizeof v);
        return v;
    }
    return (double)ply_decode_integer(p, t, big);
}

/* double to float without undefined behaviour for values beyond FLT_MAX
 * (they become infinite, which the loaders then refuse) */
static inline float ply_to_float(double v)
{
    if (v > FLT_MAX)
        return INFINITY;
    if (v < -FLT_MAX)
        return -INFINITY;
    return (float)v;
}

#endif
