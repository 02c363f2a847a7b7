/* volume_read.c - the two volume readers, raw data with a text header and
 * NRRD, and volume_load's choice between them (volume_read.h). */
#include "volume_read.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "engine/base/path.h"

/* a header is text of a few hundred bytes; anything longer than this is not
 * one (and an attached NRRD's blank line must come within it) */
#define HEADER_MAX_BYTES (1u << 20)
#define PATH_BYTES 4096
/* how much of a bad value an error message quotes */
#define QUOTE_CHARS 60

/* ---- data files ----------------------------------------------------------- */

static bool host_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char first;
    memcpy(&first, &one, 1);
    return first == 1;
}

static void swap_bytes(void *data, size_t count, size_t width)
{
    unsigned char *b = data;
    for (size_t i = 0; i < count; i++, b += width)
        for (size_t lo = 0, hi = width - 1; lo < hi; lo++, hi--) {
            unsigned char t = b[lo];
            b[lo] = b[hi];
            b[hi] = t;
        }
}

/* Where and how a header says the samples are stored. */
typedef struct data_layout {
    const char *header;   /* the header's path, for messages */
    const char *data;     /* the data file's path */
    int64_t offset;       /* bytes before the samples; -1: they are the file's last bytes */
    bool exact;           /* the samples must end the file exactly (no trailing bytes) */
    bool big_endian;      /* the file's byte order (meaningless for uint8) */
} data_layout;

/* Map or read v's samples as `lay` says, every size checked against the file
 * before anything is mapped or allocated, then compute the range. Messages
 * start with the header's path (the name the caller gave), then the data
 * file's. */
static bool load_samples(volume *v, const data_layout *lay, tess_error *err)
{
    char who[2 * PATH_BYTES + 32];
    if (strcmp(lay->header, lay->data) == 0)
        snprintf(who, sizeof who, "%s: attached data", lay->header);
    else
        snprintf(who, sizeof who, "%s: data file %s", lay->header, lay->data);
    size_t width = volume_type_size(v->type);
    uint64_t need = (uint64_t)volume_count(v) * width; /* <= 2^38: no overflow */
    int fd = open(lay->data, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return tess_error_set(err, "%s: %s", who, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return tess_error_set(err, "%s: not a regular file", who);
    }
    uint64_t size = (uint64_t)st.st_size;
    uint64_t offset;
    if (lay->offset < 0) {
        if (size < need) {
            close(fd);
            return tess_error_set(err, "%s: truncated: %llu bytes, the header needs %u*%u*%u %s = %llu", who,
                                  (unsigned long long)size, v->nx, v->ny, v->nz, volume_type_name(v->type),
                                  (unsigned long long)need);
        }
        offset = size - need;
    } else {
        offset = (uint64_t)lay->offset;
        if (offset > size || size - offset < need || (lay->exact && size - offset != need)) {
            close(fd);
            const char *what = offset > size || size - offset < need ? "truncated: " : "";
            if (offset != 0)
                return tess_error_set(err, "%s: %s%llu bytes, the header says %llu header bytes + %u*%u*%u %s = %llu",
                                      who, what, (unsigned long long)size, (unsigned long long)offset, v->nx, v->ny,
                                      v->nz, volume_type_name(v->type), (unsigned long long)(offset + need));
            return tess_error_set(err, "%s: %s%llu bytes, the header says %u*%u*%u %s = %llu", who, what,
                                  (unsigned long long)size, v->nx, v->ny, v->nz, volume_type_name(v->type),
                                  (unsigned long long)need);
        }
    }
    if (size > SIZE_MAX) {
        close(fd);
        return tess_error_set(err, "%s: %llu bytes do not fit this process's address space", who,
                              (unsigned long long)size);
    }
    bool swap = width > 1 && lay->big_endian == host_little_endian();
    if (!swap && offset % width == 0) {
        /* the file's bytes are the samples: map it whole (offsets need not be page aligned) */
        void *map = mmap(NULL, (size_t)size, PROT_READ, MAP_PRIVATE, fd, 0);
        close(fd);
        if (map == MAP_FAILED)
            return tess_error_set(err, "%s: cannot map %llu bytes: %s", who, (unsigned long long)size,
                                  strerror(errno));
        v->map = map;
        v->map_bytes = (size_t)size;
        v->data = (const unsigned char *)map + offset;
    } else {
        v->buffer = malloc((size_t)need);
        if (!v->buffer) {
            close(fd);
            return tess_error_set(err, "%s: out of memory for %llu bytes of samples", who, (unsigned long long)need);
        }
        unsigned char *dst = v->buffer;
        uint64_t done = 0;
        while (done < need) {
            size_t chunk = need - done > (1u << 30) ? (1u << 30) : (size_t)(need - done);
            ssize_t got = pread(fd, dst + done, chunk, (off_t)(offset + done));
            if (got < 0 && errno == EINTR)
                continue;
            if (got <= 0) {
                int e = got < 0 ? errno : 0;
                close(fd);
                return tess_error_set(err, "%s: read failed after %llu of %llu bytes: %s", who,
                                      (unsigned long long)done, (unsigned long long)need,
                                      e ? strerror(e) : "file shrank while read");
            }
            done += (uint64_t)got;
        }
        close(fd);
        if (swap)
            swap_bytes(v->buffer, volume_count(v), width);
        v->data = v->buffer;
    }
    return volume_update_range(v, who, err);
}

/* ---- header text ---------------------------------------------------------- */

/* A header's text: the file's first bytes (all of it for a detached header),
 * NUL-terminated, in a buffer of len + 1. */
typedef struct header_text {
    char *text;
    size_t len;
    uint64_t file_bytes; /* the whole file's size */
} header_text;

/* Read up to HEADER_MAX_BYTES of `path`; `whole`: the file must fit. */
static bool read_header(const char *path, bool whole, header_text *h, tess_error *err)
{
    memset(h, 0, sizeof *h);
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return tess_error_set(err, "%s: %s", path, strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return tess_error_set(err, "%s: not a regular file", path);
    }
    h->file_bytes = (uint64_t)st.st_size;
    if (whole && h->file_bytes > HEADER_MAX_BYTES) {
        close(fd);
        return tess_error_set(err, "%s: %llu bytes is no header (at most %u)", path,
                              (unsigned long long)h->file_bytes, HEADER_MAX_BYTES);
    }
    size_t want = h->file_bytes < HEADER_MAX_BYTES ? (size_t)h->file_bytes : HEADER_MAX_BYTES;
    h->text = malloc(want + 1);
    if (!h->text) {
        close(fd);
        return tess_error_set(err, "%s: out of memory for the header", path);
    }
    size_t done = 0;
    while (done < want) {
        ssize_t got = pread(fd, h->text + done, want - done, (off_t)done);
        if (got < 0 && errno == EINTR)
            continue;
        if (got <= 0)
            break;
        done += (size_t)got;
    }
    close(fd);
    h->len = done;
    h->text[done] = '\0';
    return true;
}

/* Cut the next line off *cursor (which moves past it), '\r' before '\n'
 * dropped; NULL at the end. A NUL byte in the text ends the text. */
static char *next_line(char **cursor, const char *end)
{
    char *line = *cursor;
    if (line >= end || *line == '\0')
        return NULL;
    char *nl = memchr(line, '\n', (size_t)(end - line));
    char *stop = nl ? nl : (char *)end;
    *cursor = nl ? nl + 1 : (char *)end;
    *stop = '\0';
    size_t n = strlen(line);
    if (n > 0 && line[n - 1] == '\r')
        line[n - 1] = '\0';
    return line;
}

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    size_t n = strlen(s);
    while (n > 0 && (s[n - 1] == ' ' || s[n - 1] == '\t'))
        s[--n] = '\0';
    return s;
}

/* A parenthesised comment after a value: "(...)" to the end, tolerated and dropped. */
static void drop_comment(char *value)
{
    char *paren = strchr(value, '(');
    if (paren)
        *paren = '\0';
}

/* Parse an unsigned decimal integer at *s (digits only), moving *s past it. */
static bool parse_u64(const char **s, uint64_t *out)
{
    const char *p = *s;
    if (!isdigit((unsigned char)*p))
        return false;
    uint64_t v = 0;
    while (isdigit((unsigned char)*p)) {
        if (v > (UINT64_MAX - 9) / 10)
            return false;
        v = v * 10 + (uint64_t)(*p++ - '0');
    }
    *s = p;
    *out = v;
    return true;
}

/* A finite number at *s, moving *s past it; "nan" and "inf" refused. */
static bool parse_double(const char **s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(*s, &end);
    if (end == *s || errno == ERANGE || !isfinite(v))
        return false;
    *s = end;
    *out = v;
    return true;
}

static const char *skip_blanks(const char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    return s;
}

/* `dir` of path + name, or name alone when it is absolute; false when too long. */
static bool join_dir(char out[PATH_BYTES], const char *path, const char *name)
{
    if (name[0] == '/')
        return snprintf(out, PATH_BYTES, "%s", name) < PATH_BYTES;
    const char *slash = strrchr(path, '/');
    int dir_len = slash ? (int)(slash - path) + 1 : 0;
    return snprintf(out, PATH_BYTES, "%.*s%s", dir_len, path, name) < PATH_BYTES;
}

/* ---- the raw + text header reader ----------------------------------------- */

/* "NX x NY x NZ" (blanks around the x optional) and nothing after */
static bool parse_dims_txt(const char *s, uint32_t n[3])
{
    for (int a = 0; a < 3; a++) {
        uint64_t v;
        s = skip_blanks(s);
        if (!parse_u64(&s, &v) || v > UINT32_MAX)
            return false;
        n[a] = (uint32_t)v;
        s = skip_blanks(s);
        if (a < 2) {
            if (*s != 'x' && *s != 'X')
                return false;
            s++;
        }
    }
    return *s == '\0';
}

/* three numbers, then at most one unit word (letters only), then nothing */
static bool parse_triple_txt(const char *s, double out[3])
{
    for (int a = 0; a < 3; a++) {
        s = skip_blanks(s);
        if (!parse_double(&s, &out[a]))
            return false;
        if (*s != '\0' && *s != ' ' && *s != '\t')
            return false;
    }
    s = skip_blanks(s);
    while (isalpha((unsigned char)*s))
        s++;
    return *skip_blanks(s) == '\0';
}

/* A type name as a word (lower case): its type, or -1. */
static int type_word(const char *w)
{
    static const struct {
        const char *name;
        volume_type type;
    } names[] = {
        {"uint8", VOLUME_UINT8},   {"uchar", VOLUME_UINT8},   {"int16", VOLUME_INT16},
        {"short", VOLUME_INT16},   {"uint16", VOLUME_UINT16}, {"ushort", VOLUME_UINT16},
        {"float32", VOLUME_FLOAT32}, {"float", VOLUME_FLOAT32},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(w, names[i].name) == 0)
            return (int)names[i].type;
    return -1;
}

/* The type line of a text header: see volume.h. Words are runs of letters
 * and digits, lower-cased; a parenthesised comment was dropped. Returns
 * false with `why` set to the problem. */
static bool parse_type_txt(const char *value, volume_type *type, bool *big_endian, const char **why)
{
    char words[32][16];
    int count = 0;
    for (const char *s = value; *s;) {
        if (!isalnum((unsigned char)*s)) {
            s++;
            continue;
        }
        size_t n = 0;
        while (isalnum((unsigned char)*s)) {
            if (n + 1 < sizeof words[0])
                words[count][n++] = (char)tolower((unsigned char)*s);
            s++;
        }
        words[count][n] = '\0';
        if (++count == 32)
            break;
    }
    /* read_as: a type after "read as"; read_sign: "read as signed/unsigned";
     * sign: a free-standing "signed"/"unsigned" (+1 / -1) */
    int named = -1, read_as = -1, read_sign = 0, bits = 0, sign = 0;
    bool little = false, big = false, floating = false;
    for (int w = 0; w < count; w++) {
        const char *word = words[w];
        int t = type_word(word);
        if (w >= 2 && strcmp(words[w - 2], "read") == 0 && strcmp(words[w - 1], "as") == 0) {
            if (t >= 0)
                read_as = t;
            else if (strcmp(word, "signed") == 0)
                read_sign = 1;
            else if (strcmp(word, "unsigned") == 0)
                read_sign = -1;
            else {
                *why = "'read as' names no type (uint8, int16, uint16, float32, signed or unsigned)";
                return false;
            }
            continue;
        }
        if (t >= 0) {
            if (named >= 0 && named != t) {
                *why = "names two different types";
                return false;
            }
            named = t;
        } else if (strcmp(word, "signed") == 0)
            sign = 1;
        else if (strcmp(word, "unsigned") == 0)
            sign = -1;
        else if (strcmp(word, "8") == 0 || strcmp(word, "16") == 0 || strcmp(word, "32") == 0) {
            if (w + 1 < count && strcmp(words[w + 1], "bit") == 0)
                bits = atoi(word);
        } else if (strcmp(word, "little") == 0)
            little = true;
        else if (strcmp(word, "big") == 0)
            big = true;
        else if (strcmp(word, "floating") == 0)
            floating = true;
    }
    if (little && big) {
        *why = "says both little and big endian";
        return false;
    }
    *big_endian = big;
    int t = -1;
    if (read_as >= 0)
        t = read_as; /* the header's own instruction wins */
    else if (named >= 0) {
        bool named_signed = named == VOLUME_INT16 || named == VOLUME_FLOAT32;
        if (read_sign == 0 && sign != 0 && (sign > 0) != named_signed && named != VOLUME_FLOAT32) {
            *why = sign > 0 ? "names an unsigned type but says 'signed'" : "names a signed type but says 'unsigned'";
            return false;
        }
        t = named;
        if (read_sign != 0 && named != VOLUME_FLOAT32)
            bits = (int)(8 * volume_type_size((volume_type)named));
        else
            read_sign = 0;
    }
    if (read_sign != 0)
        sign = read_sign;
    if (t < 0 || read_sign != 0) {
        if (bits == 16 && sign != 0)
            t = sign > 0 ? VOLUME_INT16 : VOLUME_UINT16;
        else if (bits == 8 && sign <= 0)
            t = VOLUME_UINT8;
        else if (bits == 32 && floating)
            t = VOLUME_FLOAT32;
        else if (bits == 16) {
            *why = "16-bit without 'signed', 'unsigned' or 'read as int16/uint16'";
            return false;
        } else if (bits == 8) {
            *why = "signed 8-bit samples are not supported (uint8, int16, uint16, float32)";
            return false;
        } else if (bits == 32) {
            *why = "32-bit samples other than 'floating point' are not supported (uint8, int16, uint16, float32)";
            return false;
        } else {
            *why = "unknown type (uint8, int16, uint16, float32, or e.g. '16-bit signed')";
            return false;
        }
    }
    if (bits != 0 && (size_t)bits != 8 * volume_type_size((volume_type)t)) {
        *why = "the bit width disagrees with the type";
        return false;
    }
    *type = (volume_type)t;
    return true;
}

/* one field of a text header: where it was seen (0: not given) and its value */
typedef struct txt_field {
    const char *name;
    unsigned line;
    char *value;
} txt_field;

enum { TXT_DIMS, TXT_TYPE, TXT_FILE, TXT_BYTES, TXT_SPACING, TXT_ORIGIN, TXT_FIELDS };

volume *volume_load_raw_txt(const char *header_path, tess_error *err)
{
    header_text h;
    if (!read_header(header_path, true, &h, err))
        return NULL;
    if (memchr(h.text, '\0', h.len)) {
        free(h.text);
        tess_error_set(err, "%s: a NUL byte: not a text header", header_path);
        return NULL;
    }
    txt_field f[TXT_FIELDS] = {{"dims", 0, NULL},    {"type", 0, NULL},    {"file", 0, NULL},
                               {"bytes", 0, NULL},   {"spacing", 0, NULL}, {"origin", 0, NULL}};
    char *cursor = h.text, *end = h.text + h.len, *line;
    volume *v = NULL;
    unsigned line_no = 0;
    while ((line = next_line(&cursor, end))) {
        line_no++;
        if (line[0] == ' ' || line[0] == '\t' || line[0] == '#' || trim(line)[0] == '\0')
            continue; /* a continuation, a comment or a blank line */
        char *colon = strchr(line, ':');
        if (!colon) {
            tess_error_set(err, "%s:%u: expected 'field: value', got '%.*s'", header_path, line_no, QUOTE_CHARS,
                           line);
            goto fail;
        }
        *colon = '\0';
        char *name = trim(line);
        for (char *c = name; *c; c++)
            *c = (char)tolower((unsigned char)*c);
        for (int i = 0; i < TXT_FIELDS; i++) {
            if (strcmp(name, f[i].name) != 0)
                continue;
            if (f[i].line) {
                tess_error_set(err, "%s:%u: field '%s' given again (first on line %u)", header_path, line_no, name,
                               f[i].line);
                goto fail;
            }
            f[i].line = line_no;
            f[i].value = trim(colon + 1);
        }
    }
    for (int i = 0; i < 3; i++)
        if (!f[i].line) {
            tess_error_set(err, "%s: missing field '%s'", header_path, f[i].name);
            goto fail;
        }

    uint32_t n[3];
    drop_comment(f[TXT_DIMS].value);
    if (!parse_dims_txt(f[TXT_DIMS].value, n)) {
        tess_error_set(err, "%s:%u: field 'dims': expected 'NX x NY x NZ', got '%.*s'", header_path,
                       f[TXT_DIMS].line, QUOTE_CHARS, trim(f[TXT_DIMS].value));
        goto fail;
    }
    char what[PATH_BYTES + 32];
    snprintf(what, sizeof what, "%s:%u: field 'dims'", header_path, f[TXT_DIMS].line);
    if (!volume_check_dims(n, what, err))
        goto fail;

    volume_type type;
    bool big_endian;
    const char *why = NULL;
    drop_comment(f[TXT_TYPE].value);
    if (!parse_type_txt(f[TXT_TYPE].value, &type, &big_endian, &why)) {
        tess_error_set(err, "%s:%u: field 'type': %s: '%.*s'", header_path, f[TXT_TYPE].line, why, QUOTE_CHARS,
                       trim(f[TXT_TYPE].value));
        goto fail;
    }

    v = volume_alloc_header(n, type);
    if (!v) {
        tess_error_set(err, "%s: out of memory", header_path);
        goto fail;
    }
    const int triples[2] = {TXT_SPACING, TXT_ORIGIN};
    for (int t = 0; t < 2; t++) {
        txt_field *tf = &f[triples[t]];
        if (!tf->line)
            continue;
        double *out = t == 0 ? v->spacing : v->origin;
        drop_comment(tf->value);
        if (!parse_triple_txt(tf->value, out)) {
            tess_error_set(err, "%s:%u: field '%s': expected three finite numbers and a unit, got '%.*s'",
                           header_path, tf->line, tf->name, QUOTE_CHARS, trim(tf->value));
            goto fail;
        }
        if (t == 0)
            for (int a = 0; a < 3; a++)
                if (!(out[a] > 0.0)) {
                    tess_error_set(err, "%s:%u: field 'spacing': %g along %c is not positive", header_path, tf->line,
                                   out[a], "xyz"[a]);
                    goto fail;
                }
    }
    uint64_t need = (uint64_t)volume_count(v) * volume_type_size(type);
    if (f[TXT_BYTES].line) {
        const char *s = skip_blanks(f[TXT_BYTES].value);
        uint64_t bytes;
        if (!parse_u64(&s, &bytes)) {
            tess_error_set(err, "%s:%u: field 'bytes': expected a byte count, got '%.*s'", header_path,
                           f[TXT_BYTES].line, QUOTE_CHARS, f[TXT_BYTES].value);
            goto fail;
        }
        if (bytes != need) {
            tess_error_set(err, "%s:%u: field 'bytes': %llu, but dims and type make %u*%u*%u %s = %llu", header_path,
                           f[TXT_BYTES].line, (unsigned long long)bytes, n[0], n[1], n[2], volume_type_name(type),
                           (unsigned long long)need);
            goto fail;
        }
    }
    char *file = f[TXT_FILE].value;
    drop_comment(file);
    file = trim(file);
    char data_path[PATH_BYTES];
    if (file[0] == '\0' || !join_dir(data_path, header_path, file)) {
        tess_error_set(err, "%s:%u: field 'file': %s", header_path, f[TXT_FILE].line,
                       file[0] ? "path too long" : "empty");
        goto fail;
    }
    data_layout lay = {header_path, data_path, 0, true, big_endian};
    if (!load_samples(v, &lay, err))
        goto fail;
    free(h.text);
    return v;
fail:
    volume_destroy(v);
    free(h.text);
    return NULL;
}

/* ---- the NRRD reader ------------------------------------------------------ */

/* NRRD type names (format.html, "type") mapped to ours; -1: known but not supported */
static int nrrd_type(const char *s, bool *known)
{
    static const struct {
        const char *name;
        int type;
    } names[] = {
        {"uchar", VOLUME_UINT8},
        {"unsigned char", VOLUME_UINT8},
        {"uint8", VOLUME_UINT8},
        {"uint8_t", VOLUME_UINT8},
        {"short", VOLUME_INT16},
        {"short int", VOLUME_INT16},
        {"signed short", VOLUME_INT16},
        {"signed short int", VOLUME_INT16},
        {"int16", VOLUME_INT16},
        {"int16_t", VOLUME_INT16},
        {"ushort", VOLUME_UINT16},
        {"unsigned short", VOLUME_UINT16},
        {"unsigned short int", VOLUME_UINT16},
        {"uint16", VOLUME_UINT16},
        {"uint16_t", VOLUME_UINT16},
        {"float", VOLUME_FLOAT32},
        {"signed char", -1},
        {"int8", -1},
        {"int8_t", -1},
        {"int", -1},
        {"signed int", -1},
        {"int32", -1},
        {"int32_t", -1},
        {"uint", -1},
        {"unsigned int", -1},
        {"uint32", -1},
        {"uint32_t", -1},
        {"longlong", -1},
        {"long long", -1},
        {"long long int", -1},
        {"signed long long", -1},
        {"signed long long int", -1},
        {"int64", -1},
        {"int64_t", -1},
        {"ulonglong", -1},
        {"unsigned long long", -1},
        {"unsigned long long int", -1},
        {"uint64", -1},
        {"uint64_t", -1},
        {"double", -1},
        {"block", -1},
    };
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strcmp(s, names[i].name) == 0) {
            *known = true;
            return names[i].type;
        }
    *known = false;
    return -1;
}

/* "(a,b,c)" with blanks anywhere between the tokens; *s moves past it */
static bool parse_vector(const char **s, double out[3])
{
    const char *p = skip_blanks(*s);
    if (*p++ != '(')
        return false;
    for (int a = 0; a < 3; a++) {
        p = skip_blanks(p);
        if (!parse_double(&p, &out[a]))
            return false;
        p = skip_blanks(p);
        if (*p++ != (a < 2 ? ',' : ')'))
            return false;
    }
    *s = p;
    return true;
}

enum {
    NRRD_TYPE,
    NRRD_DIMENSION,
    NRRD_SIZES,
    NRRD_ENDIAN,
    NRRD_ENCODING,
    NRRD_SPACINGS,
    NRRD_DIRECTIONS,
    NRRD_ORIGIN,
    NRRD_DATA_FILE,
    NRRD_BYTE_SKIP,
    NRRD_LINE_SKIP,
    NRRD_SPACE_DIMENSION,
    NRRD_SPACE,
    NRRD_FIELDS
};

volume *volume_load_nrrd(const char *path, tess_error *err)
{
    header_text h;
    if (!read_header(path, false, &h, err))
        return NULL;
    txt_field f[NRRD_FIELDS] = {
        {"type", 0, NULL},        {"dimension", 0, NULL},        {"sizes", 0, NULL},
        {"endian", 0, NULL},      {"encoding", 0, NULL},         {"spacings", 0, NULL},
        {"space directions", 0, NULL}, {"space origin", 0, NULL}, {"data file", 0, NULL},
        {"byte skip", 0, NULL},   {"line skip", 0, NULL},        {"space dimension", 0, NULL},
        {"space", 0, NULL},
    };
    volume *v = NULL;
    char *cursor = h.text, *end = h.text + h.len, *line;
    unsigned line_no = 0;
    bool blank_seen = false;
    while ((line = next_line(&cursor, end))) {
        line_no++;
        if (line_no == 1) {
            if (strncmp(line, "NRRD000", 7) != 0 || line[7] < '1' || line[7] > '5' || line[8] != '\0') {
                tess_error_set(err, "%s:1: expected the magic 'NRRD0001' to 'NRRD0005', got '%.*s'", path, 16, line);
                goto fail;
            }
            continue;
        }
        if (line[0] == '\0') {
            blank_seen = true;
            break; /* the header ends; an attached file's data follows */
        }
        if (line[0] == '#')
            continue;
        char *sep = strstr(line, ": ");
        char *kv = strstr(line, ":=");
        if (kv && (!sep || kv < sep))
            continue; /* a key/value pair: free text for other programs */
        if (!sep) {
            tess_error_set(err, "%s:%u: expected 'field: value', got '%.*s'", path, line_no, QUOTE_CHARS, line);
            goto fail;
        }
        *sep = '\0';
        const char *name = line;
        if (strcmp(name, "datafile") == 0)
            name = "data file";
        else if (strcmp(name, "byteskip") == 0)
            name = "byte skip";
        else if (strcmp(name, "lineskip") == 0)
            name = "line skip";
        for (int i = 0; i < NRRD_FIELDS; i++) {
            if (strcmp(name, f[i].name) != 0)
                continue;
            if (f[i].line) {
                tess_error_set(err, "%s:%u: field '%s' given again (first on line %u)", path, line_no, name,
                               f[i].line);
                goto fail;
            }
            f[i].line = line_no;
            f[i].value = trim(sep + 2);
        }
    }
    if (line_no == 0) {
        tess_error_set(err, "%s: empty file, expected the magic 'NRRD0001' to 'NRRD0005'", path);
        goto fail;
    }
    const int required[] = {NRRD_TYPE, NRRD_DIMENSION, NRRD_SIZES, NRRD_ENCODING};
    for (size_t i = 0; i < sizeof required / sizeof required[0]; i++)
        if (!f[required[i]].line) {
            tess_error_set(err, "%s: missing field '%s'", path, f[required[i]].name);
            goto fail;
        }

    bool known;
    int type = nrrd_type(f[NRRD_TYPE].value, &known);
    if (type < 0) {
        tess_error_set(err, "%s:%u: field 'type': %s '%.*s' (uchar, short, ushort, float)", path,
                       f[NRRD_TYPE].line, known ? "not supported:" : "unknown type", QUOTE_CHARS,
                       f[NRRD_TYPE].value);
        goto fail;
    }
    if (strcmp(f[NRRD_DIMENSION].value, "3") != 0) {
        tess_error_set(err, "%s:%u: field 'dimension': '%.*s', only 3 is supported", path, f[NRRD_DIMENSION].line,
                       QUOTE_CHARS, f[NRRD_DIMENSION].value);
        goto fail;
    }
    uint32_t n[3];
    const char *s = f[NRRD_SIZES].value;
    for (int a = 0; a < 3; a++) {
        uint64_t size;
        s = skip_blanks(s);
        if (!parse_u64(&s, &size) || size > UINT32_MAX || (*s != ' ' && *s != '\t' && *s != '\0')) {
            tess_error_set(err, "%s:%u: field 'sizes': expected three positive integers, got '%.*s'", path,
                           f[NRRD_SIZES].line, QUOTE_CHARS, f[NRRD_SIZES].value);
            goto fail;
        }
        n[a] = (uint32_t)size;
    }
    if (*skip_blanks(s) != '\0') {
        tess_error_set(err, "%s:%u: field 'sizes': more than three sizes in '%.*s'", path, f[NRRD_SIZES].line,
                       QUOTE_CHARS, f[NRRD_SIZES].value);
        goto fail;
    }
    char what[PATH_BYTES + 32];
    snprintf(what, sizeof what, "%s:%u: field 'sizes'", path, f[NRRD_SIZES].line);
    if (!volume_check_dims(n, what, err))
        goto fail;

    if (strcmp(f[NRRD_ENCODING].value, "raw") != 0) {
        tess_error_set(err, "%s:%u: field 'encoding': '%.*s' is not supported (raw only)", path,
                       f[NRRD_ENCODING].line, QUOTE_CHARS, f[NRRD_ENCODING].value);
        goto fail;
    }
    bool big_endian = false;
    if (f[NRRD_ENDIAN].line) {
        if (strcmp(f[NRRD_ENDIAN].value, "big") == 0)
            big_endian = true;
        else if (strcmp(f[NRRD_ENDIAN].value, "little") != 0) {
            tess_error_set(err, "%s:%u: field 'endian': expected 'little' or 'big', got '%.*s'", path,
                           f[NRRD_ENDIAN].line, QUOTE_CHARS, f[NRRD_ENDIAN].value);
            goto fail;
        }
    } else if (volume_type_size((volume_type)type) > 1) {
        tess_error_set(err, "%s: missing field 'endian' (required for %s samples)", path,
                       volume_type_name((volume_type)type));
        goto fail;
    }
    if (f[NRRD_LINE_SKIP].line && strcmp(f[NRRD_LINE_SKIP].value, "0") != 0) {
        tess_error_set(err, "%s:%u: field 'line skip': '%.*s' is not supported (0 only)", path,
                       f[NRRD_LINE_SKIP].line, QUOTE_CHARS, f[NRRD_LINE_SKIP].value);
        goto fail;
    }
    int64_t byte_skip = 0;
    if (f[NRRD_BYTE_SKIP].line) {
        const char *b = f[NRRD_BYTE_SKIP].value;
        uint64_t skip;
        if (strcmp(b, "-1") == 0)
            byte_skip = -1;
        else if (parse_u64(&b, &skip) && *b == '\0' && skip <= HEADER_MAX_BYTES * (uint64_t)1024)
            byte_skip = (int64_t)skip;
        else {
            tess_error_set(err, "%s:%u: field 'byte skip': expected -1 or a byte count, got '%.*s'", path,
                           f[NRRD_BYTE_SKIP].line, QUOTE_CHARS, f[NRRD_BYTE_SKIP].value);
            goto fail;
        }
    }
    if (f[NRRD_SPACE_DIMENSION].line && strcmp(f[NRRD_SPACE_DIMENSION].value, "3") != 0) {
        tess_error_set(err, "%s:%u: field 'space dimension': '%.*s', only 3 is supported", path,
                       f[NRRD_SPACE_DIMENSION].line, QUOTE_CHARS, f[NRRD_SPACE_DIMENSION].value);
        goto fail;
    }

    v = volume_alloc_header(n, (volume_type)type);
    if (!v) {
        tess_error_set(err, "%s: out of memory", path);
        goto fail;
    }
    if (f[NRRD_SPACINGS].line && f[NRRD_DIRECTIONS].line) {
        tess_error_set(err, "%s:%u: both 'spacings' and 'space directions' (line %u) are given", path,
                       f[NRRD_SPACINGS].line, f[NRRD_DIRECTIONS].line);
        goto fail;
    }
    if (f[NRRD_SPACINGS].line) {
        s = f[NRRD_SPACINGS].value;
        for (int a = 0; a < 3; a++) {
            s = skip_blanks(s);
            if (!parse_double(&s, &v->spacing[a]) || !(v->spacing[a] > 0.0)) {
                tess_error_set(err, "%s:%u: field 'spacings': expected three positive numbers, got '%.*s'", path,
                               f[NRRD_SPACINGS].line, QUOTE_CHARS, f[NRRD_SPACINGS].value);
                goto fail;
            }
        }
        if (*skip_blanks(s) != '\0') {
            tess_error_set(err, "%s:%u: field 'spacings': more than three in '%.*s'", path, f[NRRD_SPACINGS].line,
                           QUOTE_CHARS, f[NRRD_SPACINGS].value);
            goto fail;
        }
    }
    if (f[NRRD_DIRECTIONS].line) {
        s = f[NRRD_DIRECTIONS].value;
        for (int a = 0; a < 3; a++) {
            double dir[3];
            if (!parse_vector(&s, dir)) {
                tess_error_set(err, "%s:%u: field 'space directions': expected three vectors '(x,y,z)', got '%.*s'",
                               path, f[NRRD_DIRECTIONS].line, QUOTE_CHARS, f[NRRD_DIRECTIONS].value);
                goto fail;
            }
            /* axis a of the samples must run along world axis a, forwards: the grid is
             * axis-aligned and x fastest in the world too */
            if (dir[(a + 1) % 3] != 0.0 || dir[(a + 2) % 3] != 0.0) {
                tess_error_set(err,
                               "%s:%u: field 'space directions': axis %d is (%g,%g,%g): rotated or permuted axes "
                               "are not supported (axis-aligned only)",
                               path, f[NRRD_DIRECTIONS].line, a, dir[0], dir[1], dir[2]);
                goto fail;
            }
            if (!(dir[a] > 0.0)) {
                tess_error_set(err,
                               "%s:%u: field 'space directions': axis %d is (%g,%g,%g): a spacing that is not "
                               "positive (a flipped axis) is not supported",
                               path, f[NRRD_DIRECTIONS].line, a, dir[0], dir[1], dir[2]);
                goto fail;
            }
            v->spacing[a] = dir[a];
        }
        if (*skip_blanks(s) != '\0') {
            tess_error_set(err, "%s:%u: field 'space directions': more than three vectors in '%.*s'", path,
                           f[NRRD_DIRECTIONS].line, QUOTE_CHARS, f[NRRD_DIRECTIONS].value);
            goto fail;
        }
    }
    if (f[NRRD_ORIGIN].line) {
        s = f[NRRD_ORIGIN].value;
        if (!parse_vector(&s, v->origin) || *skip_blanks(s) != '\0') {
            tess_error_set(err, "%s:%u: field 'space origin': expected '(x,y,z)' of finite numbers, got '%.*s'", path,
                           f[NRRD_ORIGIN].line, QUOTE_CHARS, f[NRRD_ORIGIN].value);
            goto fail;
        }
    }

    char data_path[PATH_BYTES];
    data_layout lay = {path, data_path, byte_skip, byte_skip >= 0, big_endian};
    if (f[NRRD_DATA_FILE].line) {
        const char *file = f[NRRD_DATA_FILE].value;
        if (strncmp(file, "LIST", 4) == 0 || strchr(file, '%')) {
            tess_error_set(err, "%s:%u: field 'data file': '%.*s': data split over several files is not supported",
                           path, f[NRRD_DATA_FILE].line, QUOTE_CHARS, file);
            goto fail;
        }
        if (file[0] == '\0' || !join_dir(data_path, path, file)) {
            tess_error_set(err, "%s:%u: field 'data file': %s", path, f[NRRD_DATA_FILE].line,
                           file[0] ? "path too long" : "empty");
            goto fail;
        }
        /* byte skip counts from the data file's start */
    } else {
        /* attached: the samples start after the blank line */
        if (!blank_seen) {
            if (h.file_bytes > h.len)
                tess_error_set(err, "%s: no blank line ends the header within its first %u bytes", path,
                               HEADER_MAX_BYTES);
            else
                tess_error_set(err, "%s: no 'data file' and no blank line before attached data", path);
            goto fail;
        }
        snprintf(data_path, sizeof data_path, "%s", path);
        if (byte_skip >= 0)
            lay.offset = (int64_t)(cursor - h.text) + byte_skip;
    }
    if (!load_samples(v, &lay, err))
        goto fail;
    free(h.text);
    return v;
fail:
    volume_destroy(v);
    free(h.text);
    return NULL;
}

/* ---- by name -------------------------------------------------------------- */

volume *volume_load(const char *path, tess_error *err)
{
    if (path_has_extension(path, ".nrrd") || path_has_extension(path, ".nhdr"))
        return volume_load_nrrd(path, err);
    if (path_has_extension(path, ".txt"))
        return volume_load_raw_txt(path, err);
    if (path_has_extension(path, ".raw")) {
        char header[PATH_BYTES];
        if (snprintf(header, sizeof header, "%.*s.txt", (int)(strlen(path) - 4), path) >= (int)sizeof header) {
            tess_error_set(err, "%s: path too long", path);
            return NULL;
        }
        if (access(header, R_OK) != 0) {
            tess_error_set(err, "%s: raw data needs its header %s: %s", path, header, strerror(errno));
            return NULL;
        }
        return volume_load_raw_txt(header, err);
    }
    /* no known extension: a NRRD by its magic, else refused */
    char magic[8] = {0};
    FILE *file = fopen(path, "rb");
    if (!file) {
        tess_error_set(err, "%s: %s", path, strerror(errno));
        return NULL;
    }
    size_t got = fread(magic, 1, sizeof magic, file);
    fclose(file);
    if (got == sizeof magic && memcmp(magic, "NRRD000", 7) == 0)
        return volume_load_nrrd(path, err);
    tess_error_set(err, "%s: not a volume this reader knows (.nrrd, .nhdr, .txt header with .raw data)", path);
    return NULL;
}
