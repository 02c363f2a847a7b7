/* camera_path.h - camera paths: keyframed cameras over time, read from and
 * written to JSON files, evaluated at any time.
 *
 * CAMERA PATH FILE FORMAT (docs/camera-path-format.md holds the same reference)
 *
 * One JSON object; comments (/ * ... * / and //) are allowed; a field the format
 * does not name is an error, and so is a key given twice in one object.
 *
 *   "format": "tessera-camera-path"    required, exactly this
 *   "version": 1                       required, exactly 1
 *   "interpolation": "catmull-rom"     or "linear"; default "catmull-rom"
 *   "loop": false                      true: the path repeats (see Time)
 *   "keyframes": [                     required, at least 1
 *       {"time": 0.0,                  required: seconds, finite, >= 0, strictly
 *                                      greater than the previous key's time
 *        "eye": [x, y, z],             required
 *        "look_at": [x, y, z],         required, not equal to eye
 *        "up": [x, y, z],              default [0, 1, 0]; not parallel to the view
 *        "fov_deg": 40},               vertical, in (0, 180); default 40
 *       ...
 *   ]
 *
 * Each keyframe is a camera as in a scene file and must pass camera_validate.
 * Coordinates are floats (world units); times are doubles (seconds). With
 * "loop": true there must be at least 2 keyframes and the last must repeat the
 * first camera exactly (eye, look_at, up and fov_deg) so that the path closes;
 * its time is where the repetition starts.
 *
 * Time. Let t_0 .. t_{n-1} be the key times and D = t_{n-1} - t_0 the duration.
 * Without loop a time before t_0 gives key 0 and after t_{n-1} gives the last
 * key. With loop a time outside [t_0, t_{n-1}] is wrapped into [t_0, t_{n-1})
 * by multiples of D. A NaN time (or an infinite one on a looping path) gives
 * key 0. One keyframe is a still camera.
 *
 * Interpolation, all in double precision, rounded to float at the end. For
 * t_k <= t < t_{k+1}, with h = t_{k+1} - t_k and s = (t - t_k) / h in [0, 1):
 *  - at t == t_k exactly the result is key k, bit for bit;
 *  - "linear": eye and look_at are p_k + s (p_{k+1} - p_k);
 *  - "catmull-rom": eye and look_at follow the cubic Hermite curve
 *      p(s) = (2s^3 - 3s^2 + 1) p_k + (s^3 - 2s^2 + s) h m_k
 *           + (-2s^3 + 3s^2) p_{k+1} + (s^3 - s^2) h m_{k+1}
 *    with tangents (velocities, units per second) for non-uniform key times
 *      m_k = ((p_{k+1} - p_k) / (t_{k+1} - t_k) * (t_k - t_{k-1})
 *           + (p_k - p_{k-1}) / (t_k - t_{k-1}) * (t_{k+1} - t_k)) / (t_{k+1} - t_{k-1}),
 *    i.e. the two neighbouring chord velocities weighted by the opposite
 *    interval. It passes through every key, is C1 at the keys, and keys that
 *    lie on a line at constant speed give exactly that motion. At the ends the
 *    tangent is one-sided: m_0 = (p_1 - p_0) / (t_1 - t_0), and the same with
 *    the last two keys. With loop the neighbours wrap: key 0's previous key is
 *    key n-2 at time t_0 - (t_{n-1} - t_{n-2}), the last key's next key is key
 *    1 at time t_{n-1} + (t_1 - t_0), so the seam is C1 as well. Two keys give
 *    the linear motion;
 *  - up is always interpolated linearly and used as it is (the camera only
 *    needs a hint that is not parallel to the view); fov_deg is linear.
 * The result always passes camera_validate. Where the interpolated up is zero
 * or parallel to the interpolated view, the up of the nearer key (s < 0.5: key
 * k, else key k+1) is used, else that of the other key, else +Y, else +Z. Where
 * eye and look_at coincide (or a value is not finite), the whole camera of the
 * nearer key is returned.
 *
 * Errors are one line naming the file and the field, as for scenes:
 *   "path.json: field 'keyframes[3].time': must be greater than
 *    keyframes[2].time (1.5), got 1.5"
 * plus the messages of json_read.h (syntax with LINE:COL, duplicate keys,
 * unknown fields, types, ranges, finiteness). */
#ifndef TESSERA_CAMERA_PATH_H
#define TESSERA_CAMERA_PATH_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/base/camera.h"
#include "engine/base/err.h"

typedef struct camera_keyframe {
    double time_s;      /* seconds; finite, >= 0 */
    camera_desc camera; /* passes camera_validate */
} camera_keyframe;

/* Zero is the file default, so `camera_path p = {0};` is an empty Catmull-Rom path. */
typedef enum camera_path_interp {
    CAMERA_PATH_CATMULL_ROM = 0,
    CAMERA_PATH_LINEAR = 1,
} camera_path_interp;

/* Invariant (kept by load, parse and append): keys[0..count) have strictly
 * increasing times and valid cameras. loop is meaningful only as the file
 * describes (>= 2 keys, last camera == first); save checks it. */
typedef struct camera_path {
    camera_keyframe *keys; /* malloc'ed, `capacity` entries */
    size_t count, capacity;
    camera_path_interp interp;
    bool loop;
} camera_path;

/* Read a camera path file. On success *out owns its keys (camera_path_free);
 * on failure *out is an empty path and err says why. *out is overwritten, not
 * freed first. Files larger than 16 MiB are refused. */
bool camera_path_load(const char *file, camera_path *out, tess_error *err);

/* The same from `len` bytes of JSON text (need not be NUL-terminated); `name`
 * stands for the file in messages. */
bool camera_path_parse(const char *name, const char *text, size_t len, camera_path *out, tess_error *err);

/* Release the keys; *p becomes an empty path (Catmull-Rom, no loop). */
void camera_path_free(camera_path *p);

/* t_{n-1} - t_0 in seconds; 0 for zero or one key. */
double camera_path_duration(const camera_path *p);

/* The camera at `time_s` seconds; see "Time" and "Interpolation" above. An
 * empty path gives a fixed valid camera (eye (0, 0, 1) looking at the origin,
 * up +Y, fov CAMERA_DEFAULT_FOV_DEG). */
camera_desc camera_path_eval(const camera_path *p, double time_s);

/* Recording: add a key after the last one. The time must be finite, >= 0 and
 * greater than the last key's time, and the camera valid; else false with err
 * set and the path unchanged. Does not look at loop. */
bool camera_path_append(camera_path *p, double time_s, const camera_desc *c, tess_error *err);

/* Write the path in the file format (overwriting `file`). Floats are printed
 * with the fewest digits (at most 9) and times with the fewest (at most 17)
 * that read back to the same value, so save then load gives bit-identical keys.
 * Refuses, without writing, a path that would not load (no keys, or loop
 * without a closing last key): "FILE: not saved: camera path: field ...". */
bool camera_path_save(const camera_path *p, const char *file, tess_error *err);

#endif
