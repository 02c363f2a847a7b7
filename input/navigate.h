/* navigate.h - camera motions of interactive exploration, pure functions of a
 * camera_desc (engine/base/camera.h): orbit about a pivot, pan, dolly towards a
 * point, flight, fly-to, and the ray through a point of the image plane.
 *
 * Conventions. A camera's view direction is look_at - eye; its "view
 * distance" is |look_at - eye|. Plane coordinates (sx, sy) are those of
 * camera.h over a whole image plane of aspect `plane_aspect` (width / height):
 * the ray through (sx, sy) has direction forward + sx * right + sy * up with
 * |up| = tan(fov / 2), |right| = tan(fov / 2) * plane_aspect. Every function
 * returns a camera that passes camera_validate when its input does (it
 * returns the input unchanged when a motion would break that, e.g. a zero
 * distance or a view along up, and for an invalid input camera or an
 * argument that is not finite or out of its range). All arithmetic in
 * double, rounded to float at the end; no fused multiply-add
 * (bit-reproducible, as the engine). */
#ifndef TESSERA_INPUT_NAVIGATE_H
#define TESSERA_INPUT_NAVIGATE_H

#include <stdbool.h>

#include "engine/base/camera.h"
#include "engine/base/err.h"
#include "engine/base/vec3.h"

/* Highest elevation an orbit reaches above or below the plane normal to the
 * camera's up hint, so the view never becomes parallel to up. */
#define NAVIGATE_MAX_ELEVATION_DEG 85.0

/* The ray through plane point (sx, sy): origin eye, unit direction, on the
 * basis camera_basis_window builds for the whole plane (so the ray through a
 * pixel's plane point is that pixel's ray). For an invalid camera, a
 * plane_aspect that is not > 0, or a non-finite point: origin eye and the
 * zero direction. */
void navigate_plane_ray(const camera_desc *c, float plane_aspect, double sx, double sy, vec3 *origin, vec3 *dir);

/* Orbit: eye and look_at turn about `pivot` by yaw_rad about the camera's up
 * hint (positive: the camera moves to its right, the scene seems to turn
 * left) and then by pitch_rad about the camera's right axis
 * normalize(view x up) (positive: the camera moves up, so it looks further
 * down). The pitch is cut so that the view's elevation stays within
 * +-NAVIGATE_MAX_ELEVATION_DEG; a view already outside may only come back.
 * up and fov are kept (the horizon stays level). Distances from pivot to eye
 * and to look_at are kept to one float rounding per orbit (composed orbits
 * add those roundings up like a random walk), and the pivot stays at the same
 * place in the image. */
camera_desc navigate_orbit(const camera_desc *c, vec3 pivot, double yaw_rad, double pitch_rad);

/* Pan: eye and look_at move parallel to the image plane, by
 * -depth * (dsx * right + dsy * up) with the plane vectors of the header
 * comment, so that a point at depth `depth` (> 0, distance along the view
 * direction) that was under plane point (sx, sy) is under (sx + dsx,
 * sy + dsy) afterwards (grab and drag). */
camera_desc navigate_pan(const camera_desc *c, float plane_aspect, double depth, double dsx, double dsy);

/* Dolly towards `point`: eye and look_at are scaled about point by `factor`
 * (> 0; < 1 moves closer). The point stays where it is in the image, and
 * dolly(dolly(c, p, a), p, b) == dolly(c, p, a * b) up to rounding. */
camera_desc navigate_dolly(const camera_desc *c, vec3 point, double factor);

/* Flight: eye and look_at move by `forward` along the view direction
 * (unit), `right` along the camera's right and `up` along the camera's up
 * hint (normalized), all in world units. */
camera_desc navigate_fly(const camera_desc *c, double forward, double right, double up);

/* Fly-to target: look_at = point exactly, eye = point - distance * unit view
 * direction (the current one), distance > 0; up and fov kept. */
camera_desc navigate_look_at_point(const camera_desc *c, vec3 point, double distance);

/* Blend between two cameras: eye, look_at, up and fov linear in s in
 * [0, 1] (s <= 0 and NaN give a, s >= 1 gives b, bit for bit); where the blend
 * is not a valid camera, the nearer of a and b (a for s < 0.5, else b). */
camera_desc navigate_blend(const camera_desc *a, const camera_desc *b, double s);

/* An attract tour for any scene: `keys` cameras (>= 3) evenly around the
 * up hint through c's look_at (navigate_orbit of c), one turn per period_s,
 * a looping Catmull-Rom camera path whose first and last key are c bit for
 * bit. Replaces *out (free it with camera_path_free). False with err. */
struct camera_path;
bool navigate_orbit_path(const camera_desc *c, double period_s, int keys, struct camera_path *out, tess_error *err);

/* Smoothstep easing 3s^2 - 2s^3 of s clamped to [0, 1] (NaN gives 0). */
double navigate_ease(double s);

#endif
