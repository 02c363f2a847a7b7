/* err.h - error reports for input the user can get wrong (files, configs, options).
 *
 * Every loader and parser returns bool (or NULL) and fills a tess_error with one
 * line that names the file, the line or field, and the problem, e.g.
 *   "scene.json:12: field 'camera.fov': expected a number, got a string".
 * Library code never prints or exits; the caller decides what to do. */
#ifndef TESSERA_ERR_H
#define TESSERA_ERR_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

#define TESS_ERROR_MSG_BYTES 1024 /* long enough for a path, a field name and a reason (a list of
                                     the choices: the bindings' actions) */

typedef struct tess_error {
    char msg[TESS_ERROR_MSG_BYTES]; /* one line, no trailing newline; "" when unset */
} tess_error;

/* Keep the first failure: a second set on an already-set error is ignored, so
 * the root cause survives the unwinding. The message is kept one printable
 * line: control characters that input put in it (a quoted token) become '?'
 * (a tab a space). err may be NULL. Always returns false,
 * so `return tess_error_set(err, ...);` reads as a failed return. */
bool tess_error_set(tess_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* Prefix an already-set message (e.g. with the scene file that named a mesh). */
void tess_error_prefix(tess_error *err, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

static inline bool tess_error_is_set(const tess_error *err) { return err && err->msg[0] != '\0'; }

#ifdef __cplusplus
}
#endif

#endif
