/* json_read.h - strict reading of small JSON files (scenes, camera paths) with
 * json-c: the file, the syntax, duplicate keys, and typed reads of fields
 * whose failures name the file and the field.
 *
 * Messages are one line and start with the file name as the caller gave it:
 *   "PATH: cannot open: REASON"                 (jr_read_file)
 *   "PATH:LINE:COL: JSON syntax error: DESC"    (jr_parse; LINE and COL from 1,
 *                                                COL counts bytes)
 *   "PATH:LINE:COL: duplicate key 'K' in a JSON object"
 *   "PATH: field 'lights[1].color[2]': PROBLEM" (everything that uses a jr_ctx)
 *
 * json-c notes: its default (non-strict) mode is needed for comments, and that
 * mode also accepts single-quoted strings, trailing commas and any-case
 * true/false/null; those are tolerated. Even strict mode accepts NaN and
 * Infinity, hence the finiteness checks of the number readers. json-c keeps the
 * last of duplicate keys silently, hence the scan for them in jr_parse.
 *
 * Usage: read the text, jr_parse it, then walk the tree with a jr_ctx whose
 * field path follows the walk (jr_field_key / jr_field_index on the way in,
 * jr_field_leave on the way out). Every reader returns false after setting the
 * error, so checks chain with &&. */
#ifndef TESSERA_JSON_READ_H
#define TESSERA_JSON_READ_H

#include <json.h>
#include <stdbool.h>
#include <stddef.h>

#include "camera.h"
#include "err.h"
#include "vec3.h"

/* ---- the file and its syntax ------------------------------------------ */

/* strerror_r text for `errnum` in buf (for "PATH: cannot open: REASON"). */
const char *jr_errno_text(int errnum, char *buf, size_t size);

/* The whole regular file `path` as a NUL-terminated buffer the caller frees,
 * its length in *len_out. A file larger than `max_bytes` is refused with
 * "PATH: cannot open: N bytes is larger than WHAT may be (M MiB)", where `what`
 * names the kind of file ("a scene file"). NULL on failure, with err set. */
char *jr_read_file(const char *path, size_t max_bytes, const char *what, size_t *len_out, tess_error *err);

/* Parse `len` bytes of `text` (need not be NUL-terminated) into *root, which
 * the caller releases with json_object_put (NULL for a top-level JSON null).
 * False, with a "PATH:LINE:COL:" message, on a syntax error, on anything but
 * whitespace and comments after the value, or on a key given twice in one
 * object. `path` only names the text in messages. */
bool jr_parse(const char *path, const char *text, size_t len, json_object **root, tess_error *err);

/* ---- the field path ---------------------------------------------------- */

/* Enough for a deep field path such as "materials.<63 bytes>.specular[2]". */
#define JR_FIELD_BYTES 256

/* Where a check is, for its message: the file and the JSON field path. */
typedef struct jr_ctx {
    const char *path;            /* the file as given; every message starts with it */
    tess_error *err;             /* may be NULL */
    char field[JR_FIELD_BYTES];  /* e.g. "lights[1].color"; "" at the top level; cut if deep */
    size_t field_len;            /* strlen(field) */
} jr_ctx;

/* Step into member `key` / element `index` of the current field. Both return
 * the length to give back to jr_field_leave. Control characters in keys are
 * shown as '?' so that messages stay one line. */
size_t jr_field_key(jr_ctx *c, const char *key);
size_t jr_field_index(jr_ctx *c, size_t index);
void jr_field_leave(jr_ctx *c, size_t saved);

/* Report "PATH: field 'FIELD': REASON" for the current field; returns false. */
bool jr_field_fail(jr_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* The same for member `key` of the current field; returns false. */
bool jr_member_fail(jr_ctx *c, const char *key, const char *reason);

/* ---- types and members ------------------------------------------------- */

/* "null", "boolean", "number", "object", "array" or "string" (for messages). */
const char *jr_kind(json_object *v);

/* Whether v is a JSON number (integer or not). */
bool jr_is_number(json_object *v);

/* The current field must be an object / an array ("expected an object, got KIND"). */
bool jr_expect_object(jr_ctx *c, json_object *v);
bool jr_expect_array(jr_ctx *c, json_object *v);

/* Every key of object `v` must be in the NULL-terminated `allowed`; an unknown
 * key fails with "unknown field (expected one of: a, b, c)" at that key. */
bool jr_check_fields(jr_ctx *c, json_object *v, const char *const *allowed);

/* Whether object `obj` has member `key`, its value in *v. A JSON null is a
 * present member (*v == NULL) that the readers report as a type error. */
bool jr_get_member(json_object *obj, const char *key, json_object **v);

/* Member `key` must exist ("required field is missing" at that key). */
bool jr_require_member(jr_ctx *c, json_object *obj, const char *key);

/* ---- numbers ------------------------------------------------------------ */

/* An interval for a number; each bound closed or open. */
typedef struct jr_range {
    double lo, hi;
    bool lo_open, hi_open; /* true: the bound itself is excluded */
} jr_range;

extern const jr_range jr_range_float;    /* any float: [-FLT_MAX, FLT_MAX] */
extern const jr_range jr_range_nonneg;   /* [0, FLT_MAX] */
extern const jr_range jr_range_positive; /* (0, FLT_MAX] */
extern const jr_range jr_range_unit;     /* [0, 1] */
extern const jr_range jr_range_fov;      /* (0, 180): a field of view in degrees */

/* The current field as a double in `r`: a JSON number that is finite and not
 * an integer json-c had to clamp to 64 bits. Messages: "expected a number, got
 * KIND", "integer out of range", "expected a finite number, got nan", "must be
 * >= 0, got -1", "must be in (0, 180), got 180", "1e+39 is out of range for a
 * float" (for jr_range_float). */
bool jr_double(jr_ctx *c, json_object *v, jr_range r, double *out);

/* jr_double, then rounded to float (r must lie within the float range). */
bool jr_number(jr_ctx *c, json_object *v, jr_range r, float *out);

/* The current field as an array of exactly `n` numbers, each in `r`
 * ("expected an array of 3 numbers, got 2 elements"); errors name the element. */
bool jr_numbers(jr_ctx *c, json_object *v, size_t n, jr_range r, float *out);
bool jr_vec3(jr_ctx *c, json_object *v, jr_range r, vec3 *out);

/* ---- optional members: absent leaves *out as it is and succeeds ---------- */

bool jr_opt_double(jr_ctx *c, json_object *obj, const char *key, jr_range r, double *out);
bool jr_opt_number(jr_ctx *c, json_object *obj, const char *key, jr_range r, float *out);
bool jr_opt_vec3(jr_ctx *c, json_object *obj, const char *key, jr_range r, vec3 *out);
bool jr_opt_bool(jr_ctx *c, json_object *obj, const char *key, bool *out);

/* A non-empty string; *out points into the JSON tree (valid while it lives). */
bool jr_opt_string(jr_ctx *c, json_object *obj, const char *key, const char **out);

/* A string that must be one of the NULL-terminated `names`; *out its index.
 * Else "unknown value 'X' (expected one of: a, b)". */
bool jr_opt_choice(jr_ctx *c, json_object *obj, const char *key, const char *const *names, int *out);

/* ---- shared by the formats --------------------------------------------- */

/* The header of a tessera file format. "format" must be `format_name`:
 * check it first, so that another kind of JSON file is reported as that
 * rather than as unknown fields (`what` names the kind in the message, e.g.
 * "a wall file"). "version" must be `version`. */
bool jr_check_format(jr_ctx *c, json_object *root, const char *format_name, const char *what);
bool jr_check_version(jr_ctx *c, json_object *root, int version);


/* The camera members of object `obj` (the current field), as scene files and
 * camera paths write them: "eye" and "look_at" required, "up" default [0, 1, 0],
 * "fov_deg" in (0, 180) default CAMERA_DEFAULT_FOV_DEG. The result must pass
 * camera_validate, whose message is reported at the current field
 * ("PATH: field 'camera': camera: eye and look_at are the same point"). The
 * caller checks the object's field names. *out is written only on success. */
bool jr_camera_members(jr_ctx *c, json_object *obj, camera_desc *out);

#endif
