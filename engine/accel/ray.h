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

#include "engine/base/vec3.h"

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
    vec3 inv_dir;     /* 1/dir, with +-FLT_MAX for a zero component */
    unsigned zero_axes; /* bit a: dir component a is zero; box tests then use containment
                           lo <= org <= hi on that axis instead of slab distances */
    int kx, ky, kz;   /* watertight test: kz = axis of largest |dir|, kx, ky the others */
    float shear_x, shear_y, shear_z; /* dir[kx]/dir[kz], dir[ky]/dir[kz], 1/dir[kz] */
    float cull_slack; /* absolute margin on t_far when culling boxes (intersect_cull_slack); 0 from
                         ray_derive, set by traversal for the geometry at hand */
    /* NEXT-HIT QUERIES (accel_intersect_after): only hits after (after_t,
     * after_geom, after_prim) in the closest-hit order count; ray_derive sets
     * after_t = -inf (no such bound). With a bound the ray's t_near is at most
     * the float below after_t, so hits at exactly after_t reach the test. */
    float after_t;
    uint32_t after_geom, after_prim;
} ray_derived;

/* The closest-hit order: does a hit at t on (geom, prim) come before one at
 * best_t on (best_geom, best_prim)? Smaller t first, then the lower geometry
 * id, then the lower primitive id, so a query's answer never depends on the
 * order in which it meets its candidates. */
static inline bool hit_comes_first(float t, uint32_t geom, uint32_t prim, float best_t, uint32_t best_geom,
                                   uint32_t best_prim)
{
    return t < best_t || (t == best_t && (geom < best_geom || (geom == best_geom && prim < best_prim)));
}

/* Whether a hit at t on (geom, prim) comes after the bound of d: t above
 * after_t, or at it with a greater (geom, prim). Only hits with t >= after_t
 * are ever asked (the ray's t_near sees to it). */
static inline bool ray_hit_after(const ray_derived *d, float t, uint32_t geom, uint32_t prim)
{
    return t != d->after_t || geom > d->after_geom || (geom == d->after_geom && prim > d->after_prim);
}

ray_derived ray_derive(const ray *r);

/* A surface point and the uncertainty a ray leaving it must clear,
 * componentwise: the rounding of the point itself and of the intersection
 * test that a ray from it makes against the same surface. */
typedef struct surface_point {
    vec3 p;
    vec3 error; /* >= 0 */
} surface_point;

/* Where a ray leaving a surface point must start so that it cannot re-hit the
 * surface through rounding, at any scale and with no per-scene epsilon: move
 * the point along the unit normal n (pointing to the side the ray leaves to)
 * by the error projected on n, then one more ulp away in each component (the
 * shape of pbrt-v4's OffsetRayOrigin, Pharr, Jakob, Humphreys, "Physically
 * Based Rendering" 4th ed., 6.8.6). */
vec3 ray_offset_origin(surface_point sp, vec3 n);

/* Error allowance, in units of u = 2^-24 of the magnitudes involved: 7 for
 * the barycentric interpolation (pbrt-v4 6.8.5) and the rest for the
 * watertight test of a ray leaving the point, whose t error is a few roundings
 * of the vertex coordinates relative to the ray origin (the vertices' and the
 * point's magnitudes) divided by the same sine of the angle to the surface as
 * the distance to cover, so the allowance holds at every angle. */
#define SURFACE_ERROR_ULPS 32

/* The point of a triangle at barycentrics (u, v), P = (1-u-v) v0 + u v1 + v v2,
 * with error gamma(SURFACE_ERROR_ULPS) (max_i |v_i| + |P|) (max norms), the
 * same in every component. */
surface_point surface_point_triangle(vec3 v0, vec3 v1, vec3 v2, float u, float v);

/* The point of a sphere hit at org + t dir, projected back onto the sphere,
 * with error gamma(SURFACE_ERROR_ULPS) (|centre| + radius) (max norm) in
 * every component;
 * *normal gets the unit outward normal. */
surface_point surface_point_sphere(vec3 org, vec3 dir, float t, vec3 centre, float radius, vec3 *normal);

#endif
