/* navigate.c - camera motions of interactive exploration (input/navigate.h).
 *
 * Every motion reads the float camera into double, does all its arithmetic
 * there, rounds to float once at the end, and returns its input unchanged
 * when the rounded result fails camera_validate (or when the input itself
 * does, or an argument is not finite). The camera frame is built as
 * camera_basis_window builds it (engine/base/camera.c), only in double:
 *   forward = normalize(look_at - eye), right = normalize(forward x up),
 *   up_img = right x forward,
 * so plane coordinates here and pixels of the renderer agree. */
#include "navigate.h"

#include "engine/frame/camera_path.h"
#include "engine/base/dvec3.h"

#include <math.h>
#include <stddef.h>

static const double pi = 3.14159265358979323846;

/* ---- double vectors (engine/base/dvec3.h) ------------------------------------ */

/* Rodrigues: v turned by angle_rad about the unit axis (right-handed). */
static dvec3 dv_rotate(dvec3 v, dvec3 axis, double angle_rad)
{
    double cos_a = cos(angle_rad), sin_a = sin(angle_rad);
    dvec3 along = dv_scale(axis, dv_dot(axis, v) * (1.0 - cos_a));
    return dv_add(dv_add(dv_scale(v, cos_a), dv_scale(dv_cross(axis, v), sin_a)), along);
}

/* ---- the camera frame ---------------------------------------------------- */

/* Orthonormal frame of a valid camera, in double: forward, right, up_img as
 * camera_basis_window (unit length here; the image-plane vectors are these
 * times tan(fov/2) and tan(fov/2) * aspect), plus the unit up hint. */
typedef struct frame {
    dvec3 forward, right, up_img;
    dvec3 up_hint;
} frame;

static bool frame_make(const camera_desc *c, frame *f)
{
    if (!camera_validate(c, NULL))
        return false;
    if (!dv_unit(dv_sub(dv(c->look_at), dv(c->eye)), &f->forward) || !dv_unit(dv(c->up), &f->up_hint))
        return false;
    if (!dv_unit(dv_cross(f->forward, dv(c->up)), &f->right))
        return false;
    f->up_img = dv_cross(f->right, f->forward);
    return true;
}

static double tan_half_fov(const camera_desc *c) { return tan(0.5 * (double)c->fov_deg * pi / 180.0); }

/* `out` when it is a valid camera, else `in` (the motion is refused). */
static camera_desc keep_valid(const camera_desc *in, camera_desc out)
{
    return camera_validate(&out, NULL) ? out : *in;
}

/* c with eye and look_at given in double and rounded, up and fov as c. */
static camera_desc with_points(const camera_desc *c, dvec3 eye, dvec3 look_at)
{
    camera_desc out = *c;
    out.eye = dv_to_float(eye);
    out.look_at = dv_to_float(look_at);
    return keep_valid(c, out);
}

/* ---- motions ------------------------------------------------------------- */

void navigate_plane_ray(const camera_desc *c, float plane_aspect, double sx, double sy, vec3 *origin, vec3 *dir)
{
    frame f;
    dvec3 unit;
    *origin = c->eye;
    *dir = v3(0.f, 0.f, 0.f);
    if (!frame_make(c, &f) || !(plane_aspect > 0.f) || !isfinite(plane_aspect) || !isfinite(sx) || !isfinite(sy))
        return;
    double up_len = tan_half_fov(c), right_len = up_len * (double)plane_aspect;
    dvec3 d = dv_add(f.forward, dv_add(dv_scale(f.right, sx * right_len), dv_scale(f.up_img, sy * up_len)));
    if (dv_unit(d, &unit))
        *dir = dv_to_float(unit);
}

/* The turn about the right axis (positive raises the view) that moves the
 * view's elevation from elevation_rad by turn_rad, limited to the clamp band
 * [-max, max]; an elevation already outside the band may only come back. */
static double clamped_turn_rad(double elevation_rad, double turn_rad)
{
    const double max_rad = NAVIGATE_MAX_ELEVATION_DEG * pi / 180.0;
    double target_rad = elevation_rad + turn_rad;
    if (turn_rad > 0.0)
        target_rad = fmin(target_rad, fmax(elevation_rad, max_rad));
    else if (turn_rad < 0.0)
        target_rad = fmax(target_rad, fmin(elevation_rad, -max_rad));
    return target_rad - elevation_rad;
}

camera_desc navigate_orbit(const camera_desc *c, vec3 pivot, double yaw_rad, double pitch_rad)
{
    frame f;
    if (!frame_make(c, &f) || !v3_is_finite(pivot) || !isfinite(yaw_rad) || !isfinite(pitch_rad))
        return *c;
    dvec3 p = dv(pivot);
    dvec3 eye = dv_sub(dv(c->eye), p), at = dv_sub(dv(c->look_at), p); /* relative to the pivot */

    /* yaw about the up hint: the frame turns with the points, elevation is unchanged */
    eye = dv_rotate(eye, f.up_hint, yaw_rad);
    at = dv_rotate(at, f.up_hint, yaw_rad);
    dvec3 forward = dv_rotate(f.forward, f.up_hint, yaw_rad), right;
    if (!dv_unit(dv_cross(forward, f.up_hint), &right))
        return *c;

    /* pitch about right: right is normal to both forward and the up hint, so a
     * turn by a about it changes the elevation by exactly a. The camera moving
     * up (pitch > 0) means the view tilts down: a = -pitch. */
    double sin_elevation = fmax(-1.0, fmin(1.0, dv_dot(forward, f.up_hint)));
    double turn_rad = clamped_turn_rad(asin(sin_elevation), -pitch_rad);
    eye = dv_rotate(eye, right, turn_rad);
    at = dv_rotate(at, right, turn_rad);
    return with_points(c, dv_add(eye, p), dv_add(at, p));
}

camera_desc navigate_pan(const camera_desc *c, float plane_aspect, double depth, double dsx, double dsy)
{
    frame f;
    if (!frame_make(c, &f) || !(plane_aspect > 0.f) || !isfinite(plane_aspect) || !(depth > 0.0) ||
        !isfinite(depth) || !isfinite(dsx) || !isfinite(dsy))
        return *c;
    /* a point at eye + depth * (forward + sx right + sy up_img) must end up at
     * (sx + dsx, sy + dsy) from the new eye: move by -depth * (dsx right + dsy up_img) */
    double up_len = tan_half_fov(c), right_len = up_len * (double)plane_aspect;
    dvec3 shift = dv_add(dv_scale(f.right, dsx * right_len), dv_scale(f.up_img, dsy * up_len));
    shift = dv_scale(shift, -depth);
    return with_points(c, dv_add(dv(c->eye), shift), dv_add(dv(c->look_at), shift));
}

camera_desc navigate_dolly(const camera_desc *c, vec3 point, double factor)
{
    if (!camera_validate(c, NULL) || !v3_is_finite(point) || !(factor > 0.0) || !isfinite(factor))
        return *c;
    dvec3 p = dv(point);
    dvec3 eye = dv_add(p, dv_scale(dv_sub(dv(c->eye), p), factor));
    dvec3 at = dv_add(p, dv_scale(dv_sub(dv(c->look_at), p), factor));
    return with_points(c, eye, at);
}

camera_desc navigate_fly(const camera_desc *c, double forward, double right, double up)
{
    frame f;
    if (!frame_make(c, &f) || !isfinite(forward) || !isfinite(right) || !isfinite(up))
        return *c;
    dvec3 shift = dv_add(dv_scale(f.forward, forward), dv_add(dv_scale(f.right, right), dv_scale(f.up_hint, up)));
    return with_points(c, dv_add(dv(c->eye), shift), dv_add(dv(c->look_at), shift));
}

camera_desc navigate_look_at_point(const camera_desc *c, vec3 point, double distance)
{
    frame f;
    if (!frame_make(c, &f) || !v3_is_finite(point) || !(distance > 0.0) || !isfinite(distance))
        return *c;
    dvec3 p = dv(point);
    return with_points(c, dv_sub(p, dv_scale(f.forward, distance)), p);
}

camera_desc navigate_blend(const camera_desc *a, const camera_desc *b, double s)
{
    if (!(s > 0.0)) /* NaN included */
        return *a;
    if (s >= 1.0)
        return *b;
    camera_desc out = {
        .eye = dv_to_float(dv_lerp(dv(a->eye), dv(b->eye), s)),
        .look_at = dv_to_float(dv_lerp(dv(a->look_at), dv(b->look_at), s)),
        .up = dv_to_float(dv_lerp(dv(a->up), dv(b->up), s)),
        .fov_deg = (float)((double)a->fov_deg + ((double)b->fov_deg - (double)a->fov_deg) * s),
    };
    if (camera_validate(&out, NULL))
        return out;
    return s < 0.5 ? *a : *b;
}

double navigate_ease(double s)
{
    if (!(s > 0.0)) /* NaN included */
        return 0.0;
    if (s >= 1.0)
        return 1.0;
    return s * s * (3.0 - 2.0 * s);
}

bool navigate_orbit_path(const camera_desc *c, double period_s, int keys, camera_path *out, tess_error *err)
{
    *out = (camera_path){0};
    if (keys < 3 || !(period_s > 0.0) || !isfinite(period_s))
        return tess_error_set(err, "orbit tour: needs 3 or more keys and a positive period");
    tess_error why = {{0}};
    if (!camera_validate(c, &why))
        return tess_error_set(err, "orbit tour: %s", why.msg);
    out->interp = CAMERA_PATH_CATMULL_ROM;
    out->loop = true;
    const double two_pi = 6.283185307179586;
    for (int k = 0; k <= keys; k++) {
        /* the last key repeats the first exactly, so the loop closes */
        camera_desc key = k == 0 || k == keys ? *c : navigate_orbit(c, c->look_at, two_pi * k / keys, 0.0);
        if (!camera_path_append(out, period_s * k / keys, &key, err)) {
            camera_path_free(out);
            return false;
        }
    }
    return true;
}
