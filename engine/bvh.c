#include "bvh.h"

#include <stdlib.h>
#include <string.h>

/* Bins per axis: 16 is where Wald (2007) found SAH quality saturates for binned builds. */
#define BVH_BINS 16
/* Leaves hold at most this many primitives: bounds the worst-case leaf work per ray. */
#define BVH_LEAF_MAX 8
/* Relative costs of one node visit and one primitive test in the SAH cost model. */
#define BVH_COST_TRAVERSAL 1.0f
#define BVH_COST_INTERSECT 1.0f
/* Beyond this depth splits are by count (halves), so depth stays below BVH_MAX_DEPTH. */
#define BVH_SAH_DEPTH_LIMIT 60

typedef struct build_task {
    uint32_t node;  /* node to fill */
    uint32_t begin; /* its primitives: prim_order[begin, end) */
    uint32_t end;
    uint32_t depth; /* of this node, root = 1 */
} build_task;

typedef struct bin {
    aabb bounds;
    uint32_t count;
} bin;

/* Result of evaluating splits for one node. */
typedef struct split {
    int axis;       /* -1: no split better than a leaf was found */
    int bin;        /* primitives in bins [0, bin] go left */
    float cost;
    float centroid_lo, bin_scale; /* centroid-to-bin mapping on `axis` */
} split;

static int bin_of(float centroid, float centroid_lo, float bin_scale)
{
    int b = (int)((centroid - centroid_lo) * bin_scale);
    return b < 0 ? 0 : b >= BVH_BINS ? BVH_BINS - 1 : b;
}

static split find_split(const aabb *prim_bounds, const uint32_t *order, uint32_t begin, uint32_t end,
                        aabb centroid_box, float parent_half_area)
{
    split best = {.axis = -1, .cost = INFINITY};
    for (int axis = 0; axis < 3; axis++) {
        float lo = v3_get(centroid_box.lo, axis), hi = v3_get(centroid_box.hi, axis);
        if (!(hi > lo))
            continue;
        /* scale maps [lo, hi] to [0, BINS) with the top value landing in the last bin */
        float scale = (float)BVH_BINS * (1.f - 1e-6f) / (hi - lo);
        bin bins[BVH_BINS];
        for (int b = 0; b < BVH_BINS; b++)
            bins[b] = (bin){aabb_empty(), 0};
        for (uint32_t i = begin; i < end; i++) {
            aabb pb = prim_bounds[order[i]];
            int b = bin_of(v3_get(aabb_centre(pb), axis), lo, scale);
            bins[b].bounds = aabb_grow(bins[b].bounds, pb);
            bins[b].count++;
        }
        /* sweep from the right: area and count of bins (b, BINS) */
        float right_area[BVH_BINS];
        uint32_t right_count[BVH_BINS];
        aabb acc = aabb_empty();
        uint32_t n = 0;
        for (int b = BVH_BINS - 1; b > 0; b--) {
            acc = aabb_grow(acc, bins[b].bounds);
            n += bins[b].count;
            right_area[b - 1] = aabb_half_area(acc);
            right_count[b - 1] = n;
        }
        acc = aabb_empty();
        n = 0;
        for (int b = 0; b < BVH_BINS - 1; b++) {
            acc = aabb_grow(acc, bins[b].bounds);
            n += bins[b].count;
            if (n == 0 || right_count[b] == 0)
                continue;
            float cost = BVH_COST_TRAVERSAL + BVH_COST_INTERSECT *
                                                  (aabb_half_area(acc) * (float)n +
                                                   right_area[b] * (float)right_count[b]) /
                                                  parent_half_area;
            if (cost < best.cost)
                best = (split){axis, b, cost, lo, scale};
        }
    }
    return best;
}

/* Partition order[begin, end) by the split; returns the first index of the right side. */
static uint32_t partition(const aabb *prim_bounds, uint32_t *order, uint32_t begin, uint32_t end, split s)
{
    uint32_t i = begin, j = end;
    while (i < j) {
        float c = v3_get(aabb_centre(prim_bounds[order[i]]), s.axis);
        if (bin_of(c, s.centroid_lo, s.bin_scale) <= s.bin)
            i++;
        else {
            uint32_t t = order[i];
            order[i] = order[--j];
            order[j] = t;
        }
    }
    return i;
}

bool bvh_build(bvh *out, const aabb *prim_bounds, uint32_t count, tess_error *err)
{
    memset(out, 0, sizeof *out);
    if (count == 0)
        return true;
    size_t max_nodes = 2 * (size_t)count - 1;
    out->nodes = malloc(max_nodes * sizeof *out->nodes);
    out->prim_order = malloc((size_t)count * sizeof *out->prim_order);
    build_task *stack = malloc(BVH_MAX_DEPTH * 2 * sizeof *stack);
    if (!out->nodes || !out->prim_order || !stack) {
        free(stack);
        bvh_finish(out);
        return tess_error_set(err, "bvh: out of memory for %u primitives", count);
    }
    for (uint32_t i = 0; i < count; i++)
        out->prim_order[i] = i;
    out->prim_count = count;
    out->node_count = 1;

    int top = 0;
    stack[top++] = (build_task){0, 0, count, 1};
    while (top > 0) {
        build_task t = stack[--top];
        if (t.depth > out->depth)
            out->depth = t.depth;
        aabb box = aabb_empty(), centroids = aabb_empty();
        for (uint32_t i = t.begin; i < t.end; i++) {
            aabb pb = prim_bounds[out->prim_order[i]];
            box = aabb_grow(box, pb);
            centroids = aabb_grow_point(centroids, aabb_centre(pb));
        }
        bvh_node *node = &out->nodes[t.node];
        node->bounds = box;
        uint32_t n = t.end - t.begin;
        uint32_t mid = t.begin;
        if (n > 1 && t.depth < BVH_SAH_DEPTH_LIMIT) {
            split s = find_split(prim_bounds, out->prim_order, t.begin, t.end, centroids, aabb_half_area(box));
            float leaf_cost = BVH_COST_INTERSECT * (float)n;
            if (s.axis >= 0 && (n > BVH_LEAF_MAX || s.cost < leaf_cost))
                mid = partition(prim_bounds, out->prim_order, t.begin, t.end, s);
        }
        /* no useful SAH split (coincident centroids, or too deep): halve by count if too big */
        if ((mid == t.begin || mid == t.end) && n > BVH_LEAF_MAX)
            mid = t.begin + n / 2;
        if (mid == t.begin || mid == t.end) {
            node->first = t.begin;
            node->count = n;
            continue;
        }
        uint32_t left = out->node_count;
        out->node_count += 2;
        node->first = left;
        node->count = 0;
        /* depth-first, right pushed first so the left subtree is laid out next */
        stack[top++] = (build_task){left + 1, mid, t.end, t.depth + 1};
        stack[top++] = (build_task){left, t.begin, mid, t.depth + 1};
    }
    free(stack);
    return true;
}

void bvh_finish(bvh *b)
{
    if (!b)
        return;
    free(b->nodes);
    free(b->prim_order);
    memset(b, 0, sizeof *b);
}

size_t bvh_bytes(const bvh *b)
{
    return (size_t)b->node_count * sizeof(bvh_node) + (size_t)b->prim_count * sizeof(uint32_t);
}
