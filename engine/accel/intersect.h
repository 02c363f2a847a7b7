/* intersect.h - scalar ray/primitive tests. Packet kernels must agree with
 * these bit for bit (the reference the tests compare against). */
#ifndef TESSERA_INTERSECT_H
#define TESSERA_INTERSECT_H

#include <stdbool.h>

#include "engine/base/aabb.h"
#include "ray.h"

/* TESSERA_UNROBUST: a fast, NON-robust build for measuring what robustness
 * costs (the report's robustness knob; `make unrobust` builds
 * build-unrobust/tessera, never ./tessera). Defined at build time only, it
 * takes out every robustness rule of the kernels, and nothing else:
 *   1. the double-precision redo of the watertight test (float decides
 *      every edge sign, and a zero determinant is a miss, as in the paper);
 *   2. Ize's far-distance scale of the slab test (INTERSECT_FAR_SCALE 1);
 *   3. the culling margin: relative (INTERSECT_CULL_SCALE 1) and absolute
 *      (intersect_cull_slack 0), so boxes are culled at t_far itself;
 *   4. containment for zero direction components: 1/0 is +-inf and every
 *      axis gets the plain slab test ((plane - org) * inf may be NaN);
 *   5. the shadow-ray origin offset from the rounding bound of the hit
 *      point: a fixed world-space epsilon along the normal instead
 *      (INTERSECT_UNROBUST_SHADOW_OFFSET), as tracers without error bounds do.
 * Ties still go to the lowest id (that rule is order independence, not
 * robustness). The default build never defines it, so its code is unchanged. */
#ifdef TESSERA_UNROBUST
#define INTERSECT_UNROBUST_SHADOW_OFFSET 1e-4f /* world units */
#endif

/* gamma(3) = 3u / (1 - 3u), u = 2^-24: the rounding bound of three float
 * operations (pbrt's notation). Box exit distances are scaled by
 * INTERSECT_FAR_SCALE (Ize 2013), and traversal culls a box only when its
 * entry exceeds t_far * INTERSECT_FAR_SCALE, so a primitive at exactly t_far
 * (a tie) is never culled and results do not depend on traversal order. */
#define INTERSECT_GAMMA3 (3.f * 0x1p-24f / (1.f - 3.f * 0x1p-24f))
#ifndef TESSERA_UNROBUST
#define INTERSECT_FAR_SCALE (1.f + 2.f * INTERSECT_GAMMA3)
#else
#define INTERSECT_FAR_SCALE 1.f
#endif

/* Traversal skips a box only when its entry distance exceeds the closest hit's
 * t by a margin that covers the rounding of both: the hit's t may lie a few
 * ulps below the exact value and the box entry a few above, and a primitive at
 * the same computed t (a tie, decided by id) must still be found whatever the
 * visiting order. The margin is relative (INTERSECT_CULL_SCALE) plus an
 * absolute slack from the magnitude of the coordinates involved, 2^-19 (8
 * ulps) of them, in units of the ray's t (intersect_cull_slack). */
#ifndef TESSERA_UNROBUST
#define INTERSECT_CULL_SCALE (1.f + 0x1p-19f)
#define INTERSECT_CULL_ULPS 0x1p-19f

static inline float intersect_cull_slack(float org_abs_max, float dir_abs_max, float coord_abs_max)
{
    return (org_abs_max + coord_abs_max) * INTERSECT_CULL_ULPS / dir_abs_max;
}
#else
#define INTERSECT_CULL_SCALE 1.f

static inline float intersect_cull_slack(float org_abs_max, float dir_abs_max, float coord_abs_max)
{
    (void)org_abs_max, (void)dir_abs_max, (void)coord_abs_max;
    return 0.f; /* the fast build culls at the computed t_far itself */
}
#endif

/* The float edge functions of the watertight test carry rounding from the
 * vertex differences, the shear and the products. For the edge of vertices b,
 * c it is below about 8 u (Mc Pb + Mb Pc) with u = 2^-24, M the L1 norm of a
 * vertex relative to the ray origin (which bounds the shear's rounding) and P
 * the L1 norm of its two sheared coordinates. When an edge function is not
 * larger than INTERSECT_EDGE_TOL (Mc Pb + Mb Pc) (32 u, with margin), its sign
 * is not certain and the whole test is redone in double from the original
 * coordinates. The decision depends on the edge and the ray alone, so two
 * triangles sharing an edge always decide it alike (watertightness), and
 * slivers and grazing rays get double precision exactly where float cannot
 * answer. */
#define INTERSECT_EDGE_TOL 0x1p-19f

/* True when the triangle has exactly zero area (collinear or coincident
 * vertices): it can never be hit. */
bool intersect_triangle_degenerate(vec3 v0, vec3 v1, vec3 v2);

/* Watertight ray/triangle test: Woop, Benthin, Wald, "Watertight Ray/Triangle
 * Intersection", JCGT 2(1), 2013. No ray passes between two triangles that
 * share an edge. On a hit with t in (r->t_near, r->t_far] writes t, u, v and
 * returns true. */
bool intersect_triangle(const ray *r, const ray_derived *d, vec3 v0, vec3 v1, vec3 v2, float *t, float *u,
                        float *v);

/* Ray/sphere in the numerically stable form of Haines, Guenther,
 * Akenine-Moeller, "Precision Improvements for Ray/Sphere Intersection", Ray
 * Tracing Gems ch. 7: the discriminant from the distance of the centre to the
 * ray line, and the near root without cancellation. Returns the nearest root in
 * (t_near, t_far]. */
bool intersect_sphere(const ray *r, vec3 centre, float radius, float *t);

/* Slab test with Ize's robustness bound ("Robust BVH Ray Traversal", JCGT
 * 2(2), 2013): the far distance is scaled by 1 + 2 gamma(3) so rounding never
 * rejects a box the exact ray passes through. Writes the entry distance. */
bool intersect_box(const ray *r, const ray_derived *d, const aabb *b, float *t_entry);
/* The part of [r->t_near, r->t_far] inside box b, exactly as the slabs give
 * it (no conservative widening: for integrating along the ray, not for
 * culling); false when it is empty. */
bool intersect_box_span(const ray *r, const ray_derived *d, const aabb *b, float *t_entry, float *t_exit);

#endif
