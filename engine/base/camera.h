/* camera.h - pinhole camera: description (what a user writes) and the basis
 * that primary-ray generation uses.
 *
 * Pixel (x, y) of a W x H image maps to screen coordinates
 *   sx = 2 (x + 0.5) / W - 1,  sy = 1 - 2 (y + 0.5) / H
 * and the ray direction is normalize(forward + sx * right + sy * up), where
 * |up| = tan(fov/2) and |right| = tan(fov/2) * W / H (the same rule as the
 * Embree peer harness, so images compare pixel by pixel). */
#ifndef TESSERA_CAMERA_H
#define TESSERA_CAMERA_H

#include <stdbool.h>

#include "err.h"
#include "vec3.h"

typedef struct camera_desc {
    vec3 eye;       /* world position of the pinhole */
    vec3 look_at;   /* world point at the image centre */
    vec3 up;        /* world up hint; need not be unit or orthogonal */
    float fov_deg;  /* vertical field of view in degrees, (0, 180) */
} camera_desc;

typedef struct camera_basis {
    vec3 eye;
    vec3 forward;   /* direction through the image centre; unit (eye -> look_at) except for a
                       camera_basis_window that is off-centre */
    vec3 right;     /* length tan(fov/2) * aspect */
    vec3 up;        /* length tan(fov/2) */
    int width_px, height_px;
} camera_basis;

/* Check a description: finite values, eye != look_at, up not parallel to the
 * view, fov in (0, 180). */
bool camera_validate(const camera_desc *c, tess_error *err);

/* Build the basis for an image size; the description must be valid. */
camera_basis camera_basis_make(const camera_desc *c, int width_px, int height_px);

/* A window onto a larger virtual image plane (a display wall): the screen
 * rectangle [cx - hw, cx + hw] x [cy - hh, cy + hh] in the plane's screen
 * coordinates, where the whole plane is sx, sy in [-1, 1] (sx right, sy up).
 * {0, 0, 1, 1} is the whole plane. */
typedef struct camera_window {
    float center_x, center_y;
    float half_width, half_height;
} camera_window;

#define CAMERA_WINDOW_FULL ((camera_window){0.f, 0.f, 1.f, 1.f})

/* The basis for a W x H image of `window` of the plane that camera c sees at
 * aspect plane_aspect (plane width / height): every output of a wall is one
 * off-axis view of one pinhole camera, so a straight line stays straight
 * across outputs. With the full window and plane_aspect = (float)W / H it is
 * camera_basis_make, bit for bit. */
camera_basis camera_basis_window(const camera_desc *c, float plane_aspect, camera_window window, int width_px,
                                 int height_px);

/* Unnormalised direction through the centre of pixel (x, y); see the header comment. */
static inline vec3 camera_pixel_direction(const camera_basis *b, int x, int y)
{
    float sx = 2.f * ((float)x + 0.5f) / (float)b->width_px - 1.f;
    float sy = 1.f - 2.f * ((float)y + 0.5f) / (float)b->height_px;
    return v3_add(b->forward, v3_add(v3_scale(b->right, sx), v3_scale(b->up, sy)));
}

/* Frame an axis-aligned box by the peer harness's rule: look at the box centre
 * from direction `view_dir` (default (1, 0.5, 1.5)), vertical fov `fov_deg`, at
 * the smallest distance where all 8 corners project into a W x H image, times
 * 1.05; up +Y, or +Z when the view is within ~8 degrees of +-Y. */
camera_desc camera_frame_bounds(vec3 lo, vec3 hi, vec3 view_dir, float fov_deg, int width_px, int height_px);

#define CAMERA_DEFAULT_VIEW_DIR v3(1.f, 0.5f, 1.5f)
#define CAMERA_DEFAULT_FOV_DEG 40.f

#endif
