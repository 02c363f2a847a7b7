/* bvh.h - bounding volume hierarchy over primitive boxes, built with the binned
 * surface area heuristic (Wald, "On fast Construction of SAH-based Bounding
 * Volume Hierarchies", IEEE RT 2007), evaluating all three axes, in parallel.
 *
 * The BVH knows boxes only; what a primitive is (triangle, sphere, a whole
 * geometry) is the caller's business, through prim_order.
 *
 * The result is a function of the input alone: any thread count gives the same
 * bytes in nodes and prim_order (so images never depend on the thread count). */
#ifndef TESSERA_BVH_H
#define TESSERA_BVH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/aabb.h"
#include "engine/base/err.h"

typedef struct bvh_node {
    aabb bounds;     /* of everything below */
    uint32_t first;  /* leaf: first slot in prim_order; inner: left child (right = first + 1) */
    uint32_t count;  /* leaf: primitives (1 .. BVH_LEAF_MAX); inner: 0 */
} bvh_node;          /* 32 bytes: two per cache line */

/* Layout: nodes[0] is the root; an inner node's children are a pair allocated
 * when the node is reached in a depth-first, left-first walk from the root, so
 * a left subtree's nodes precede its right sibling's descendants. */
typedef struct bvh {
    bvh_node *nodes;      /* nodes[0] is the root; node_count of them (<= 2 * prim_count - 1) */
    uint32_t node_count;
    uint32_t *prim_order; /* prim_count primitive ids in leaf order */
    uint32_t prim_count;
    uint32_t depth;       /* longest root-to-leaf path, in nodes */
} bvh;

/* Deepest tree the builder makes (SAH splits to depth 60, then halving by count,
 * which adds at most 32 levels for 2^32 primitives): traversal stacks use it. */
#define BVH_MAX_DEPTH 96

/* Leaves hold at most this many primitives: one 16-wide test of points
 * (wbvh.h WBVH_POINTS_LEAF_MAX). bvh_build's leaves hold at most
 * BVH_LEAF_DEFAULT: two 4-wide SIMD tests of triangles. */
#define BVH_LEAF_MAX 16
#define BVH_LEAF_DEFAULT 8

/* THE SAH COST MODEL, shared by every builder (bvh.c, bvh_spatial.c) and by
 * bvh_sah_cost. */
/* Relative costs of one node visit and one leaf block test in the SAH cost model
 * (MacDonald & Booth 1990; Wald 2007): an 8-wide box test and a 4-triangle test.
 * Measured with `tessera bench` on the shared meshes, 1 : 1 and 1 : 2 trace equally
 * fast with the current wide kernels, and 1 : 1 builds ~20 % faster; raise the
 * intersection cost if leaf tests get dearer relative to node visits. */
#define BVH_COST_TRAVERSAL 1.0f
#define BVH_COST_INTERSECT 1.0f
/* Leaf primitives are tested 2^this at a time (4-wide SIMD), so a leaf costs per
 * started block, not per primitive: leaves of 1..4 cost the same. 0 gives the
 * classic per-primitive cost (and, with costs 1 : 1, the original builder's tree). */
#define BVH_SAH_BLOCK_LOG2 2
/* Beyond this depth splits are by count (halves), so depth stays below BVH_MAX_DEPTH. */
#define BVH_SAH_DEPTH_LIMIT 60
/* Started blocks of 2^BVH_SAH_BLOCK_LOG2 primitives in a leaf of n: what a leaf costs. */
static inline float bvh_leaf_blocks(uint32_t n)
{
    return (float)((n + (1u << BVH_SAH_BLOCK_LOG2) - 1) >> BVH_SAH_BLOCK_LOG2);
}

/* Build over `count` primitive boxes (leaves of at most BVH_LEAF_DEFAULT) with `threads` threads, the caller's
 * included (< 1 counts as 1; small inputs use one). `prim_bounds` is read only
 * during the build; boxes may be degenerate (zero size) or empty. An empty
 * input gives an empty BVH (node_count 0). */
bool bvh_build(bvh *out, const aabb *prim_bounds, uint32_t count, int threads, tess_error *err);
/* The same with leaves of at most leaf_max (1..BVH_LEAF_MAX) primitives:
 * 1 where a primitive is costly to enter (an instance: a whole BVH below). */
bool bvh_build_leaves(bvh *out, const aabb *prim_bounds, uint32_t count, int threads, uint32_t leaf_max,
                      tess_error *err);
/* The same with leaves whose test takes 2^block_log2 (0..4) primitives at
 * once, so the SAH prices a leaf by its started blocks (bvh_build: 2, four
 * triangles; particles tested 16 at a time: 4). */
bool bvh_build_blocks(bvh *out, const aabb *prim_bounds, uint32_t count, int threads, uint32_t leaf_max,
                      unsigned block_log2, tess_error *err);
void bvh_finish(bvh *b); /* frees arrays; the struct itself is the caller's */

size_t bvh_bytes(const bvh *b);

/* The builder's own SAH cost model evaluated on the tree: the sum over nodes of
 * (area / root area) x (traversal cost for an inner node, intersection cost per
 * started block of 4 primitives for a leaf). Lower is better; 0 when empty.
 * Evaluated in node order, so equal trees give equal bits. */
double bvh_sah_cost(const bvh *b);

#endif
