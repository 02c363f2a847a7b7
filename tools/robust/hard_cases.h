/* hard_cases.h - the hard cases of numerical robustness, generated from fixed
 * seeds: shared by tests/test_robust.c (which holds the criteria) and
 * `tessera robust` (app/cmd_robust.c, which measures the kernels on
 * them for the report's robustness knob). Nothing here traces a ray: the
 * generators make meshes, rays and double-precision references, so the same
 * cases hold for any kernels behind the accel.
 *
 * The float inputs ARE the problem: every ray and vertex is rounded to float
 * once, and references are computed in double from those floats, so double
 * only removes the engine's own rounding. Each generator draws from its rng in
 * a fixed order: a seed always gives the same case. */
#ifndef TESSERA_HARD_CASES_H
#define TESSERA_HARD_CASES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/geometry/triangles/mesh.h"
#include "engine/accel/ray.h"
#include "engine/base/vec3.h"

/* ---- random numbers: splitmix64 ---- */
typedef struct rng {
    uint64_t state;
} rng;

uint64_t rng_next(rng *g);
double rng_unit(rng *g);                              /* [0, 1) */
double rng_range(rng *g, double lo, double hi);       /* [lo, hi) */
double rng_log_range(rng *g, double lo, double hi);   /* log-uniform in [lo, hi), lo > 0 */

/* ---- double vectors ---- */
typedef struct dvec {
    double x, y, z;
} dvec;

dvec dv(double x, double y, double z);
dvec dv_of(vec3 a);
vec3 dv_round(dvec a); /* to float, each component rounded once */
dvec dv_add(dvec a, dvec b);
dvec dv_sub(dvec a, dvec b);
dvec dv_scale(dvec a, double s);
double dv_dot(dvec a, dvec b);
dvec dv_cross(dvec a, dvec b);
double dv_len(dvec a);
dvec dv_unit(dvec a);
double dv_max_abs(dvec a);
dvec dv_random_unit(rng *g);
dvec dv_random_perpendicular(dvec n, rng *g); /* a random unit vector perpendicular to unit n */
void random_basis(rng *g, dvec *e0, dvec *e1, dvec *e2); /* a random right-handed orthonormal basis */

/* ---- the reference ray/triangle test ----
 * Moeller-Trumbore in double on the float inputs. Differences of the float
 * coordinates are exact in double (when they span fewer than 29 binades), so
 * the only rounding is in the products: relative errors of ~1e-16 / sin(angle
 * to the plane), under 1e-8 for a ray 1e-7 rad from the plane. */
typedef struct ref_triangle_hit {
    bool crosses; /* the ray's line is not parallel to the plane */
    double t;     /* line parameter of the crossing, in units of |dir| */
    double b[3];  /* barycentric weights of v0, v1, v2 at the crossing */
} ref_triangle_hit;

ref_triangle_hit reference_triangle(const ray *r, vec3 v0, vec3 v1, vec3 v2);
/* The crossing lies in the closed triangle and in (t_near, t_far]. */
bool reference_hits(const ref_triangle_hit *h, float t_near, float t_far);

/* ---- a. closed meshes ---- */

/* A UV sphere around `centre`: `slices` vertices per ring, `stacks` bands from
 * pole to pole, every vertex at radius 1 +- `jitter` (uniform), so no two faces
 * are coplanar. Consistently oriented and closed: every edge belongs to exactly
 * two triangles, once in each direction. The pole fans and the thin triangles
 * next to them are hard cases for a watertight test. NULL without memory. */
mesh *jittered_sphere(int slices, int stacks, double jitter, dvec centre, rng *g);

/* Ray targets on a closed mesh: every vertex, then `points_per_edge` points
 * evenly inside every undirected edge (edges in the order the triangles list
 * them, each once). Writes a malloc'd array to *targets and the number of
 * undirected edges to *edges (a closed genus-0 mesh has 3V - 6); returns the
 * number of targets, 0 without memory (*targets NULL). */
size_t closed_mesh_targets(const mesh *m, int points_per_edge, vec3 **targets, size_t *edges);

/* ---- b. slivers ---- */

/* A sliver of longest edge `len` and height len / 1e6 (aspect ratio 1e6),
 * rotated at random and placed within `len` of the world origin. A needle has
 * its short edge at one end; a cap has its third vertex half-way along the
 * long edge. */
void random_sliver(rng *g, double len, bool needle, vec3 v[3]);

/* A ray at sliver v (longest edge `len`) aimed at an interior point P whose
 * barycentrics are all >= 0.2, from an origin 1e-4 .. 1e-2 edge lengths away
 * at >= 5 degrees from the plane; P is exact (double) and the direction is
 * P - origin rounded once, so the ray passes within ~1e-9 edge lengths of P:
 * every such ray hits. t in (0, FLT_MAX]. Writes the barycentrics b1, b2 of
 * v1, v2 at P. */
ray sliver_ray(rng *g, const vec3 v[3], double len, double *b1, double *b2);

/* ---- g. lit planes (no self-shadowing) ---- */

/* A plane 4 * half across around `offset` along (1, 0.7, -0.4)/|.| in one of
 * two forms: form 0, one big triangle in a random orientation; form 1, an
 * 8 x 8 grid of quads in the plane y = const (exactly planar in float), the
 * square [-half, half]^2 around the shift. Writes the shift, the in-plane axes
 * e0, e1 and the unit normal n. NULL without memory. */
mesh *lit_plane_mesh(rng *g, double offset, int form, double half, dvec *shift, dvec *e0, dvec *e1, dvec *n);

/* Unit direction to a directional light at `tilt_deg` degrees to the plane of
 * unit normal n (on its side), rounded to float. */
vec3 lit_plane_light(rng *g, dvec n, double tilt_deg);

/* A primary ray from a viewer on the lit side (at >= 0.2 of the normal,
 * 0.2 .. 2 half-widths away) at a random point well inside the square
 * [-0.95 half, 0.95 half]^2 around `shift` of the plane (e0, e1, n). */
ray lit_plane_primary(rng *g, dvec shift, dvec e0, dvec e1, dvec n, double half);

/* What engine/render/render.c does for a triangle hit: the position from the
 * barycentrics with its rounding bound (surface_point_triangle: on the surface,
 * unlike org + t dir), and the unit geometric normal turned to face the
 * incoming ray. */
surface_point surface_at_hit(const mesh *m, const hit *h, vec3 ray_dir, vec3 *normal);

#endif
