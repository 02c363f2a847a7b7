#include "camera.h"

#include <math.h>

/* The view counts as parallel to up when |cos| exceeds this: ~0.8 degrees. */
#define CAMERA_PARALLEL_COS 0.9999f
/* The peer harness switches up to +Z when the view is this close to +-Y (~8.1 deg). */
#define CAMERA_FRAME_UP_SWITCH_COS 0.99f
/* Margin on the framing distance, as in the peer harness. */
#define CAMERA_FRAME_MARGIN 1.05f

static const float deg_to_rad = 3.14159265358979323846f / 180.f;

bool camera_validate(const camera_desc *c, tess_error *err)
{
    if (!v3_is_finite(c->eye) || !v3_is_finite(c->look_at) || !v3_is_finite(c->up) || !isfinite(c->fov_deg))
        return tess_error_set(err, "camera: eye, look_at, up and fov must be finite numbers");
    if (!(c->fov_deg > 0.f && c->fov_deg < 180.f))
        return tess_error_set(err, "camera: fov %g degrees is outside (0, 180)", (double)c->fov_deg);
    vec3 view = v3_sub(c->look_at, c->eye);
    if (v3_length(view) == 0.f)
        return tess_error_set(err, "camera: eye and look_at are the same point");
    if (v3_length(c->up) == 0.f)
        return tess_error_set(err, "camera: up is the zero vector");
    float cosine = fabsf(v3_dot(v3_normalize(view), v3_normalize(c->up)));
    if (cosine > CAMERA_PARALLEL_COS)
        return tess_error_set(err, "camera: up is parallel to the view direction");
    return true;
}

camera_basis camera_basis_make(const camera_desc *c, int width_px, int height_px)
{
    return camera_basis_window(c, (float)width_px / (float)height_px, CAMERA_WINDOW_FULL, width_px, height_px);
}

camera_basis camera_basis_window(const camera_desc *c, float plane_aspect, camera_window window, int width_px,
                                 int height_px)
{
    float tan_half = tanf(0.5f * c->fov_deg * deg_to_rad);
    float aspect = plane_aspect;
    vec3 forward = v3_normalize(v3_sub(c->look_at, c->eye));
    vec3 right = v3_normalize(v3_cross(forward, c->up));
    vec3 up = v3_cross(right, forward);
    vec3 plane_right = v3_scale(right, tan_half * aspect), plane_up = v3_scale(up, tan_half);
    if (window.center_x == 0.f && window.center_y == 0.f && window.half_width == 1.f && window.half_height == 1.f)
        return (camera_basis){c->eye, forward, plane_right, plane_up, width_px, height_px};
    /* the window's centre direction and half extents: pixel mapping as camera_pixel_direction */
    vec3 centre = v3_add(forward, v3_add(v3_scale(plane_right, window.center_x), v3_scale(plane_up, window.center_y)));
    return (camera_basis){c->eye, centre, v3_scale(plane_right, window.half_width),
                          v3_scale(plane_up, window.half_height), width_px, height_px};
}

camera_desc camera_frame_bounds(vec3 lo, vec3 hi, vec3 view_dir, float fov_deg, int width_px, int height_px)
{
    vec3 centre = v3_scale(v3_add(lo, hi), 0.5f);
    vec3 to_eye = v3_normalize(view_dir);
    vec3 up_hint = fabsf(to_eye.y) > CAMERA_FRAME_UP_SWITCH_COS ? v3(0.f, 0.f, 1.f) : v3(0.f, 1.f, 0.f);
    vec3 forward = v3_scale(to_eye, -1.f);
    vec3 right = v3_normalize(v3_cross(forward, up_hint));
    vec3 up = v3_cross(right, forward);
    float tan_half = tanf(0.5f * fov_deg * deg_to_rad);
    float aspect = (float)width_px / (float)height_px;
    /* distance from the centre along to_eye at which corner r projects inside:
     * |r.right| / (depth) <= tan_half * aspect, |r.up| / depth <= tan_half,
     * depth = dist + r.forward */
    float dist = 0.f;
    for (int k = 0; k < 8; k++) {
        vec3 corner = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        vec3 r = v3_sub(corner, centre);
        float need = fmaxf(fabsf(v3_dot(r, right)) / (tan_half * aspect), fabsf(v3_dot(r, up)) / tan_half) -
                     v3_dot(r, forward);
        dist = fmaxf(dist, need);
    }
    return (camera_desc){
        .eye = v3_add(centre, v3_scale(to_eye, CAMERA_FRAME_MARGIN * dist)),
        .look_at = centre,
        .up = up_hint,
        .fov_deg = fov_deg,
    };
}
