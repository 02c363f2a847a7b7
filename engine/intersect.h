/* intersect.h - scalar ray/primitive tests. Packet kernels must agree with
 * these bit for bit (the reference the tests compare against). */
#ifndef TESSERA_INTERSECT_H
#define TESSERA_INTERSECT_H

#include <stdbool.h>

#include "aabb.h"
#include "ray.h"

/* gamma(3) = 3u / (1 - 3u), u = 2^-24: the rounding bound of three float
 * operations (pbrt's notation). Box exit distances are scaled by
 * INTERSECT_FAR_SCALE (Ize 2013), and traversal culls a box only when its
 * entry exceeds t_far * INTERSECT_FAR_SCALE, so a primitive at exactly t_far
 * (a tie) is never culled and results do not depend on traversal order. */
#define INTERSECT_GAMMA3 (3.f * 0x1p-24f / (1.f - 3.f * 0x1p-24f))
#define INTERSECT_FAR_SCALE (1.f + 2.f * INTERSECT_GAMMA3)

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

#endif
