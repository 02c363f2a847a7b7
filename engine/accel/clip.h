/* clip.h - cutting planes: up to CLIP_MAX_PLANES planes, each a point and a
 * unit normal in world space, on or off (the frame state holds them; txn.h
 * edits them). A plane removes what lies on its normal's side:
 *   removed  { x : dot(n, x - p) > 0 }      kept  { x : dot(n, x - p) <= 0 }
 * (a point on the plane is kept). With several planes what is kept is the
 * intersection of their kept sides, so along any ray it is ONE interval:
 * clipping a ray is shrinking its (t_near, t_far], for primary and secondary
 * rays alike, before traversal.
 *
 * EXACTNESS. The crossing tc of a ray with a plane is computed in double from
 * the float ray and plane; the float bounds are then chosen so that a float t
 * is inside exactly when it is on the kept side of tc: t_near becomes the
 * largest float below tc (t_near is exclusive), t_far the largest float not
 * above it. So two rays, or a primary and a shadow ray, agree on every point
 * up to double rounding of tc (no cracks along a plane through a vertex: the
 * triangles on either side are cut by the same test).
 *
 * CAPS. Where the kept interval starts at a plane (the ray enters the kept
 * region through it), the point there may lie inside a closed part: render.c
 * decides by ray parity against that part and draws the cut face. clip_ray
 * reports which plane bounds t_near for that. */
#ifndef TESSERA_CLIP_H
#define TESSERA_CLIP_H

#include <stdbool.h>
#include <stdint.h>

#include "ray.h"
#include "engine/base/vec3.h"

#define CLIP_MAX_PLANES 8

typedef struct clip_plane {
    vec3 point;  /* world */
    vec3 normal; /* unit, world: the removed side */
    bool on;
} clip_plane;

/* The planes that are on, in double, ready for clip_ray (what a render view
 * reads). Built in the serial section from the frame state's planes. */
typedef struct clip_set {
    uint32_t count;                  /* planes on */
    uint8_t index[CLIP_MAX_PLANES];  /* their indices in the frame state */
    double n[CLIP_MAX_PLANES][3];    /* unit normal */
    double d[CLIP_MAX_PLANES];       /* dot(n, point) */
} clip_set;

/* Whether any of the CLIP_MAX_PLANES planes is on. */
static inline bool clip_planes_on(const clip_plane planes[CLIP_MAX_PLANES])
{
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        if (planes[i].on)
            return true;
    return false;
}

/* The set of planes[i] that are on (count 0: nothing clipped). */
void clip_set_make(clip_set *out, const clip_plane planes[CLIP_MAX_PLANES]);

/* Cut r's (t_near, t_far] to the kept side of every plane of c (EXACTNESS
 * above). False when nothing is left (r unchanged then): no finite float t
 * with t_near < t <= t_far (a crossing beyond float range can leave
 * (FLT_MAX, +inf], which holds no hit). *entry_plane (may be NULL) gets
 * the index (in the frame state) of the plane that now bounds t_near, or -1
 * when t_near is r's own (ties: r's own, then the lowest index). A ray that
 * is not finite gets no guarantee but never NaN bounds. */
bool clip_ray(const clip_set *c, ray *r, int *entry_plane);

/* Whether world point x is kept (on the kept side of every plane, in double). */
bool clip_keeps_point(const clip_set *c, vec3 x);

/* Where ray r crosses plane `plane` (an index in the frame state that is in
 * c): the point, computed in double and rounded once, projected onto the
 * plane; false if the ray is parallel to it. */
bool clip_crossing(const clip_set *c, int plane, const ray *r, vec3 *point);

#endif
