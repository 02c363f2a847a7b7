/* wbvh.h - 8-wide BVH with SIMD-friendly nodes.
 *
 * Built by collapsing the binary SAH BVH (bvh.h): each wide node takes up to 8
 * descendants, always opening the child with the largest surface area next,
 * so the wide tree keeps the binary tree's SAH quality. Child boxes are
 * stored as structure of arrays, so one ray tests all 8 with one 8-lane
 * compare sequence. A mesh's leaves (WBVH_MESH) and a point set's
 * (WBVH_POINTS) are ranges of the kind's own arrays, read in place. Other
 * leaves are runs of blocks of 4 spheres (SoA, tested 4 at a time) or of 4
 * primitive ids; unused lanes of a block are degenerate (a zero-radius
 * sphere at the origin) with prim id RAY_INVALID_ID and never report a hit.
 * A tree whose binary root is a leaf gets a root node with that one leaf
 * child, so traversal has no special case. */
#ifndef TESSERA_WBVH_H
#define TESSERA_WBVH_H

#include <stdalign.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <stdatomic.h>

#include "bvh.h"
#include "engine/base/err.h"
#include "geometry.h"

#define WBVH_WIDTH 8
#define WBVH_BLOCK 4
/* Most blocks one leaf can hold: BVH_LEAF_MAX primitives in blocks of 4
 * (triangle leaves hold at most BVH_LEAF_DEFAULT, points leaves no blocks). */
#define WBVH_MAX_LEAF_BLOCKS ((BVH_LEAF_MAX + WBVH_BLOCK - 1) / WBVH_BLOCK)
/* Traversal stack entries: at most 7 siblings wait per level of the binary depth bound. */
#define WBVH_STACK_SIZE (BVH_MAX_DEPTH * (WBVH_WIDTH - 1) + 1)

typedef struct wbvh_node {
    alignas(64) float lo_x[WBVH_WIDTH]; /* child boxes; empty slots are masked by child_mask */
    float hi_x[WBVH_WIDTH];
    float lo_y[WBVH_WIDTH];
    float hi_y[WBVH_WIDTH];
    float lo_z[WBVH_WIDTH];
    float hi_z[WBVH_WIDTH];
    uint32_t child[WBVH_WIDTH];      /* inner child: node index; leaf child: first block index */
    uint8_t leaf_blocks[WBVH_WIDTH]; /* 0: inner child; n > 0: leaf of n consecutive blocks */
    uint8_t child_mask;              /* bit i: slot i holds a child that may be hit (an instance
                                        level's refit clears the bits of children left empty) */
    uint8_t slot_mask;               /* bit i: slot i holds a child (as built) */
    uint8_t pad[22];
} wbvh_node; /* 256 bytes: four cache lines */

/* Four spheres, SoA. */
typedef struct wbvh_sphere_block {
    alignas(16) float cx[WBVH_BLOCK], cy[WBVH_BLOCK], cz[WBVH_BLOCK], r[WBVH_BLOCK];
    uint32_t prim_id[WBVH_BLOCK];
} wbvh_sphere_block;

/* Four primitive ids, for kinds without a SIMD layout (GEOMETRY_LEAF_PRIMS)
 * and for the instance level (ids of instances). */
typedef struct wbvh_prim_block {
    uint32_t prim_id[WBVH_BLOCK];
} wbvh_prim_block;

typedef enum wbvh_kind {
    WBVH_SPHERES,
    WBVH_PRIMS,
    WBVH_INSTANCES,
    /* GEOMETRY_LEAF_POINTS: no blocks; a leaf child's `child` is its first
     * point and `leaf_blocks` its point count (1..WBVH_POINTS_LEAF_MAX),
     * read in place through `points` */
    WBVH_POINTS,
    /* GEOMETRY_LEAF_MESH: no blocks; a leaf child's `child` is its first
     * triangle and `leaf_blocks` its triangle count (1..BVH_LEAF_DEFAULT),
     * read in place through `mesh` */
    WBVH_MESH,
} wbvh_kind;

/* Most points in one leaf of a WBVH_POINTS tree (one AVX-512 test). */
#define WBVH_POINTS_LEAF_MAX 16
/* Traversal packs a leaf's first block (or first point) and its count into
 * one 32-bit reference (isa/traverse.c: 1 flag bit, 27 bits of first, 4 of
 * count - 1): a tree holds fewer primitives than this (134 M). */
#define WBVH_MAX_LEAF_FIRST (1u << 27)

struct wbvh;

/* One leaf entry of the instance level: a geometry's tree and where rays
 * meet it. */
typedef struct wbvh_instance {
    const struct wbvh *geometry; /* the bottom level (shared by every instance of the geometry) */
    affine3 to_object;           /* world -> object */
    bool identity;               /* no transform: rays go down unchanged */
} wbvh_instance;

typedef struct wbvh {
    wbvh_kind kind;
    wbvh_node *nodes;   /* nodes[0] is the root; node_count 0 for an empty geometry */
    uint32_t node_count;
    void *blocks;       /* wbvh_sphere_block or wbvh_prim_block array, by kind */
    uint32_t block_count;
    float coord_abs_max; /* largest |coordinate| of the bounds: scales the cull slack */
    /* WBVH_PRIMS: the kind whose `intersect` tests each primitive, and its data */
    const geometry_ops *ops;
    const void *data;
    /* WBVH_INSTANCES: the instances (prim ids index this) and their hidden
     * flags (nonzero: not hit; relaxed atomics, see accel.h) */
    const wbvh_instance *instances;
    const atomic_uchar *hidden;
    /* WBVH_INSTANCES, for refitting only what changed (wbvh_mark_instances):
     * each node's parent (UINT32_MAX for the root), the node whose leaf slot
     * holds each instance, and which nodes' boxes are stale. Written only by
     * the marking and refitting calls, which the caller serialises (accel.c:
     * under its refit lock). */
    uint32_t *parent;
    uint32_t *leaf_node;
    uint8_t *stale;
    uint32_t instance_count;
    /* WBVH_POINTS: the kind's arrays, and when it crops (points.crop_value),
     * the range of crop values under each child slot (node_count * 8 each;
     * an empty slot has lo = +inf, hi = -inf), so a crop skips whole
     * subtrees. */
    geometry_points points;
    float *crop_lo, *crop_hi;
    /* WBVH_MESH: the kind's arrays, in the tree's order (read in place:
     * copying a triangle's vertices into SoA blocks took 40 bytes) */
    geometry_mesh_arrays mesh;
    /* a copy of a tree its kind keeps (geometry_ops.tree): wbvh_finish
     * leaves the arrays to the kind */
    bool borrowed;
} wbvh;


/* Build from a binary BVH over the primitives of a geometry of kind `ops`
 * (its leaf layout decides the blocks). The binary BVH's primitive i is
 * primitive prim_ids[i] of the geometry (prim_ids NULL: primitive i), so
 * primitives that can never be hit may be left out. */
bool wbvh_build(wbvh *out, const bvh *binary, const geometry_ops *ops, const void *data, const uint32_t *prim_ids,
                tess_error *err);
/* A GEOMETRY_LEAF_POINTS tree: the binary BVH's primitive i must be point
 * i (the kind has put its points in the binary tree's prim_order), so every
 * leaf is the range [first, first + count) of `points`; leaves hold at most
 * WBVH_POINTS_LEAF_MAX points. */
bool wbvh_build_points(wbvh *out, const bvh *binary, const geometry_points *points, tess_error *err);
/* A GEOMETRY_LEAF_MESH tree: the binary BVH's primitive i must be
 * triangle i of `arrays` (the kind has put its triangles in the binary
 * tree's prim_order), so every leaf is the range [first, first + count) of
 * them; leaves hold at most BVH_LEAF_DEFAULT triangles. */
bool wbvh_build_mesh(wbvh *out, const bvh *binary, const geometry_ops *ops, const void *data,
                     const geometry_mesh_arrays *arrays, tess_error *err);
/* The instance level: the binary BVH's primitive i is instance i. */
bool wbvh_build_instances(wbvh *out, const bvh *binary, const wbvh_instance *instances, const atomic_uchar *hidden,
                          tess_error *err);
/* Recompute an instance level's boxes from each instance's world box,
 * leaving hidden instances out; children left empty are masked off
 * (child_mask), so traversal never enters them. O(nodes + instances). */
void wbvh_refit_instances(wbvh *w, const aabb *instance_bounds);
/* Mark instances first..first+count-1 (clamped to the level) as changed
 * (box, hidden flag): their leaves' nodes and those nodes' ancestors become
 * stale. O(count + nodes newly marked). */
void wbvh_mark_instances(wbvh *w, uint32_t first, uint32_t count);
/* Recompute the boxes of the stale nodes only, children before parents, and
 * clear the marks; the result equals wbvh_refit_instances when every change
 * since the last refit was marked. Whether anything was stale. */
bool wbvh_refit_stale(wbvh *w, const aabb *instance_bounds);
void wbvh_finish(wbvh *w);
size_t wbvh_bytes(const wbvh *w);

#endif
