/* bvh.h - bounding volume hierarchy over primitive boxes, built with the binned
 * surface area heuristic (Wald, "On fast Construction of SAH-based Bounding
 * Volume Hierarchies", IEEE RT 2007), evaluating all three axes.
 *
 * The BVH knows boxes only; what a primitive is (triangle, sphere, a whole
 * geometry) is the caller's business, through prim_order. */
#ifndef TESSERA_BVH_H
#define TESSERA_BVH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "aabb.h"
#include "err.h"

typedef struct bvh_node {
    aabb bounds;     /* of everything below */
    uint32_t first;  /* leaf: first slot in prim_order; inner: left child (right = first + 1) */
    uint32_t count;  /* leaf: primitives (>= 1); inner: 0 */
} bvh_node;          /* 32 bytes: two per cache line */

typedef struct bvh {
    bvh_node *nodes;      /* nodes[0] is the root; node_count of them */
    uint32_t node_count;
    uint32_t *prim_order; /* prim_count primitive ids in leaf order */
    uint32_t prim_count;
    uint32_t depth;       /* longest root-to-leaf path, in nodes */
} bvh;

/* Deepest tree the builder makes (SAH splits to depth 60, then halving by count,
 * which adds at most 32 levels for 2^32 primitives): traversal stacks use it. */
#define BVH_MAX_DEPTH 96

/* Build over `count` primitive boxes. `prim_bounds` is read only during the
 * build. An empty input gives an empty BVH (node_count 0). */
bool bvh_build(bvh *out, const aabb *prim_bounds, uint32_t count, tess_error *err);
void bvh_finish(bvh *b); /* frees arrays; the struct itself is the caller's */

size_t bvh_bytes(const bvh *b);

#endif
