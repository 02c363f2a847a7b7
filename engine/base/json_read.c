/* json_read.c - strict JSON reading with json-c for the file formats
 * (engine/load/scene_json.c, engine/frame/camera_path.c); see json_read.h. */
#include "json_read.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Bytes of a duplicate key quoted in its message (longer keys are cut). */
#define JR_SHOWN_KEY_BYTES 64

/* ---- reading the file ------------------------------------------------- */

const char *jr_errno_text(int errnum, char *buf, size_t size)
{
    if (strerror_r(errnum, buf, size) != 0)
        snprintf(buf, size, "error %d", errnum);
    return buf;
}

/* Only regular files are read (O_NONBLOCK keeps open() from waiting on a FIFO). */
char *jr_read_file(const char *path, size_t max_bytes, const char *what, size_t *len_out, tess_error *err)
{
    char why[128];
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        tess_error_set(err, "%s: cannot open: %s", path, jr_errno_text(errno, why, sizeof why));
        return NULL;
    }
    struct stat st;
    char *buf = NULL;
    if (fstat(fd, &st) != 0) {
        tess_error_set(err, "%s: cannot open: %s", path, jr_errno_text(errno, why, sizeof why));
        goto fail;
    }
    if (!S_ISREG(st.st_mode)) {
        tess_error_set(err, "%s: cannot open: not a regular file", path);
        goto fail;
    }
    if ((uintmax_t)st.st_size > (uintmax_t)max_bytes) {
        tess_error_set(err, "%s: cannot open: %lld bytes is larger than %s may be (%zu MiB)", path,
                       (long long)st.st_size, what, max_bytes >> 20);
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
            tess_error_set(err, "%s: cannot read: %s", path, jr_errno_text(errno, why, sizeof why));
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
    char dup_key[JR_SHOWN_KEY_BYTES];
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

bool jr_parse(const char *path, const char *text, size_t len, json_object **root, tess_error *err)
{
    *root = NULL;
    if (len > (size_t)INT_MAX) /* json-c takes the length as an int */
        return tess_error_set(err, "%s: %zu bytes is too much JSON text", path, len);
    if (!parse_json(path, text, len, root, err))
        return false;
    if (check_no_duplicate_keys(path, text, len, err))
        return true;
    json_object_put(*root);
    *root = NULL;
    return false;
}

/* ---- field paths -------------------------------------------------------- */

/* Append to the field path; return the length to restore with jr_field_leave. */
static size_t field_append(jr_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static size_t field_append(jr_ctx *c, const char *fmt, ...)
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

size_t jr_field_key(jr_ctx *c, const char *key)
{
    return field_append(c, "%s%s", c->field_len ? "." : "", key);
}

size_t jr_field_index(jr_ctx *c, size_t index) { return field_append(c, "[%zu]", index); }

void jr_field_leave(jr_ctx *c, size_t saved)
{
    c->field_len = saved;
    c->field[saved] = '\0';
}

bool jr_field_fail(jr_ctx *c, const char *fmt, ...)
{
    char reason[TESS_ERROR_MSG_BYTES];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(reason, sizeof reason, fmt, ap);
    va_end(ap);
    make_one_line(reason);
    return tess_error_set(c->err, "%s: field '%s': %s", c->path, c->field, reason);
}

bool jr_member_fail(jr_ctx *c, const char *key, const char *reason)
{
    size_t saved = jr_field_key(c, key);
    jr_field_fail(c, "%s", reason);
    jr_field_leave(c, saved);
    return false;
}

/* ---- types ----------------------------------------------------------------- */

const char *jr_kind(json_object *v)
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

bool jr_is_number(json_object *v)
{
    return json_object_is_type(v, json_type_double) || json_object_is_type(v, json_type_int);
}

bool jr_expect_object(jr_ctx *c, json_object *v)
{
    return json_object_is_type(v, json_type_object) || jr_field_fail(c, "expected an object, got %s", jr_kind(v));
}

bool jr_expect_array(jr_ctx *c, json_object *v)
{
    return json_object_is_type(v, json_type_array) || jr_field_fail(c, "expected an array, got %s", jr_kind(v));
}

bool jr_check_fields(jr_ctx *c, json_object *v, const char *const *allowed)
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
        return jr_member_fail(c, key, reason);
    }
    return true;
}

/* ---- numbers ------------------------------------------------------------ */

const jr_range jr_range_float = {-FLT_MAX, FLT_MAX, false, false};
const jr_range jr_range_nonneg = {0.0, FLT_MAX, false, false};
const jr_range jr_range_positive = {0.0, FLT_MAX, true, false};
const jr_range jr_range_unit = {0.0, 1.0, false, false};
const jr_range jr_range_fov = {0.0, 180.0, true, true};

static bool in_range(double x, jr_range r)
{
    bool above = r.lo_open ? x > r.lo : x >= r.lo;
    bool below = r.hi_open ? x < r.hi : x <= r.hi;
    return above && below;
}

/* An upper bound of FLT_MAX or more reads as "no upper bound" in messages. */
static bool range_fail(jr_ctx *c, double x, jr_range r)
{
    if (r.lo == -FLT_MAX && r.hi == FLT_MAX)
        return jr_field_fail(c, "%g is out of range for a float", x);
    if (r.hi >= FLT_MAX)
        return jr_field_fail(c, "must be %s %g, got %g", r.lo_open ? ">" : ">=", r.lo, x);
    return jr_field_fail(c, "must be in %c%g, %g%c, got %g", r.lo_open ? '(' : '[', r.lo, r.hi,
                         r.hi_open ? ')' : ']', x);
}

bool jr_double(jr_ctx *c, json_object *v, jr_range r, double *out)
{
    if (!jr_is_number(v))
        return jr_field_fail(c, "expected a number, got %s", jr_kind(v));
    double x = json_object_get_double(v);
    /* json-c clamps integers that overflow 64 bits to these values */
    if (json_object_is_type(v, json_type_int) &&
        (json_object_get_int64(v) == INT64_MIN || json_object_get_uint64(v) == UINT64_MAX))
        return jr_field_fail(c, "integer out of range");
    if (!isfinite(x))
        return jr_field_fail(c, "expected a finite number, got %g", x);
    if (!in_range(x, r))
        return range_fail(c, x, r);
    *out = x;
    return true;
}

bool jr_number(jr_ctx *c, json_object *v, jr_range r, float *out)
{
    double x;
    if (!jr_double(c, v, r, &x))
        return false;
    *out = (float)x; /* r lies within the float range, so this rounds but never overflows */
    return true;
}

bool jr_numbers(jr_ctx *c, json_object *v, size_t n, jr_range r, float *out)
{
    if (!json_object_is_type(v, json_type_array))
        return jr_field_fail(c, "expected an array of %zu numbers, got %s", n, jr_kind(v));
    size_t got = json_object_array_length(v);
    if (got != n)
        return jr_field_fail(c, "expected an array of %zu numbers, got %zu element%s", n, got, got == 1 ? "" : "s");
    for (size_t i = 0; i < n; i++) {
        size_t saved = jr_field_index(c, i);
        bool ok = jr_number(c, json_object_array_get_idx(v, i), r, &out[i]);
        jr_field_leave(c, saved);
        if (!ok)
            return false;
    }
    return true;
}

bool jr_vec3(jr_ctx *c, json_object *v, jr_range r, vec3 *out)
{
    float xyz[3];
    if (!jr_numbers(c, v, 3, r, xyz))
        return false;
    *out = v3(xyz[0], xyz[1], xyz[2]);
    return true;
}

/* ---- members -------------------------------------------------------------- */

bool jr_get_member(json_object *obj, const char *key, json_object **v)
{
    return json_object_object_get_ex(obj, key, v);
}

bool jr_require_member(jr_ctx *c, json_object *obj, const char *key)
{
    json_object *v;
    return jr_get_member(obj, key, &v) || jr_member_fail(c, key, "required field is missing");
}

bool jr_opt_double(jr_ctx *c, json_object *obj, const char *key, jr_range r, double *out)
{
    json_object *v;
    if (!jr_get_member(obj, key, &v))
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = jr_double(c, v, r, out);
    jr_field_leave(c, saved);
    return ok;
}

bool jr_opt_number(jr_ctx *c, json_object *obj, const char *key, jr_range r, float *out)
{
    json_object *v;
    if (!jr_get_member(obj, key, &v))
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = jr_number(c, v, r, out);
    jr_field_leave(c, saved);
    return ok;
}

bool jr_opt_vec3(jr_ctx *c, json_object *obj, const char *key, jr_range r, vec3 *out)
{
    json_object *v;
    if (!jr_get_member(obj, key, &v))
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = jr_vec3(c, v, r, out);
    jr_field_leave(c, saved);
    return ok;
}

bool jr_opt_bool(jr_ctx *c, json_object *obj, const char *key, bool *out)
{
    json_object *v;
    if (!jr_get_member(obj, key, &v))
        return true;
    if (!json_object_is_type(v, json_type_boolean)) {
        size_t saved = jr_field_key(c, key);
        jr_field_fail(c, "expected a boolean, got %s", jr_kind(v));
        jr_field_leave(c, saved);
        return false;
    }
    *out = json_object_get_boolean(v);
    return true;
}

bool jr_opt_string(jr_ctx *c, json_object *obj, const char *key, const char **out)
{
    json_object *v;
    if (!jr_get_member(obj, key, &v))
        return true;
    size_t saved = jr_field_key(c, key);
    bool ok = json_object_is_type(v, json_type_string) ||
              jr_field_fail(c, "expected a string, got %s", jr_kind(v));
    if (ok && json_object_get_string_len(v) == 0)
        ok = jr_field_fail(c, "must not be empty");
    if (ok)
        *out = json_object_get_string(v);
    jr_field_leave(c, saved);
    return ok;
}

bool jr_opt_choice(jr_ctx *c, json_object *obj, const char *key, const char *const *names, int *out)
{
    const char *value = NULL;
    if (!jr_opt_string(c, obj, key, &value))
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
    size_t saved = jr_field_key(c, key);
    jr_field_fail(c, "unknown value '%s' (expected one of: %s)", value, list);
    jr_field_leave(c, saved);
    return false;
}


/* ---- shared by the formats --------------------------------------------- */

bool jr_camera_members(jr_ctx *c, json_object *obj, camera_desc *out)
{
    camera_desc cam = {.up = v3(0.f, 1.f, 0.f), .fov_deg = CAMERA_DEFAULT_FOV_DEG};
    bool ok = jr_require_member(c, obj, "eye") && jr_require_member(c, obj, "look_at") &&
              jr_opt_vec3(c, obj, "eye", jr_range_float, &cam.eye) &&
              jr_opt_vec3(c, obj, "look_at", jr_range_float, &cam.look_at) &&
              jr_opt_vec3(c, obj, "up", jr_range_float, &cam.up) &&
              jr_opt_number(c, obj, "fov_deg", jr_range_fov, &cam.fov_deg);
    if (!ok)
        return false;
    tess_error why = {{0}};
    if (!camera_validate(&cam, &why))
        return jr_field_fail(c, "%s", why.msg);
    *out = cam;
    return true;
}

bool jr_check_format(jr_ctx *c, json_object *root, const char *format_name, const char *what)
{
    const char *name = NULL;
    json_object *v;
    if (!jr_get_member(root, "format", &v)) {
        char reason[256];
        snprintf(reason, sizeof reason, "required field is missing (%s has \"format\": \"%s\")", what, format_name);
        return jr_member_fail(c, "format", reason);
    }
    if (!jr_opt_string(c, root, "format", &name))
        return false;
    if (strcmp(name, format_name) == 0)
        return true;
    size_t saved = jr_field_key(c, "format");
    jr_field_fail(c, "expected \"%s\", got \"%.64s\"", format_name, name);
    jr_field_leave(c, saved);
    return false;
}

bool jr_check_version(jr_ctx *c, json_object *root, int version)
{
    json_object *v;
    if (!jr_require_member(c, root, "version") || !jr_get_member(root, "version", &v))
        return false;
    size_t saved = jr_field_key(c, "version");
    double found = 0.0;
    bool ok = jr_double(c, v, jr_range_float, &found) &&
              (found == version ||
               jr_field_fail(c, "unsupported version %g (this build reads version %d)", found, version));
    jr_field_leave(c, saved);
    return ok;
}
