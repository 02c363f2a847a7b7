/* scene_json.c - scene_load_json: JSON scene files, read with json-c.
 *
 * SCENE FILE FORMAT (docs/scene-format.md holds the same reference as Markdown)
 *
 * A scene file is one JSON object. Every field is optional except as noted, a
 * field the format does not name is an error, and so is a key given twice in
 * one object. Comments are allowed: / * ... * / and // to the end of the line.
 * Colours are linear RGB; lengths are in the units of the mesh files (world
 * units); angles are in degrees.
 *
 *   "camera": {                     without it the renderer frames the bounds
 *       "eye": [x, y, z],           required: the pinhole
 *       "look_at": [x, y, z],       required: the point at the image centre
 *       "up": [x, y, z],            default [0, 1, 0]; not parallel to the view
 *       "fov_deg": 40               vertical field of view, in (0, 180); default 40
 *   }
 *   "background": [r, g, b]         colour of rays that hit nothing, each >= 0;
 *                                   default [0.02, 0.02, 0.03]
 *   "ambient": [r, g, b]            ambient light, each >= 0; default [0.1, 0.1, 0.1]
 *   "materials": {                  name -> material, names 1..63 bytes
 *       "NAME": {
 *           "model": "lambert" | "phong",   default "lambert"
 *           "diffuse": [r, g, b],   reflectance, each in [0, 1]; default 0.7 grey
 *           "specular": [r, g, b],  Phong lobe colour, each >= 0; default [0, 0, 0]
 *           "shininess": 32,        Phong exponent, >= 0; default 0
 *           "ambient": 1.0          fraction of diffuse under ambient light, [0, 1]; default 1
 *       }, ...
 *   }
 *   "lights": [                     absent: one default directional light
 *       {"type": "directional",     required: "directional" or "point"
 *        "direction": [x, y, z],    directional only, required: towards the light, not zero
 *        "position": [x, y, z],     point only, required
 *        "color": [r, g, b],        each >= 0; default [1, 1, 1]
 *        "intensity": 1,            >= 0; default 1 (point lights fall off as 1/d^2)
 *        "shadows": true},          default true
 *       ...                         [] means no lights at all (ambient only)
 *   ]
 *   "meshes": [
 *       {"file": "mesh.ply",        required: any file mesh_load() reads; a relative
 *                                   path is relative to the scene file's directory
 *        "material": "NAME",        a name from "materials"; without it the mesh's own
 *                                   file materials (OBJ+MTL) are used, else the default
 *                                   material; with it, file materials are ignored
 *        "transform": {             object -> world: p' = T * Rz * Ry * Rx * S * p
 *            "translate": [x, y, z],    default [0, 0, 0]
 *            "rotate_deg": [x, y, z],   about X, then Y, then Z (right-handed); default 0
 *            "scale": s | [sx, sy, sz]  no component 0; default 1
 *        },
 *        "matrix": [12 numbers],    instead of "transform": row-major 3x4 [R|t],
 *                                   p' = R p + t; R must not be singular
 *        "optional": false},        true: a file that does not exist is skipped with a
 *                                   warning (a file that exists but fails to load is
 *                                   still an error)
 *   ]
 *   "spheres": [
 *       {"center": [x, y, z],       required
 *        "radius": r,               required, > 0
 *        "material": "NAME"}        default: the default material
 *   ]
 *
 * The default material is material_default() (grey Lambert), or the file's own
 * material if "materials" names one "default". A scene must end up with at
 * least one triangle or sphere. Numbers must be finite (json-c would otherwise
 * accept NaN and Infinity) and fit a float.
 *
 * Errors are one line: "PATH: cannot open: REASON", "PATH:LINE:COL: JSON syntax
 * error: DESC" (column in bytes), "PATH:LINE:COL: duplicate key 'K' in a JSON
 * object", "PATH: field 'lights[1].color': PROBLEM", or "PATH: scene has no
 * geometry".
 *
 * json-c notes: its default (non-strict) mode is needed for comments, and that
 * mode also accepts single-quoted strings, trailing commas and any-case
 * true/false/null; those are tolerated, not part of the format. Even strict
 * mode accepts NaN/Infinity, hence the finiteness checks. json-c keeps the last
 * of duplicate keys silently, hence the scan for them here. */
#include "scene.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <json.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "log.h"

/* Scene files describe; the geometry lives in mesh files. Refusing anything
 * larger keeps a mistaken path (a mesh, /dev/zero) from eating memory. */
#define SCENE_JSON_MAX_BYTES (16u << 20)
/* Enough for a deep field path such as "materials.<63 bytes>.specular[2]". */
#define FIELD_PATH_BYTES 256
/* Resolved mesh file paths. */
#define MESH_PATH_BYTES 4096

/* ---- reading the file ------------------------------------------------- */

static const char *errno_text(int errnum, char *buf, size_t size)
{
    if (strerror_r(errnum, buf, size) != 0)
        snprintf(buf, size, "error %d", errnum);
    return buf;
}

/* The whole file as a NUL-terminated buffer the caller frees. Only regular
 * files are read (O_NONBLOCK keeps open() from waiting on a FIFO). */
static char *read_text_file(const char *path, size_t *len_out, tess_error *err)
{
    char why[128];
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        tess_error_set(err, "%s: cannot open: %s", path, errno_text(errno, why, sizeof why));
        return NULL;
    }
    struct stat st;
    char *buf = NULL;
    if (fstat(fd, &st) != 0) {
        tess_error_set(err, "%s: cannot open: %s", path, errno_text(errno, why, sizeof why));
        goto fail;
    }
    if (!S_ISREG(st.st_mode)) {
        tess_error_set(err, "%s: cannot open: not a regular file", path);
        goto fail;
    }
    if (st.st_size > (off_t)SCENE_JSON_MAX_BYTES) {
        tess_error_set(err, "%s: cannot open: %lld bytes is larger than a scene file may be (%u MiB)", path,
                       (long long)st.st_size, SCENE_JSON_MAX_BYTES >> 20);
        goto fail;
    }
    /* one byte more than fstat promised, to notice a file that grows meanwhile */
    size_t room = (size_t)st.st_size + 1, len = 0;
    buf = malloc(room + 1);
    if (!buf) {
        tess_error_set(err, "%s: out of memory reading the file", path);
        goto fail;
    }
    while (len < room) {
        ssize_t got = read(fd, buf + len, room - len);
        if (got < 0 && errno == EINTR)
            continue;
        if (got < 0) {
            tess_error_set(err, "%s: cannot read: %s", path, errno_text(errno, why, sizeof why));
            goto fail;
        }
        if (got == 0)
            break;
        len += (size_t)got;
    }
    if (len == room) {
        tess_error_set(err, "%s: cannot read: the file changed while being read", path);
        goto fail;
    }
    buf[len] = '\0';
    close(fd);
    *len_out = len;
    return buf;

fail:
    free(buf);
    close(fd);
    return NULL;
}

/* ---- syntax: json-c, positions, duplicate keys ------------------------ */

/* 1-based line and byte column of `offset` in `text`. */
static void line_col(const char *text, size_t offset, unsigned long *line, unsigned long *col)
{
    *line = 1;
    size_t line_start = 0;
    for (size_t i = 0; i < offset; i++)
        if (text[i] == '\n') {
            (*line)++;
            line_start = i + 1;
        }
    *col = (unsigned long)(offset - line_start) + 1;
}

static bool syntax_error(const char *path, const char *text, size_t offset, const char *desc, tess_error *err)
{
    unsigned long line, col;
    line_col(text, offset, &line, &col);
    return tess_error_set(err, "%s:%lu:%lu: JSON syntax error: %s", path, line, col, desc);
}

/* Replace control characters (a key or name may hold "\n") so that every
 * message stays one line. */
static void make_one_line(char *s)
{
    for (; *s; s++)
        if ((unsigned char)*s < 0x20 || *s == 0x7f)
            *s = '?';
}

/* Offset just past whitespace and comments from `pos`; an unterminated block
 * comment runs to the end. */
static size_t skip_space(const char *text, size_t len, size_t pos)
{
    while (pos < len) {
        char ch = text[pos];
        if (ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r') {
            pos++;
        } else if (ch == '/' && pos + 1 < len && text[pos + 1] == '/') {
            while (pos < len && text[pos] != '\n')
                pos++;
        } else if (ch == '/' && pos + 1 < len && text[pos + 1] == '*') {
            const char *end = NULL;
            for (size_t i = pos + 2; i + 1 < len && !end; i++)
                if (text[i] == '*' && text[i + 1] == '/')
                    end = text + i;
            pos = end ? (size_t)(end - text) + 2 : len;
        } else {
            break;
        }
    }
    return pos;
}

/* Parse the whole text into *root (NULL for a JSON null; the caller puts
 * it). False with a "PATH:LINE:COL:" error on bad syntax or anything but
 * whitespace and comments after the top-level value. */
static bool parse_json(const char *path, const char *text, size_t len, json_object **root_out, tess_error *err)
{
    struct json_tokener *tok = json_tokener_new(); /* nesting limit JSON_TOKENER_DEFAULT_DEPTH */
    if (!tok)
        return tess_error_set(err, "%s: out of memory parsing JSON", path);
    json_tokener_set_flags(tok, JSON_TOKENER_VALIDATE_UTF8);
    json_object *root = json_tokener_parse_ex(tok, text, (int)len);
    enum json_tokener_error status = json_tokener_get_error(tok);
    size_t end = json_tokener_get_parse_end(tok);
    if (status == json_tokener_continue) {
        /* json-c waits for more input after a final // comment with no newline:
         * give it the newline. Still waiting afterwards means truncated input. */
        root = json_tokener_parse_ex(tok, "\n", 1);
        status = json_tokener_get_error(tok);
        end = len;
        if (status == json_tokener_continue)
            status = json_tokener_error_parse_eof;
    }
    json_tokener_free(tok);
    if (status != json_tokener_success) {
        json_object_put(root);
        return syntax_error(path, text, end, json_tokener_error_desc(status), err);
    }
    size_t rest = skip_space(text, len, end < len ? end : len);
    if (rest < len) {
        json_object_put(root);
        return syntax_error(path, text, rest, json_tokener_error_desc(json_tokener_error_parse_unexpected), err);
    }
    *root_out = root;
    return true;
}

/* One key of an object as written in the text. */
typedef struct key_ref {
    const char *bytes; /* the key's characters (points into the text, or into `owned`) */
    size_t len;
    size_t offset;     /* of its opening quote, for the message */
    char *owned;       /* decoded copy when the key holds escapes, else NULL */
} key_ref;

/* A walk over text json-c has already accepted, to find a key given twice in
 * one object (json-c silently keeps the last). The grammar is trusted; every
 * loop still advances so nothing can spin. Recursion depth is bounded by
 * json-c's nesting limit. */
typedef struct dup_scan {
    const char *text;
    size_t len, pos;
    size_t dup_offset;     /* of the first duplicate found, SIZE_MAX while none */
    char dup_key[SCENE_NAME_BYTES];
    bool out_of_memory;
} dup_scan;

static void scan_value(dup_scan *d);

/* Past a quoted string starting at d->pos ('"' or '\''). */
static void scan_string(dup_scan *d)
{
    char quote = d->text[d->pos++];
    while (d->pos < d->len && d->text[d->pos] != quote)
        d->pos += d->text[d->pos] == '\\' ? 2 : 1;
    d->pos = d->pos < d->len ? d->pos + 1 : d->len;
}

/* Fill `k` for the string at d->pos and move past it. Escaped keys are
 * decoded by json-c so that "a" and "\u0061" compare equal. */
static void scan_key(dup_scan *d, key_ref *k)
{
    size_t start = d->pos;
    scan_string(d);
    k->offset = start;
    k->bytes = d->text + start + 1;
    k->len = d->pos - start >= 2 ? d->pos - start - 2 : 0;
    k->owned = NULL;
    if (!memchr(k->bytes, '\\', k->len))
        return;
    struct json_tokener *tok = json_tokener_new();
    json_object *str = tok ? json_tokener_parse_ex(tok, d->text + start, (int)(d->pos - start)) : NULL;
    if (str && json_object_is_type(str, json_type_string)) {
        size_t n = (size_t)json_object_get_string_len(str);
        k->owned = malloc(n + 1);
        if (k->owned) {
            memcpy(k->owned, json_object_get_string(str), n + 1);
            k->bytes = k->owned;
            k->len = n;
        }
    }
    d->out_of_memory |= !k->owned;
    json_object_put(str);
    json_tokener_free(tok);
}

static int key_order(const void *pa, const void *pb)
{
    const key_ref *a = pa, *b = pb;
    size_t n = a->len < b->len ? a->len : b->len;
    int c = memcmp(a->bytes, b->bytes, n);
    if (c != 0)
        return c;
    if (a->len != b->len)
        return a->len < b->len ? -1 : 1;
    return a->offset < b->offset ? -1 : a->offset > b->offset;
}

/* Sort the keys of one object and remember the earliest second occurrence. */
static void check_keys_unique(dup_scan *d, key_ref *keys, size_t count)
{
    if (count < 2)
        return;
    qsort(keys, count, sizeof *keys, key_order);
    for (size_t i = 1; i < count; i++) {
        const key_ref *a = &keys[i - 1], *b = &keys[i];
        if (a->len != b->len || memcmp(a->bytes, b->bytes, a->len) != 0 || b->offset >= d->dup_offset)
            continue;
        d->dup_offset = b->offset;
        snprintf(d->dup_key, sizeof d->dup_key, "%.*s", (int)(b->len < 60 ? b->len : 60), b->bytes);
        make_one_line(d->dup_key);
    }
}

static bool push_key(dup_scan *d, key_ref **keys, size_t *count, size_t *cap)
{
    if (*count == *cap) {
        size_t n = *cap ? *cap * 2 : 16;
        key_ref *p = realloc(*keys, n * sizeof *p);
        if (!p) {
            d->out_of_memory = true;
            return false;
        }
        *keys = p;
        *cap = n;
    }
    scan_key(d, &(*keys)[(*count)++]);
    return true;
}

static void scan_object(dup_scan *d)
{
    key_ref *keys = NULL;
    size_t count = 0, cap = 0;
    d->pos++; /* '{' */
    while (d->pos < d->len) {
        d->pos = skip_space(d->text, d->len, d->pos);
        if (d->pos >= d->len)
            break;
        char ch = d->text[d->pos];
        if (ch == '}') {
            d->pos++;
            break;
        }
        if (ch == ',') {
            d->pos++;
            continue;
        }
        if (ch != '"' && ch != '\'') {
            d->pos++; /* not valid JSON here; json-c would have refused it */
            continue;
        }
        if (!push_key(d, &keys, &count, &cap))
            break;
        d->pos = skip_space(d->text, d->len, d->pos);
        if (d->pos < d->len && d->text[d->pos] == ':')
            d->pos++;
        scan_value(d);
    }
    check_keys_unique(d, keys, count);
    for (size_t i = 0; i < count; i++)
        free(keys[i].owned);
    free(keys);
}

static void scan_array(dup_scan *d)
{
    d->pos++; /* '[' */
    while (d->pos < d->len) {
        d->pos = skip_space(d->text, d->len, d->pos);
        if (d->pos >= d->len)
            break;
        char ch = d->text[d->pos];
        if (ch == ']') {
            d->pos++;
            break;
        }
        size_t before = d->pos;
        if (ch == ',')
            d->pos++;
        else
            scan_value(d);
        if (d->pos == before)
            d->pos++;
    }
}

static void scan_value(dup_scan *d)
{
    d->pos = skip_space(d->text, d->len, d->pos);
    if (d->pos >= d->len)
        return;
    switch (d->text[d->pos]) {
    case '{':
        scan_object(d);
        return;
    case '[':
        scan_array(d);
        return;
    case '"':
    case '\'':
        scan_string(d);
        return;
    default: /* number or literal: up to a delimiter */
        while (d->pos < d->len && !strchr(",]} \t\r\n/", d->text[d->pos]))
            d->pos++;
        return;
    }
}

static bool check_no_duplicate_keys(const char *path, const char *text, size_t len, tess_error *err)
{
    dup_scan d = {.text = text, .len = len, .pos = 0, .dup_offset = SIZE_MAX};
    scan_value(&d);
    if (d.out_of_memory)
        return tess_error_set(err, "%s: out of memory checking JSON keys", path);
    if (d.dup_offset == SIZE_MAX)
        return true;
    unsigned long line, col;
    line_col(text, d.dup_offset, &line, &col);
    return tess_error_set(err, "%s:%lu:%lu: duplicate key '%s' in a JSON object", path, line, col, d.dup_key);
}

/* ---- field paths and typed reads --------------------------------------- */


/* Where a check is, for its message: the scene file and the JSON field path. */
typedef struct json_ctx {
    const char *path;              /* the scene file as given; every message starts with it */
    tess_error *err;
    char field[FIELD_PATH_BYTES];  /* e.g. "lights[1].color"; "" at the top level; truncated if deep */
    size_t field_len;
} json_ctx;

/* Append to the field path; return the length to restore with field_leave. */
static size_t field_append(json_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static size_t field_append(json_ctx *c, const char *fmt, ...)
{
    size_t saved = c->field_len, room = sizeof c->field - saved;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(c->field + saved, room, fmt, ap);
    va_end(ap);
    if (n > 0)
        c->field_len += (size_t)n < room ? (size_t)n : room - 1;
    make_one_line(c->field + saved);
    return saved;
}

static size_t field_enter_key(json_ctx *c, const char *key)
{
    return field_append(c, "%s%s", c->field_len ? "." : "", key);
}

static size_t field_enter_index(json_ctx *c, size_t index) { return field_append(c, "[%zu]", index); }

static void field_leave(json_ctx *c, size_t saved)
{
    c->field_len = saved;
    c->field[saved] = '\0';
}

/* Report a problem with the current field; returns false. */
static bool field_fail(json_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static bool field_fail(json_ctx *c, const char *fmt, ...)
{
    char reason[TESS_ERROR_MSG_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    make_one_line(reason);
    return tess_error_set(c->err, "%s: field '%s': %s", c->path, c->field, reason);
}

/* Report a problem with member `key` of the current field. */
static bool member_fail(json_ctx *c, const char *key, const char *reason)
{
    size_t saved = field_enter_key(c, key);
    field_fail(c, "%s", reason);
    field_leave(c, saved);
    return false;
}

static const char *json_kind(json_object *v)
{
    switch (json_object_get_type(v)) {
    case json_type_null:
        return "null";
    case json_type_boolean:
        return "boolean";
    case json_type_double:
    case json_type_int:
        return "number";
    case json_type_object:
        return "object";
    case json_type_array:
        return "array";
    case json_type_string:
        return "string";
    }
    return "unknown";
}

static bool is_number(json_object *v)
{
    return json_object_is_type(v, json_type_double) || json_object_is_type(v, json_type_int);
}

static bool expect_object(json_ctx *c, json_object *v)
{
    return json_object_is_type(v, json_type_object) || field_fail(c, "expected an object, got %s", json_kind(v));
}

static bool expect_array(json_ctx *c, json_object *v)
{
    return json_object_is_type(v, json_type_array) || field_fail(c, "expected an array, got %s", json_kind(v));
}

/* Every key of object `v` must be in the NULL-terminated `allowed`. */
static bool check_fields(json_ctx *c, json_object *v, const char *const *allowed)
{
    struct json_object_iterator it = json_object_iter_begin(v), end = json_object_iter_end(v);
    for (; !json_object_iter_equal(&it, &end); json_object_iter_next(&it)) {
        const char *key = json_object_iter_peek_name(&it);
        bool known = false;
        for (const char *const *a = allowed; *a && !known; a++)
            known = strcmp(*a, key) == 0;
        if (known)
            continue;
        char reason[256];
        size_t used = (size_t)snprintf(reason, sizeof reason, "unknown field (expected one of: ");
        for (const char *const *a = allowed; *a && used < sizeof reason; a++)
            used += (size_t)snprintf(reason + used, sizeof reason - used, "%s%s", a == allowed ? "" : ", ", *a);
        if (used < sizeof reason)
            snprintf(reason + used, sizeof reason - used, ")");
        return member_fail(c, key, reason);
    }
    return true;
}

/* A closed or open interval for a number. */
typedef struct num_range {
    double lo, hi;
    bool lo_open, hi_open; /* true: the bound itself is excluded */
} num_range;

static const num_range range_float = {-FLT_MAX, FLT_MAX, false, false};
static const num_range range_nonneg = {0.0, FLT_MAX, false, false};
static const num_range range_positive = {0.0, FLT_MAX, true, false};
static const num_range range_unit = {0.0, 1.0, false, false};
static const num_range range_fov = {0.0, 180.0, true, true};

static bool in_range(double x, num_range r)
{
    bool above = r.lo_open ? x > r.lo : x >= r.lo;
    bool below = r.hi_open ? x < r.hi : x <= r.hi;
    return above && below;
}

static bool range_fail(json_ctx *c, double x, num_range r)
{
    if (r.lo == -FLT_MAX && r.hi == FLT_MAX)
        return field_fail(c, "%g is out of range for a float", x);
    if (r.hi == FLT_MAX)
        return field_fail(c, "must be %s %g, got %g", r.lo_open ? ">" : ">=", r.lo, x);
    return field_fail(c, "must be in %c%g, %g%c, got %g", r.lo_open ? '(' : '[', r.lo, r.hi, r.hi_open ? ')' : ']',
                      x);
}

/* The current field as a float in `r`. */
static bool value_number(json_ctx *c, json_object *v, num_range r, float *out)
{
    if (!is_number(v))
        return field_fail(c, "expected a number, got %s", json_kind(v));
    double x = json_object_get_double(v);
    /* json-c clamps integers that overflow 64 bits to these values */
    if (json_object_is_type(v, json_type_int) &&
        (json_object_get_int64(v) == INT64_MIN || json_object_get_uint64(v) == UINT64_MAX))
        return field_fail(c, "integer out of range");
    if (!isfinite(x))
        return field_fail(c, "expected a finite number, got %g", x);
    if (!in_range(x, r))
        return range_fail(c, x, r);
    *out = (float)x;
    return true;
}

/* The current field as an array of exactly `n` numbers, each in `r`. */
static bool value_numbers(json_ctx *c, json_object *v, size_t n, num_range r, float *out)
{
    if (!json_object_is_type(v, json_type_array))
        return field_fail(c, "expected an array of %zu numbers, got %s", n, json_kind(v));
    size_t got = json_object_array_length(v);
    if (got != n)
        return field_fail(c, "expected an array of %zu numbers, got %zu element%s", n, got, got == 1 ? "" : "s");
    for (size_t i = 0; i < n; i++) {
        size_t saved = field_enter_index(c, i);
        bool ok = value_number(c, json_object_array_get_idx(v, i), r, &out[i]);
        field_leave(c, saved);
        if (!ok)
            return false;
    }
    return true;
}

static bool value_vec3(json_ctx *c, json_object *v, num_range r, vec3 *out)
{
    float xyz[3];
    if (!value_numbers(c, v, 3, r, xyz))
        return false;
    *out = v3(xyz[0], xyz[1], xyz[2]);
    return true;
}

/* Whether `obj` has member `key`, and its value in *v. A JSON null is a
 * present member (*v == NULL) that the readers report as a type error. */
static bool get_member(json_object *obj, const char *key, json_object **v)
{
    return json_object_object_get_ex(obj, key, v);
}

static bool require_member(json_ctx *c, json_object *obj, const char *key)
{
    json_object *v;
    return get_member(obj, key, &v) || member_fail(c, key, "required field is missing");
}

/* Optional members: absent leaves *out as it is and succeeds. */
static bool opt_number(json_ctx *c, json_object *obj, const char *key, num_range r, float *out)
{
    json_object *v;
    if (!get_member(obj, key, &v))
        return true;
    size_t saved = field_enter_key(c, key);
    bool ok = value_number(c, v, r, out);
    field_leave(c, saved);
    return ok;
}

static bool opt_vec3(json_ctx *c, json_object *obj, const char *key, num_range r, vec3 *out)
{
    json_object *v;
    if (!get_member(obj, key, &v))
        return true;
    size_t saved = field_enter_key(c, key);
    bool ok = value_vec3(c, v, r, out);
    field_leave(c, saved);
    return ok;
}

static bool opt_bool(json_ctx *c, json_object *obj, const char *key, bool *out)
{
    json_object *v;
    if (!get_member(obj, key, &v))
        return true;
    if (!json_object_is_type(v, json_type_boolean)) {
        size_t saved = field_enter_key(c, key);
        field_fail(c, "expected a boolean, got %s", json_kind(v));
        field_leave(c, saved);
        return false;
    }
    *out = json_object_get_boolean(v);
    return true;
}

/* A non-empty string; *out points into the JSON tree. */
static bool opt_string(json_ctx *c, json_object *obj, const char *key, const char **out)
{
    json_object *v;
    if (!get_member(obj, key, &v))
        return true;
    size_t saved = field_enter_key(c, key);
    bool ok = json_object_is_type(v, json_type_string) ? true
                                                       : field_fail(c, "expected a string, got %s", json_kind(v));
    if (ok && json_object_get_string_len(v) == 0)
        ok = field_fail(c, "must not be empty");
    if (ok)
        *out = json_object_get_string(v);
    field_leave(c, saved);
    return ok;
}

/* A string that must be one of the NULL-terminated `names`; *out its index. */
static bool opt_choice(json_ctx *c, json_object *obj, const char *key, const char *const *names, int *out)
{
    const char *value = NULL;
    if (!opt_string(c, obj, key, &value))
        return false;
    if (!value)
        return true;
    for (int i = 0; names[i]; i++)
        if (strcmp(names[i], value) == 0) {
            *out = i;
            return true;
        }
    char list[128] = "";
    size_t used = 0;
    for (int i = 0; names[i] && used < sizeof list; i++)
        used += (size_t)snprintf(list + used, sizeof list - used, "%s%s", i ? ", " : "", names[i]);
    size_t saved = field_enter_key(c, key);
    field_fail(c, "unknown value '%s' (expected one of: %s)", value, list);
    field_leave(c, saved);
    return false;
}

/* ---- building the scene ------------------------------------------------ */

typedef struct loader {
    json_ctx ctx;
    scene *s;                 /* being built; owned by scene_load_json until returned */
    size_t dir_len;           /* bytes of ctx.path up to and including its last '/', 0 if none */
    uint32_t named_materials; /* scene materials 0..n-1 are the file's "materials", in file order */
    int default_material;     /* scene id of the fallback material, -1 until something needs it */
} loader;

static bool out_of_memory(loader *L)
{
    return tess_error_set(L->ctx.err, "%s: out of memory building the scene", L->ctx.path);
}

/* Id of the material named `name` in the file's "materials", or -1. */
static int find_material(const loader *L, const char *name)
{
    for (uint32_t i = 0; i < L->named_materials; i++)
        if (strcmp(L->s->materials[i].name, name) == 0)
            return (int)i;
    return -1;
}

/* The material for geometry without a "material": the file's "default" if it
 * defines one, else material_default(), added on first use. -1 on OOM. */
static int default_material_id(loader *L)
{
    if (L->default_material < 0)
        L->default_material = find_material(L, "default");
    if (L->default_material < 0) {
        material m = material_default();
        L->default_material = scene_add_material(L->s, &m);
    }
    return L->default_material;
}

/* Report member "material" naming `name`, which "materials" does not define. */
static bool unknown_material(json_ctx *c, const char *name)
{
    char reason[160];
    snprintf(reason, sizeof reason, "unknown material '%.64s' (not defined under 'materials')", name);
    return member_fail(c, "material", reason);
}

/* The material id for member "material" of `obj` (absent: the default). */
static bool material_ref(loader *L, json_object *obj, uint32_t *id)
{
    const char *name = NULL;
    if (!opt_string(&L->ctx, obj, "material", &name))
        return false;
    int found = name ? find_material(L, name) : default_material_id(L);
    if (found >= 0) {
        *id = (uint32_t)found;
        return true;
    }
    return name ? unknown_material(&L->ctx, name) : out_of_memory(L);
}

static bool load_material(json_ctx *c, json_object *v, const char *name, material *m)
{
    static const char *const fields[] = {"model", "diffuse", "specular", "shininess", "ambient", NULL};
    static const char *const models[] = {"lambert", "phong", NULL}; /* in material_model order */
    if (!expect_object(c, v) || !check_fields(c, v, fields))
        return false;
    *m = material_default();
    snprintf(m->name, sizeof m->name, "%s", name);
    int model = (int)m->model;
    if (!opt_choice(c, v, "model", models, &model))
        return false;
    m->model = (material_model)model;
    return opt_vec3(c, v, "diffuse", range_unit, &m->diffuse) &&
           opt_vec3(c, v, "specular", range_nonneg, &m->specular) &&
           opt_number(c, v, "shininess", range_nonneg, &m->shininess) &&
           opt_number(c, v, "ambient", range_unit, &m->ambient);
}

static bool load_materials(loader *L, json_object *root)
{
    json_ctx *c = &L->ctx;
    json_object *all;
    if (!get_member(root, "materials", &all))
        return true;
    size_t outer = field_enter_key(c, "materials");
    if (!expect_object(c, all)) {
        field_leave(c, outer);
        return false;
    }
    bool ok = true;
    struct json_object_iterator it = json_object_iter_begin(all), end = json_object_iter_end(all);
    for (; ok && !json_object_iter_equal(&it, &end); json_object_iter_next(&it)) {
        const char *name = json_object_iter_peek_name(&it);
        size_t saved = field_enter_key(c, name);
        material m;
        if (strlen(name) == 0 || strlen(name) >= SCENE_NAME_BYTES)
            ok = field_fail(c, "a material name must be 1 to %d bytes long", SCENE_NAME_BYTES - 1);
        else if (load_material(c, json_object_iter_peek_value(&it), name, &m))
            ok = scene_add_material(L->s, &m) >= 0 || out_of_memory(L);
        else
            ok = false;
        field_leave(c, saved);
    }
    field_leave(c, outer);
    L->named_materials = L->s->material_count;
    return ok;
}

/* A direction normalised in double precision, so tiny vectors survive; false
 * for the zero vector. */
static bool unit_direction(vec3 d, vec3 *out)
{
    double x = d.x, y = d.y, z = d.z, len = sqrt(x * x + y * y + z * z);
    if (!(len > 0.0))
        return false;
    *out = v3((float)(x / len), (float)(y / len), (float)(z / len));
    return true;
}

static bool load_light(json_ctx *c, json_object *v, light *l)
{
    static const char *const fields[] = {"type", "direction", "position", "color", "intensity", "shadows", NULL};
    static const char *const types[] = {"directional", "point", NULL}; /* in light_kind order */
    if (!expect_object(c, v) || !check_fields(c, v, fields) || !require_member(c, v, "type"))
        return false;
    *l = light_default_directional();
    int kind = 0;
    if (!opt_choice(c, v, "type", types, &kind))
        return false;
    l->kind = (light_kind)kind;
    const char *needed = l->kind == LIGHT_DIRECTIONAL ? "direction" : "position";
    const char *unused = l->kind == LIGHT_DIRECTIONAL ? "position" : "direction";
    json_object *ignored;
    if (get_member(v, unused, &ignored))
        return member_fail(c, unused,
                           l->kind == LIGHT_DIRECTIONAL ? "only point lights have a position"
                                                        : "only directional lights have a direction");
    if (!require_member(c, v, needed))
        return false;
    if (l->kind == LIGHT_DIRECTIONAL) {
        vec3 d;
        if (!opt_vec3(c, v, "direction", range_float, &d))
            return false;
        if (!unit_direction(d, &l->direction))
            return member_fail(c, "direction", "must not be the zero vector");
    } else if (!opt_vec3(c, v, "position", range_float, &l->position)) {
        return false;
    }
    return opt_vec3(c, v, "color", range_nonneg, &l->color) &&
           opt_number(c, v, "intensity", range_nonneg, &l->intensity) &&
           opt_bool(c, v, "shadows", &l->casts_shadows);
}

static bool load_lights(loader *L, json_object *root)
{
    json_ctx *c = &L->ctx;
    json_object *all;
    if (!get_member(root, "lights", &all)) {
        light l = light_default_directional();
        return scene_add_light(L->s, &l) >= 0 || out_of_memory(L);
    }
    size_t outer = field_enter_key(c, "lights");
    bool ok = expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = field_enter_index(c, i);
        light l;
        ok = load_light(c, json_object_array_get_idx(all, i), &l) && (scene_add_light(L->s, &l) >= 0 || out_of_memory(L));
        field_leave(c, saved);
    }
    field_leave(c, outer);
    return ok;
}

static bool load_camera(loader *L, json_object *root)
{
    static const char *const fields[] = {"eye", "look_at", "up", "fov_deg", NULL};
    json_ctx *c = &L->ctx;
    json_object *v;
    if (!get_member(root, "camera", &v))
        return true;
    size_t outer = field_enter_key(c, "camera");
    camera_desc cam = {.up = v3(0.f, 1.f, 0.f), .fov_deg = CAMERA_DEFAULT_FOV_DEG};
    bool ok = expect_object(c, v) && check_fields(c, v, fields) && require_member(c, v, "eye") &&
              require_member(c, v, "look_at") && opt_vec3(c, v, "eye", range_float, &cam.eye) &&
              opt_vec3(c, v, "look_at", range_float, &cam.look_at) && opt_vec3(c, v, "up", range_float, &cam.up) &&
              opt_number(c, v, "fov_deg", range_fov, &cam.fov_deg);
    if (ok) {
        tess_error why = {{0}};
        ok = camera_validate(&cam, &why) || field_fail(c, "%s", why.msg);
    }
    field_leave(c, outer);
    if (ok) {
        L->s->camera = cam;
        L->s->has_camera = true;
    }
    return ok;
}

static const float identity_xform[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

/* sin and cos of an angle in degrees, exact for multiples of 90 degrees so that
 * axis-aligned rotations do not smear 1e-17 into other axes. */
static void sin_cos_deg(double deg, double *s, double *co)
{
    static const double quarter_sin[4] = {0, 1, 0, -1};
    double turns = fmod(deg, 360.0);
    if (turns < 0)
        turns += 360.0;
    if (fmod(turns, 90.0) == 0.0) {
        int q = (int)(turns / 90.0) % 4;
        *s = quarter_sin[q];
        *co = quarter_sin[(q + 1) % 4];
        return;
    }
    double rad = deg * (3.14159265358979323846 / 180.0);
    *s = sin(rad);
    *co = cos(rad);
}

/* 3x3 product a * b, row-major. */
static void mat3_mul(const double a[9], const double b[9], double out[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* xform = T * Rz * Ry * Rx * S, row-major 3x4. */
static void compose_transform(vec3 translate, vec3 rotate_deg, vec3 scale, float xform[12])
{
    double sx, cx, sy, cy, sz, cz;
    sin_cos_deg(rotate_deg.x, &sx, &cx);
    sin_cos_deg(rotate_deg.y, &sy, &cy);
    sin_cos_deg(rotate_deg.z, &sz, &cz);
    const double rx[9] = {1, 0, 0, 0, cx, -sx, 0, sx, cx};
    const double ry[9] = {cy, 0, sy, 0, 1, 0, -sy, 0, cy};
    const double rz[9] = {cz, -sz, 0, sz, cz, 0, 0, 0, 1};
    double zy[9], r[9];
    mat3_mul(rz, ry, zy);
    mat3_mul(zy, rx, r);
    const double s[3] = {scale.x, scale.y, scale.z}, t[3] = {translate.x, translate.y, translate.z};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            xform[4 * i + j] = (float)(r[3 * i + j] * s[j]);
        xform[4 * i + 3] = (float)t[i];
    }
}

/* "scale": one number for all axes or three; none of them 0. */
static bool read_scale(json_ctx *c, json_object *t, vec3 *scale)
{
    json_object *v;
    if (!get_member(t, "scale", &v))
        return true;
    size_t saved = field_enter_key(c, "scale");
    bool ok;
    if (is_number(v)) {
        float k = 1.f;
        ok = value_number(c, v, range_float, &k);
        *scale = v3(k, k, k);
    } else if (json_object_is_type(v, json_type_array)) {
        ok = value_vec3(c, v, range_float, scale);
    } else {
        ok = field_fail(c, "expected a number or an array of 3 numbers, got %s", json_kind(v));
    }
    if (ok && (scale->x == 0.f || scale->y == 0.f || scale->z == 0.f))
        ok = field_fail(c, "must not be zero (on any axis)");
    field_leave(c, saved);
    return ok;
}

static bool read_transform(json_ctx *c, json_object *t, float xform[12])
{
    static const char *const fields[] = {"translate", "rotate_deg", "scale", NULL};
    vec3 translate = v3(0.f, 0.f, 0.f), rotate = v3(0.f, 0.f, 0.f), scale = v3(1.f, 1.f, 1.f);
    if (!expect_object(c, t) || !check_fields(c, t, fields) ||
        !opt_vec3(c, t, "translate", range_float, &translate) ||
        !opt_vec3(c, t, "rotate_deg", range_float, &rotate) || !read_scale(c, t, &scale))
        return false;
    compose_transform(translate, rotate, scale, xform);
    return true;
}

static bool read_matrix(json_ctx *c, json_object *v, float xform[12])
{
    if (!value_numbers(c, v, 12, range_float, xform))
        return false;
    const float *m = xform;
    double det = (double)m[0] * ((double)m[5] * m[10] - (double)m[6] * m[9]) -
                 (double)m[1] * ((double)m[4] * m[10] - (double)m[6] * m[8]) +
                 (double)m[2] * ((double)m[4] * m[9] - (double)m[5] * m[8]);
    return det != 0.0 || field_fail(c, "the 3x3 part is singular (determinant 0)");
}

/* Object -> world transform of mesh entry `v`: "transform", "matrix" or identity. */
static bool mesh_xform(json_ctx *c, json_object *v, float xform[12])
{
    json_object *t, *m;
    bool has_t = get_member(v, "transform", &t), has_m = get_member(v, "matrix", &m);
    memcpy(xform, identity_xform, sizeof identity_xform);
    if (has_t && has_m)
        return field_fail(c, "give either 'transform' or 'matrix', not both");
    const char *key = has_t ? "transform" : "matrix";
    if (!has_t && !has_m)
        return true;
    size_t saved = field_enter_key(c, key);
    bool ok = has_t ? read_transform(c, t, xform) : read_matrix(c, m, xform);
    field_leave(c, saved);
    return ok;
}

/* `file` relative to the scene file's directory (absolute paths as they are). */
static bool resolve_path(loader *L, const char *file, char *out, size_t out_bytes)
{
    size_t dir_len = file[0] == '/' ? 0 : L->dir_len;
    int n = snprintf(out, out_bytes, "%.*s%s", (int)dir_len, L->ctx.path, file);
    return (n >= 0 && (size_t)n < out_bytes) || member_fail(&L->ctx, "file", "path too long");
}

/* Forget the mesh file's own materials (the scene file chose one for it). */
static void drop_mesh_materials(mesh *m)
{
    free(m->triangle_material);
    free(m->materials);
    m->triangle_material = NULL;
    m->materials = NULL;
    m->material_count = 0;
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

static bool load_mesh(loader *L, json_object *v)
{
    static const char *const fields[] = {"file", "material", "transform", "matrix", "optional", NULL};
    json_ctx *c = &L->ctx;
    const char *file = NULL, *material_name = NULL;
    bool optional = false;
    float xform[12];
    char resolved[MESH_PATH_BYTES];
    if (!expect_object(c, v) || !check_fields(c, v, fields) || !require_member(c, v, "file") ||
        !opt_string(c, v, "file", &file) || !opt_bool(c, v, "optional", &optional) ||
        !opt_string(c, v, "material", &material_name) || !mesh_xform(c, v, xform) ||
        !resolve_path(L, file, resolved, sizeof resolved))
        return false;
    int named = material_name ? find_material(L, material_name) : -1;
    if (material_name && named < 0)
        return unknown_material(c, material_name);
    struct stat st;
    if (optional && stat(resolved, &st) != 0 && (errno == ENOENT || errno == ENOTDIR)) {
        log_warn("%s: field '%s.file': %s does not exist; skipped (optional)", c->path, c->field, resolved);
        return true;
    }
    tess_error why = {{0}};
    mesh *m = mesh_load(resolved, &why);
    if (!m)
        return member_fail(c, "file", why.msg[0] ? why.msg : "cannot load the mesh");
    if (named >= 0)
        drop_mesh_materials(m);
    if (memcmp(xform, identity_xform, sizeof identity_xform) != 0)
        mesh_transform(m, xform);
    bool own_materials = m->material_count > 0 && m->triangle_material != NULL;
    int material_id = named >= 0 ? named : own_materials ? 0 : default_material_id(L);
    if (material_id < 0) {
        mesh_destroy(m);
        return out_of_memory(L);
    }
    int id = scene_add_mesh(L->s, m, (uint32_t)material_id, base_name(resolved));
    if (id < 0)
        return out_of_memory(L);
    scene_mesh *sm = &L->s->meshes[id];
    if (sm->mesh_material_ids) /* keep material_id a valid index even where it is unused */
        sm->material_id = sm->mesh_material_ids[0];
    return true;
}

static bool load_meshes(loader *L, json_object *root)
{
    json_ctx *c = &L->ctx;
    json_object *all;
    if (!get_member(root, "meshes", &all))
        return true;
    size_t outer = field_enter_key(c, "meshes");
    bool ok = expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = field_enter_index(c, i);
        ok = load_mesh(L, json_object_array_get_idx(all, i));
        field_leave(c, saved);
    }
    field_leave(c, outer);
    return ok;
}

static bool load_sphere(loader *L, json_object *v)
{
    static const char *const fields[] = {"center", "radius", "material", NULL};
    json_ctx *c = &L->ctx;
    vec3 center = v3(0.f, 0.f, 0.f);
    float radius = 0.f;
    uint32_t material_id = 0;
    if (!expect_object(c, v) || !check_fields(c, v, fields) || !require_member(c, v, "center") ||
        !require_member(c, v, "radius") || !opt_vec3(c, v, "center", range_float, &center) ||
        !opt_number(c, v, "radius", range_positive, &radius) || !material_ref(L, v, &material_id))
        return false;
    return scene_add_sphere(L->s, center, radius, material_id) >= 0 || out_of_memory(L);
}

static bool load_spheres(loader *L, json_object *root)
{
    json_ctx *c = &L->ctx;
    json_object *all;
    if (!get_member(root, "spheres", &all))
        return true;
    size_t outer = field_enter_key(c, "spheres");
    bool ok = expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = field_enter_index(c, i);
        ok = load_sphere(L, json_object_array_get_idx(all, i));
        field_leave(c, saved);
    }
    field_leave(c, outer);
    return ok;
}

static bool load_scene(loader *L, json_object *root)
{
    static const char *const fields[] = {"camera",    "background", "ambient", "materials",
                                         "lights",    "meshes",     "spheres", NULL};
    json_ctx *c = &L->ctx;
    if (!json_object_is_type(root, json_type_object))
        return tess_error_set(c->err, "%s: expected a JSON object at the top level, got %s", c->path,
                              json_kind(root));
    if (!check_fields(c, root, fields) || !opt_vec3(c, root, "background", range_nonneg, &L->s->background) ||
        !opt_vec3(c, root, "ambient", range_nonneg, &L->s->ambient) || !load_materials(L, root) ||
        !load_lights(L, root) || !load_camera(L, root) || !load_meshes(L, root) || !load_spheres(L, root))
        return false;
    if (scene_triangle_count(L->s) == 0 && L->s->spheres.count == 0)
        return tess_error_set(c->err, "%s: scene has no geometry", c->path);
    return true;
}

scene *scene_load_json(const char *path, tess_error *err)
{
    size_t len = 0;
    char *text = read_text_file(path, &len, err);
    if (!text)
        return NULL;
    json_object *root = NULL;
    bool ok = parse_json(path, text, len, &root, err) && check_no_duplicate_keys(path, text, len, err);
    free(text);
    loader L = {.ctx = {.path = path, .err = err}, .default_material = -1};
    const char *slash = strrchr(path, '/');
    L.dir_len = slash ? (size_t)(slash - path) + 1 : 0;
    L.s = ok ? scene_create() : NULL;
    if (ok && !L.s)
        ok = tess_error_set(err, "%s: out of memory building the scene", path);
    ok = ok && load_scene(&L, root);
    json_object_put(root);
    if (!ok) {
        scene_destroy(L.s);
        return NULL;
    }
    return L.s;
}
