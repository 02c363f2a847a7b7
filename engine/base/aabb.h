/* aabb.h - axis-aligned bounding boxes. An empty box has lo = +inf, hi = -inf,
 * so growing it by any point or box gives that point or box. */
#ifndef TESSERA_AABB_H
#define TESSERA_AABB_H

#include <math.h>

#include "vec3.h"

typedef struct aabb {
    vec3 lo, hi; /* world units; lo <= hi componentwise unless empty */
} aabb;

static inline aabb aabb_empty(void) { return (aabb){v3(INFINITY, INFINITY, INFINITY), v3(-INFINITY, -INFINITY, -INFINITY)}; }
static inline aabb aabb_grow_point(aabb b, vec3 p) { return (aabb){v3_min(b.lo, p), v3_max(b.hi, p)}; }
static inline aabb aabb_grow(aabb b, aabb o) { return (aabb){v3_min(b.lo, o.lo), v3_max(b.hi, o.hi)}; }
static inline vec3 aabb_centre(aabb b) { return v3_scale(v3_add(b.lo, b.hi), 0.5f); }
static inline int aabb_is_empty(aabb b) { return !(b.lo.x <= b.hi.x); }
/* Half the surface area (the SAH only needs ratios); 0 for an empty box. */
static inline float aabb_half_area(aabb b)
{
    if (aabb_is_empty(b))
        return 0.f;
    vec3 e = v3_sub(b.hi, b.lo);
    return e.x * e.y + e.y * e.z + e.z * e.x;
}

#endif
