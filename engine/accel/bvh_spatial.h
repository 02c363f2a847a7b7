/* bvh_spatial.h - a binary BVH over triangles with spatial splits (SBVH:
 * Stich, Friedrich, Dietrich, "Spatial Splits in Bounding Volume
 * Hierarchies", HPG 2009).
 *
 * At every node the best binned object split (as bvh.c, the same SAH cost
 * model of bvh.h) is compared with the best spatial split: a plane that
 * chops the triangles crossing it, each side keeping a reference with the
 * bounds of the triangle's part on that side. Spatial splits are tried only
 * where the object split's two children overlap by more than
 * BVH_SPATIAL_ALPHA of the root's area, and only while the references stay
 * within BVH_SPATIAL_GROWTH of the triangle count. A chopped reference whose
 * duplication costs more than it saves goes whole to one side (reference
 * unsplitting).
 *
 * The output is a bvh whose prim_order holds REFERENCES: input triangle
 * numbers, a triangle in every leaf that holds a part of it; prim_count is
 * the number of references. Every leaf box contains the parts of its
 * triangles it stands for (boxes are rounded outward, never inward), so the
 * leaves together cover every triangle. The build is serial; its result is a
 * function of the input alone. */
#ifndef TESSERA_BVH_SPATIAL_H
#define TESSERA_BVH_SPATIAL_H

#include <stdbool.h>
#include <stdint.h>

#include "bvh.h"
#include "engine/base/err.h"

/* Spatial splits are tried where the object split's children overlap by
 * more than this fraction of the root's half area (the paper's alpha). */
#define BVH_SPATIAL_ALPHA 1e-5f
/* At most this fraction more references than triangles (0.3: 30 %). */
#define BVH_SPATIAL_GROWTH 0.3
/* Slabs per axis of the spatial binning: 16 builds 1.7 times faster than 32 for
 * the same SAH cost (within 0.5 %) on the bunny, a gen-assembly and a pipe rack. */
#define BVH_SPATIAL_BINS 16

/* The triangles to build over: input triangle i has the corners
 * indices[3 * ids[i] + 0..2], each a vertex of 3 floats in positions. */
typedef struct bvh_triangles {
    const float *positions;
    const uint32_t *indices;
    const uint32_t *ids;
    uint32_t count;
} bvh_triangles;

/* Build with leaves of at most BVH_LEAF_DEFAULT references. Triangles
 * should have area (a degenerate one is kept, in one leaf at least). An
 * empty input gives an empty BVH. False (err set): out of memory, or more
 * triangles than the reference budget can number. */
bool bvh_build_spatial(bvh *out, const bvh_triangles *tris, tess_error *err);

/* The reference budget for `count` triangles: count + floor(GROWTH * count). */
uint64_t bvh_spatial_reference_budget(uint32_t count);

#endif
