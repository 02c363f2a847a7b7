/* ray.h - one ray, its hit record, and the per-ray values the kernels derive.
 *
 * Conventions (shared with `tessera trace` and the packet kernels to come):
 * a hit is accepted only for t_near < t <= t_far; u, v are the barycentric
 * weights of a triangle's 2nd and 3rd vertex (P = (1-u-v) v0 + u v1 + v v2);
 * for spheres u, v are 0. A miss leaves t = +inf and ids = RAY_INVALID_ID. */
#ifndef TESSERA_RAY_H
#define TESSERA_RAY_H

#include <stdbool.h>
#include <stdint.h>

#include "vec3.h"

#define RAY_INVALID_ID 0xFFFFFFFFu

typedef struct ray {
    vec3 org;      /* world units */
    vec3 dir;      /* need not be unit; t is in units of |dir| */
    float t_near;  /* exclusive lower bound of the hit interval */
    float t_far;   /* inclusive upper bound; shrinks to the closest hit so far */
} ray;

typedef struct hit {
    float t;          /* +inf on a miss */
    float u, v;       /* barycentrics (triangles) */
    uint32_t prim_id; /* triangle or sphere index within its geometry */
    uint32_t geom_id; /* scene geometry: meshes first, then the sphere set */
} hit;

static inline hit hit_none(void)
{
    return (hit){.t = INFINITY, .u = 0.f, .v = 0.f, .prim_id = RAY_INVALID_ID, .geom_id = RAY_INVALID_ID};
}

/* True for rays no kernel may trace: non-finite origin or direction, zero
 * direction, NaN bounds, or an empty interval. Such rays miss. */
static inline bool ray_is_degenerate(const ray *r)
{
    return !v3_is_finite(r->org) || !v3_is_finite(r->dir) || (r->dir.x == 0.f && r->dir.y == 0.f && r->dir.z == 0.f) ||
           isnan(r->t_near) || isnan(r->t_far) || !(r->t_near < r->t_far);
}

/* Values derived once per ray and used by every node and triangle test. */
typedef struct ray_derived {
    vec3 inv_dir;     /* 1/dir, with +-FLT_MAX for a zero component (see accel.c) */
    int kx, ky, kz;   /* watertight test: kz = axis of largest |dir|, kx, ky the others */
    float shear_x, shear_y, shear_z; /* dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz] */
} ray_derived;

ray_derived ray_derive(const ray *r);

/* Offset a surface point along its geometric normal (pointing to the side the
 * new ray leaves from) far enough that a ray starting there cannot re-hit the
 * surface through rounding, at any scale: Waechter & Binder, "A Fast and
 * Robust Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6. */
vec3 ray_offset_origin(vec3 p, vec3 n);

#endif
