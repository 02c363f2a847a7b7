/* camera_path.c - camera paths: the JSON file format, evaluation over time and
 * recording. The format and the interpolation are documented in
 * camera_path.h (and docs/camera-path-format.md). */
#include "camera_path.h"

#include "engine/base/dvec3.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/json_read.h"

/* A path is a small description; a larger file is most likely a mistake. */
#define CAMERA_PATH_MAX_BYTES (16u << 20)
/* Keys reserved by the first append. */
#define CAMERA_PATH_FIRST_CAPACITY 16
/* Room for one number as printed by format_float / format_double. */
#define NUMBER_TEXT_BYTES 40

static const char format_name[] = "tessera-camera-path";
static const int format_version = 1;

/* Key times: finite seconds from 0 (the upper bound only excludes infinity). */
static const jr_range time_range = {0.0, DBL_MAX, false, false};

/* ---- numbers as text that reads back exactly --------------------------- */

/* Negative zero as "-0.0": json-c reads "-0" as the integer 0, losing the sign. */
static bool format_negative_zero(char *buf, size_t size, double x)
{
    if (x != 0.0 || !signbit(x))
        return false;
    snprintf(buf, size, "-0.0");
    return true;
}

/* The shortest %g text with 1..max_digits digits that strtod reads back as x
 * (as a float when `as_float`: how json-c then jr_number read it, string ->
 * double -> float). Shortest by length, not by digits, so 40 is "40" rather
 * than "4e+01"; ties go to fewer digits. */
static const char *format_shortest(char *buf, size_t size, double x, int max_digits, bool as_float)
{
    if (format_negative_zero(buf, size, x))
        return buf;
    char best[64] = "", text[64];
    for (int digits = 1; digits <= max_digits; digits++) {
        snprintf(text, sizeof text, "%.*g", digits, x);
        double back = strtod(text, NULL);
        bool same = as_float ? (float)back == (float)x : back == x;
        if (same && (!best[0] || strlen(text) < strlen(best)))
            snprintf(best, sizeof best, "%s", text);
    }
    if (!best[0]) /* not reached for finite values: 9 / 17 digits always round-trip */
        snprintf(best, sizeof best, "%.*g", max_digits, x);
    snprintf(buf, size, "%s", best);
    return buf;
}

static const char *format_float(char *buf, size_t size, float x) { return format_shortest(buf, size, x, 9, true); }

static const char *format_double(char *buf, size_t size, double x) { return format_shortest(buf, size, x, 17, false); }

/* ---- reading the file --------------------------------------------------- */

static bool same_camera(const camera_desc *a, const camera_desc *b)
{
    return a->eye.x == b->eye.x && a->eye.y == b->eye.y && a->eye.z == b->eye.z && a->look_at.x == b->look_at.x &&
           a->look_at.y == b->look_at.y && a->look_at.z == b->look_at.z && a->up.x == b->up.x &&
           a->up.y == b->up.y && a->up.z == b->up.z && a->fov_deg == b->fov_deg;
}


/* Keyframe `v` (the current field is "keyframes[i]"); `prev` is the key
 * before it, NULL for the first. */
static bool read_keyframe(jr_ctx *c, json_object *v, const camera_keyframe *prev, size_t index,
                          camera_keyframe *out)
{
    static const char *const fields[] = {"time", "eye", "look_at", "up", "fov_deg", NULL};
    double t = 0.0;
    if (!jr_expect_object(c, v) || !jr_check_fields(c, v, fields) || !jr_require_member(c, v, "time") ||
        !jr_opt_double(c, v, "time", time_range, &t))
        return false;
    if (prev && !(t > prev->time_s)) {
        char before[NUMBER_TEXT_BYTES], got[NUMBER_TEXT_BYTES];
        size_t saved = jr_field_key(c, "time");
        jr_field_fail(c, "must be greater than keyframes[%zu].time (%s), got %s", index - 1,
                      format_double(before, sizeof before, prev->time_s), format_double(got, sizeof got, t));
        jr_field_leave(c, saved);
        return false;
    }
    out->time_s = t;
    return jr_camera_members(c, v, &out->camera);
}

/* "keyframes": at least one, into p->keys (which the caller frees). */
static bool read_keyframes(jr_ctx *c, json_object *root, camera_path *p)
{
    json_object *all;
    if (!jr_require_member(c, root, "keyframes") || !jr_get_member(root, "keyframes", &all))
        return false;
    size_t outer = jr_field_key(c, "keyframes");
    bool ok = jr_expect_array(c, all);
    size_t n = ok ? json_object_array_length(all) : 0;
    if (ok && n == 0)
        ok = jr_field_fail(c, "needs at least 1 keyframe");
    p->keys = ok ? calloc(n, sizeof *p->keys) : NULL;
    if (ok && !p->keys)
        ok = tess_error_set(c->err, "%s: out of memory reading the keyframes", c->path);
    p->capacity = p->keys ? n : 0;
    for (size_t i = 0; ok && i < n; i++) {
        size_t saved = jr_field_index(c, i);
        const camera_keyframe *prev = i ? &p->keys[i - 1] : NULL;
        ok = read_keyframe(c, json_object_array_get_idx(all, i), prev, i, &p->keys[i]);
        if (ok)
            p->count++;
        jr_field_leave(c, saved);
    }
    jr_field_leave(c, outer);
    return ok;
}

/* With loop: at least 2 keys, and the last repeats the first camera. */
static bool check_loop(jr_ctx *c, const camera_path *p)
{
    if (!p->loop)
        return true;
    if (p->count < 2)
        return jr_member_fail(c, "loop", "needs at least 2 keyframes (the last repeating the first)");
    if (same_camera(&p->keys[0].camera, &p->keys[p->count - 1].camera))
        return true;
    size_t outer = jr_field_key(c, "keyframes"), saved = jr_field_index(c, p->count - 1);
    jr_field_fail(c, "with \"loop\": true the last keyframe must repeat the camera of keyframes[0] (eye, look_at, "
                     "up, fov_deg) so that the path closes");
    jr_field_leave(c, saved);
    jr_field_leave(c, outer);
    return false;
}

static bool read_path(jr_ctx *c, json_object *root, camera_path *p)
{
    static const char *const fields[] = {"format", "version", "interpolation", "loop", "keyframes", NULL};
    static const char *const interps[] = {"catmull-rom", "linear", NULL}; /* in camera_path_interp order */
    if (!json_object_is_type(root, json_type_object))
        return tess_error_set(c->err, "%s: expected a JSON object at the top level, got %s", c->path,
                              jr_kind(root));
    int interp = CAMERA_PATH_CATMULL_ROM;
    if (!jr_check_format(c, root, format_name, "a camera path file") || !jr_check_fields(c, root, fields) ||
        !jr_check_version(c, root, format_version) ||
        !jr_opt_choice(c, root, "interpolation", interps, &interp) || !jr_opt_bool(c, root, "loop", &p->loop) ||
        !read_keyframes(c, root, p))
        return false;
    p->interp = (camera_path_interp)interp;
    return check_loop(c, p);
}

bool camera_path_parse(const char *name, const char *text, size_t len, camera_path *out, tess_error *err)
{
    *out = (camera_path){0};
    json_object *root = NULL;
    jr_ctx ctx = {.path = name, .err = err};
    bool ok = jr_parse(name, text, len, &root, err) && read_path(&ctx, root, out);
    json_object_put(root);
    if (!ok)
        camera_path_free(out);
    return ok;
}

bool camera_path_load(const char *file, camera_path *out, tess_error *err)
{
    *out = (camera_path){0};
    size_t len = 0;
    char *text = jr_read_file(file, CAMERA_PATH_MAX_BYTES, "a camera path file", &len, err);
    if (!text)
        return false;
    bool ok = camera_path_parse(file, text, len, out, err);
    free(text);
    return ok;
}

void camera_path_free(camera_path *p)
{
    free(p->keys);
    *p = (camera_path){0};
}

double camera_path_duration(const camera_path *p)
{
    return p->count < 2 ? 0.0 : p->keys[p->count - 1].time_s - p->keys[0].time_s;
}

/* ---- evaluation ---------------------------------------------------------- */

/* Points and velocities in double precision: dvec3.h. */

/* The two interpolated points of a camera. */
typedef enum path_point { POINT_EYE, POINT_LOOK_AT } path_point;

static dvec3 key_point(const camera_path *p, size_t k, path_point which)
{
    const camera_desc *c = &p->keys[k].camera;
    return dv(which == POINT_EYE ? c->eye : c->look_at);
}

/* The time given to the curve: inside [t_0, t_{n-1}] as it is (so key times
 * stay exact), else clamped, or wrapped by the duration when looping. */
static double path_time(const camera_path *p, double t)
{
    double first = p->keys[0].time_s, last = p->keys[p->count - 1].time_s;
    if (t >= first && t <= last)
        return t;
    if (isnan(t))
        return first;
    if (!p->loop || !(last > first))
        return t < first ? first : last;
    double r = fmod(t - first, last - first); /* in (-D, D); NaN for an infinite t */
    if (!isfinite(r))
        return first;
    if (r < 0.0)
        r += last - first;
    double u = first + r;
    return u < first ? first : u > last ? last : u; /* rounding can step just outside */
}

/* The last key k with t_k <= t, for t in [t_0, t_{n-1}]. */
static size_t key_at_or_before(const camera_path *p, double t)
{
    size_t lo = 0, hi = p->count - 1; /* invariant: t_lo <= t, and t < t_hi unless hi is the answer */
    while (lo < hi) {
        size_t mid = lo + (hi - lo + 1) / 2;
        if (p->keys[mid].time_s <= t)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* Velocity (units per second) of point `which` at key k: the weighted chord
 * velocities of camera_path.h, one-sided at the ends of an open path. With
 * loop, key 0's previous key is n-2 and key n-1's next key is 1 (key n-1
 * repeats key 0), the gaps being t_{n-1} - t_{n-2} and t_1 - t_0. */
static dvec3 key_velocity(const camera_path *p, size_t k, path_point which)
{
    size_t n = p->count;
    bool has_prev = k > 0 || p->loop, has_next = k + 1 < n || p->loop;
    size_t prev = k > 0 ? k - 1 : n - 2, next = k + 1 < n ? k + 1 : 1;
    double gap_prev = k > 0 ? p->keys[k].time_s - p->keys[k - 1].time_s
                            : p->keys[n - 1].time_s - p->keys[n - 2].time_s;
    double gap_next = k + 1 < n ? p->keys[k + 1].time_s - p->keys[k].time_s : p->keys[1].time_s - p->keys[0].time_s;
    dvec3 here = key_point(p, k, which);
    dvec3 v_prev = has_prev ? dv_scale(dv_sub(here, key_point(p, prev, which)), 1.0 / gap_prev) : (dvec3){0, 0, 0};
    dvec3 v_next = has_next ? dv_scale(dv_sub(key_point(p, next, which), here), 1.0 / gap_next) : (dvec3){0, 0, 0};
    if (!has_prev)
        return v_next;
    if (!has_next)
        return v_prev;
    return dv_scale(dv_add(dv_scale(v_next, gap_prev), dv_scale(v_prev, gap_next)), 1.0 / (gap_prev + gap_next));
}

/* Point `which` at fraction s of segment k (keys k and k+1, h seconds long). */
static dvec3 segment_point(const camera_path *p, size_t k, double h, double s, path_point which)
{
    dvec3 a = key_point(p, k, which), b = key_point(p, k + 1, which);
    if (p->interp == CAMERA_PATH_LINEAR)
        return dv_lerp(a, b, s);
    dvec3 ma = dv_scale(key_velocity(p, k, which), h), mb = dv_scale(key_velocity(p, k + 1, which), h);
    double s2 = s * s, s3 = s2 * s;
    double h00 = 2.0 * s3 - 3.0 * s2 + 1.0, h10 = s3 - 2.0 * s2 + s, h01 = 3.0 * s2 - 2.0 * s3, h11 = s3 - s2;
    return dv_add(dv_add(dv_scale(a, h00), dv_scale(ma, h10)), dv_add(dv_scale(b, h01), dv_scale(mb, h11)));
}

/* `c` with the first up that makes it valid (its own, the nearer key's, the
 * other key's, +Y, +Z); the nearer key's camera when no up helps (eye and
 * look_at coincide, or a value is not finite). */
static camera_desc make_valid(camera_desc c, const camera_desc *nearer, const camera_desc *other)
{
    const vec3 ups[] = {c.up, nearer->up, other->up, v3(0.f, 1.f, 0.f), v3(0.f, 0.f, 1.f)};
    for (size_t i = 0; i < sizeof ups / sizeof ups[0]; i++) {
        c.up = ups[i];
        if (camera_validate(&c, NULL))
            return c;
    }
    return *nearer;
}

/* Used for an empty path, which has no camera of its own. */
static camera_desc empty_path_camera(void)
{
    return (camera_desc){.eye = v3(0.f, 0.f, 1.f), .look_at = v3(0.f, 0.f, 0.f), .up = v3(0.f, 1.f, 0.f),
                         .fov_deg = CAMERA_DEFAULT_FOV_DEG};
}

camera_desc camera_path_eval(const camera_path *p, double time_s)
{
    if (p->count == 0)
        return empty_path_camera();
    double t = path_time(p, time_s);
    size_t k = key_at_or_before(p, t);
    const camera_keyframe *a = &p->keys[k];
    if (t == a->time_s || k + 1 == p->count)
        return a->camera;
    const camera_keyframe *b = a + 1;
    double h = b->time_s - a->time_s, s = (t - a->time_s) / h; /* h > 0, s in [0, 1] */
    double fov = a->camera.fov_deg + s * ((double)b->camera.fov_deg - a->camera.fov_deg);
    camera_desc c = {
        .eye = dv_to_float(segment_point(p, k, h, s, POINT_EYE)),
        .look_at = dv_to_float(segment_point(p, k, h, s, POINT_LOOK_AT)),
        .up = dv_to_float(dv_lerp(dv(a->camera.up), dv(b->camera.up), s)),
        .fov_deg = (float)fov,
    };
    bool a_nearer = s < 0.5;
    return make_valid(c, a_nearer ? &a->camera : &b->camera, a_nearer ? &b->camera : &a->camera);
}

/* ---- recording and saving ------------------------------------------------ */

static bool reserve_one_more(camera_path *p)
{
    if (p->count < p->capacity)
        return true;
    size_t n = p->capacity ? p->capacity * 2 : CAMERA_PATH_FIRST_CAPACITY;
    if (n < p->capacity || n > SIZE_MAX / sizeof *p->keys)
        return false;
    camera_keyframe *keys = realloc(p->keys, n * sizeof *keys);
    if (!keys)
        return false;
    p->keys = keys;
    p->capacity = n;
    return true;
}

bool camera_path_append(camera_path *p, double time_s, const camera_desc *c, tess_error *err)
{
    char t[NUMBER_TEXT_BYTES], last[NUMBER_TEXT_BYTES];
    if (!isfinite(time_s) || time_s < 0.0)
        return tess_error_set(err, "camera path: time %s s must be finite and >= 0",
                              format_double(t, sizeof t, time_s));
    if (p->count > 0 && !(time_s > p->keys[p->count - 1].time_s))
        return tess_error_set(err, "camera path: time %s s is not after the last keyframe's (%s s)",
                              format_double(t, sizeof t, time_s),
                              format_double(last, sizeof last, p->keys[p->count - 1].time_s));
    tess_error why = {{0}};
    if (!camera_validate(c, &why))
        return tess_error_set(err, "camera path: keyframe at %s s: %s", format_double(t, sizeof t, time_s),
                              why.msg);
    if (!reserve_one_more(p))
        return tess_error_set(err, "camera path: out of memory adding a keyframe");
    p->keys[p->count++] = (camera_keyframe){.time_s = time_s, .camera = *c};
    return true;
}

static void print_vec3(FILE *f, const char *key, vec3 v)
{
    char x[NUMBER_TEXT_BYTES], y[NUMBER_TEXT_BYTES], z[NUMBER_TEXT_BYTES];
    fprintf(f, "\"%s\": [%s, %s, %s]", key, format_float(x, sizeof x, v.x), format_float(y, sizeof y, v.y),
            format_float(z, sizeof z, v.z));
}

static void print_keyframe(FILE *f, const camera_keyframe *key, bool last)
{
    char t[NUMBER_TEXT_BYTES], fov[NUMBER_TEXT_BYTES];
    fprintf(f, "    {\"time\": %s, ", format_double(t, sizeof t, key->time_s));
    print_vec3(f, "eye", key->camera.eye);
    fputs(", ", f);
    print_vec3(f, "look_at", key->camera.look_at);
    fputs(", ", f);
    print_vec3(f, "up", key->camera.up);
    fprintf(f, ", \"fov_deg\": %s}%s\n", format_float(fov, sizeof fov, key->camera.fov_deg), last ? "" : ",");
}

/* The whole file as text (malloc'ed, *len_out bytes); NULL when out of memory. */
static char *format_path(const camera_path *p, size_t *len_out)
{
    char *text = NULL;
    FILE *f = open_memstream(&text, len_out);
    if (!f)
        return NULL;
    fprintf(f, "{\n  \"format\": \"%s\",\n  \"version\": %d,\n", format_name, format_version);
    fprintf(f, "  \"interpolation\": \"%s\",\n", p->interp == CAMERA_PATH_LINEAR ? "linear" : "catmull-rom");
    fprintf(f, "  \"loop\": %s,\n  \"keyframes\": [\n", p->loop ? "true" : "false");
    for (size_t i = 0; i < p->count; i++)
        print_keyframe(f, &p->keys[i], i + 1 == p->count);
    fputs("  ]\n}\n", f);
    bool failed = ferror(f) != 0;
    if (fclose(f) != 0 || failed) {
        free(text);
        return NULL;
    }
    return text;
}

static bool write_file(const char *file, const char *text, size_t len, tess_error *err)
{
    char why[128];
    FILE *f = fopen(file, "w");
    if (!f)
        return tess_error_set(err, "%s: cannot write: %s", file, jr_errno_text(errno, why, sizeof why));
    bool ok = fwrite(text, 1, len, f) == len;
    int write_errno = errno;
    if (fclose(f) != 0 && ok) {
        ok = false;
        write_errno = errno;
    }
    return ok || tess_error_set(err, "%s: cannot write: %s", file, jr_errno_text(write_errno, why, sizeof why));
}

bool camera_path_save(const camera_path *p, const char *file, tess_error *err)
{
    size_t len = 0;
    char *text = format_path(p, &len);
    if (!text)
        return tess_error_set(err, "%s: out of memory formatting the camera path", file);
    /* what is written must load: the reader is the check */
    camera_path check;
    tess_error why = {{0}};
    bool ok = camera_path_parse("camera path", text, len, &check, &why);
    camera_path_free(&check);
    if (!ok)
        tess_error_set(err, "%s: not saved: %s", file, why.msg);
    ok = ok && write_file(file, text, len, err);
    free(text);
    return ok;
}
