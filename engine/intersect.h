/* intersect.h - scalar ray/primitive tests. Packet kernels must agree with
 * these bit for bit (the reference the tests compare against). */
#ifndef TESSERA_INTERSECT_H
#define TESSERA_INTERSECT_H

#include <stdbool.h>

#include "aabb.h"
#include "ray.h"

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
