#include "packet.h"

#include <float.h>
#include <math.h>

#include "engine/base/camera.h"
#include "kernels.h"

void packet_reset(ray_packet *p, uint32_t count, uint32_t fact_flags)
{
    p->count = count;
    p->active = packet_span_mask(0, count);
    p->flags = fact_flags & (PACKET_COMMON_ORIGIN | PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED);
    for (uint32_t i = 0; i < count; i++) {
        p->hit_t[i] = INFINITY;
        p->hit_u[i] = p->hit_v[i] = 0.f;
        p->prim_id[i] = p->geom_id[i] = RAY_INVALID_ID;
    }
}

void packet_set_ray(ray_packet *p, uint32_t i, const ray *r)
{
    p->org_x[i] = r->org.x;
    p->org_y[i] = r->org.y;
    p->org_z[i] = r->org.z;
    p->dir_x[i] = r->dir.x;
    p->dir_y[i] = r->dir.y;
    p->dir_z[i] = r->dir.z;
    p->t_near[i] = r->t_near;
    p->t_far[i] = r->t_far;
}

ray packet_get_ray(const ray_packet *p, uint32_t i)
{
    return (ray){v3(p->org_x[i], p->org_y[i], p->org_z[i]), v3(p->dir_x[i], p->dir_y[i], p->dir_z[i]), p->t_near[i],
                 p->t_far[i]};
}

hit packet_get_hit(const ray_packet *p, uint32_t i)
{
    return (hit){.t = p->hit_t[i], .u = p->hit_u[i], .v = p->hit_v[i], .prim_id = p->prim_id[i],
                 .geom_id = p->geom_id[i]};
}

void packet_set_hit(ray_packet *p, uint32_t i, const hit *h)
{
    p->hit_t[i] = h->t;
    p->hit_u[i] = h->u;
    p->hit_v[i] = h->v;
    p->prim_id[i] = h->prim_id;
    p->geom_id[i] = h->geom_id;
    p->t_far[i] = h->t;
}

void packet_set_after(ray_packet *p, uint32_t i, const hit *after)
{
    if (!(p->flags & PACKET_AFTER_HIT)) {
        for (uint32_t k = 0; k < PACKET_MAX_RAYS; k++) {
            p->after_t[k] = -INFINITY;
            p->after_geom[k] = p->after_prim[k] = RAY_INVALID_ID;
        }
        p->flags |= PACKET_AFTER_HIT;
    }
    p->after_t[i] = after->t;
    p->after_geom[i] = after->geom_id;
    p->after_prim[i] = after->prim_id;
    float below = nextafterf(after->t, -INFINITY);
    if (p->t_near[i] < below)
        p->t_near[i] = below;
}

void packet_detect_facts(ray_packet *p)
{
    uint32_t facts = PACKET_COMMON_ORIGIN | PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED;
    for (uint32_t i = 0; i < p->count; i++) {
        if (p->org_x[i] != p->org_x[0] || p->org_y[i] != p->org_y[0] || p->org_z[i] != p->org_z[0])
            facts &= ~(uint32_t)PACKET_COMMON_ORIGIN;
        if (signbit(p->dir_x[i]) != signbit(p->dir_x[0]) || signbit(p->dir_y[i]) != signbit(p->dir_y[0]) ||
            signbit(p->dir_z[i]) != signbit(p->dir_z[0]))
            facts &= ~(uint32_t)PACKET_CONSTANT_SIGNS;
        float len2 = p->dir_x[i] * p->dir_x[i] + p->dir_y[i] * p->dir_y[i] + p->dir_z[i] * p->dir_z[i];
        if (fabsf(len2 - 1.f) > 4.f * FLT_EPSILON)
            facts &= ~(uint32_t)PACKET_NORMALIZED;
    }
    p->flags = (p->flags & ~(uint32_t)(PACKET_COMMON_ORIGIN | PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED)) | facts;
}

#ifndef TESSERA_UNROBUST
static float safe_reciprocal(float x) { return x != 0.f ? 1.f / x : copysignf(FLT_MAX, x); }
#else
static float safe_reciprocal(float x) { return 1.f / x; } /* fast build (intersect.h): +-inf for a zero x */
#endif

void packet_derive_inv_dir(ray_packet *p)
{
    if (p->flags & PACKET_HAVE_INV_DIR)
        return;
    for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++) { /* all lanes: a branch-free loop vectorises */
        p->inv_dir_x[i] = safe_reciprocal(p->dir_x[i]);
        p->inv_dir_y[i] = safe_reciprocal(p->dir_y[i]);
        p->inv_dir_z[i] = safe_reciprocal(p->dir_z[i]);
    }
    p->flags |= PACKET_HAVE_INV_DIR;
}

void packet_primary(ray_packet *p, const camera_basis *cam, int x0, int y0, int w, int h)
{
    packet_reset(p, (uint32_t)(w * h), PACKET_COMMON_ORIGIN | PACKET_NORMALIZED);
    kernels_default()->primary_directions(p, cam, x0, y0, w, h);
    const uint32_t count = (uint32_t)(w * h);
    for (uint32_t i = 0; i < count; i++) {
        p->org_x[i] = cam->eye.x;
        p->org_y[i] = cam->eye.y;
        p->org_z[i] = cam->eye.z;
        p->t_near[i] = 0.f;
        p->t_far[i] = FLT_MAX;
    }
    /* a tile's directions keep their signs unless it straddles an axis plane */
    bool same_sign = true;
    for (uint32_t k = 1; k < count && same_sign; k++)
        same_sign = signbit(p->dir_x[k]) == signbit(p->dir_x[0]) && signbit(p->dir_y[k]) == signbit(p->dir_y[0]) &&
                    signbit(p->dir_z[k]) == signbit(p->dir_z[0]);
    if (same_sign)
        p->flags |= PACKET_CONSTANT_SIGNS;
}

/* camera.h's screen mapping for continuous pixel coordinates, with the
 * divisions by the image size hoisted into two scales. */
typedef struct screen_map {
    float x_scale, y_scale; /* 2 / W, 2 / H */
    vec3 forward, right, up;
} screen_map;

static screen_map screen_map_make(const camera_basis *cam)
{
    return (screen_map){2.f / (float)cam->width_px, 2.f / (float)cam->height_px, cam->forward, cam->right, cam->up};
}

/* Unit direction through pixel position (px, py): camera_pixel_direction's
 * sum order, then v3_normalize's arithmetic: x * (1 / len), and a zero or
 * NaN length leaves the vector as it is (selected, not branched on). */
static inline void screen_direction(const screen_map *m, float px, float py, float *dx, float *dy, float *dz)
{
    float sx = px * m->x_scale - 1.f;
    float sy = 1.f - py * m->y_scale;
    float x = m->forward.x + (m->right.x * sx + m->up.x * sy);
    float y = m->forward.y + (m->right.y * sx + m->up.y * sy);
    float z = m->forward.z + (m->right.z * sx + m->up.z * sy);
    float len = sqrtf(x * x + y * y + z * z);
    float inv = 1.f / len;
    float ux = x * inv, uy = y * inv, uz = z * inv;
    bool scale = len > 0.f;
    *dx = scale ? ux : x;
    *dy = scale ? uy : y;
    *dz = scale ? uz : z;
}

/* True when each direction component has one sign bit over rays [0, count). */
static bool directions_keep_signs(const ray_packet *p, uint32_t count)
{
    uint32_t any_negative = 0, all_negative = 7u;
    for (uint32_t i = 0; i < count; i++) {
        uint32_t negative = (uint32_t)(signbit(p->dir_x[i]) != 0) | (uint32_t)(signbit(p->dir_y[i]) != 0) << 1 |
                            (uint32_t)(signbit(p->dir_z[i]) != 0) << 2;
        any_negative |= negative;
        all_negative &= negative;
    }
    return any_negative == all_negative;
}

void packet_primary_at(ray_packet *p, const camera_basis *cam, const float *px, const float *py, uint32_t count)
{
    packet_reset(p, count, PACKET_COMMON_ORIGIN | PACKET_NORMALIZED);
    const screen_map m = screen_map_make(cam);
    const vec3 eye = cam->eye;
    for (uint32_t i = 0; i < count; i++) {
        screen_direction(&m, px[i], py[i], &p->dir_x[i], &p->dir_y[i], &p->dir_z[i]);
        p->org_x[i] = eye.x;
        p->org_y[i] = eye.y;
        p->org_z[i] = eye.z;
        p->t_near[i] = 0.f;
        p->t_far[i] = FLT_MAX;
    }
    if (directions_keep_signs(p, count))
        p->flags |= PACKET_CONSTANT_SIGNS;
}

ray packet_primary_ray_at(const camera_basis *cam, float px, float py)
{
    const screen_map m = screen_map_make(cam);
    ray r = {cam->eye, v3(0.f, 0.f, 0.f), 0.f, FLT_MAX};
    screen_direction(&m, px, py, &r.dir.x, &r.dir.y, &r.dir.z);
    return r;
}
