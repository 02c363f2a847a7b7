#include "wbvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/base/memory.h"
#include "ray.h"


/* Fills one block lane from a primitive; the block was zeroed, so unused
 * lanes stay degenerate. */
typedef void (*fill_lane_fn)(void *block, int lane, uint32_t prim, const void *source);

/* Prim-id blocks: the id is all there is. */
static void fill_prim_id(void *block, int lane, uint32_t prim, const void *source)
{
    (void)source;
    ((wbvh_prim_block *)block)->prim_id[lane] = prim;
}

typedef struct collapse {
    const bvh *binary;
    wbvh *out;
    size_t block_bytes;
    fill_lane_fn fill;
    const void *source;
    const uint32_t *prim_ids; /* binary primitive -> source primitive, or NULL for identity */
} collapse;

static void init_block(collapse *c, uint32_t index)
{
    char *block = (char *)c->out->blocks + (size_t)index * c->block_bytes;
    memset(block, 0, c->block_bytes);
    /* prim_id is the last member of every block type */
    uint32_t *ids = (uint32_t *)(block + c->block_bytes - WBVH_BLOCK * sizeof(uint32_t));
    for (int i = 0; i < WBVH_BLOCK; i++)
        ids[i] = RAY_INVALID_ID;
}

/* Emit the primitives of binary leaf `leaf` as consecutive blocks; returns the first. */
static uint32_t emit_leaf(collapse *c, const bvh_node *leaf, uint8_t *block_count)
{
    uint32_t first = c->out->block_count;
    uint32_t blocks = (leaf->count + WBVH_BLOCK - 1) / WBVH_BLOCK;
    for (uint32_t b = 0; b < blocks; b++) {
        init_block(c, first + b);
        char *block = (char *)c->out->blocks + (size_t)(first + b) * c->block_bytes;
        for (uint32_t lane = 0; lane < WBVH_BLOCK && b * WBVH_BLOCK + lane < leaf->count; lane++)
        {
            uint32_t prim = c->binary->prim_order[leaf->first + b * WBVH_BLOCK + lane];
            c->fill(block, (int)lane, c->prim_ids ? c->prim_ids[prim] : prim, c->source);
        }
    }
    c->out->block_count += blocks;
    *block_count = (uint8_t)blocks;
    return first;
}

/* Choose up to 8 binary descendants of binary node `b` to become the wide
 * node's children: open the inner child of largest surface area until 8 are
 * there or only leaves remain. Order stays left to right. */
static int gather_children(const bvh *binary, uint32_t b, uint32_t kids[WBVH_WIDTH])
{
    const bvh_node *root = &binary->nodes[b];
    if (root->count > 0) { /* the whole tree is one leaf */
        kids[0] = b;
        return 1;
    }
    int n = 2;
    kids[0] = root->first;
    kids[1] = root->first + 1;
    while (n < WBVH_WIDTH) {
        int best = -1;
        float best_area = -1.f;
        for (int i = 0; i < n; i++) {
            const bvh_node *k = &binary->nodes[kids[i]];
            float area = aabb_half_area(k->bounds);
            if (k->count == 0 && area > best_area) {
                best = i;
                best_area = area;
            }
        }
        if (best < 0)
            break;
        uint32_t opened = binary->nodes[kids[best]].first;
        memmove(&kids[best + 2], &kids[best + 1], (size_t)(n - best - 1) * sizeof kids[0]);
        kids[best] = opened;
        kids[best + 1] = opened + 1;
        n++;
    }
    return n;
}

static bool run_collapse(collapse *c, tess_error *err)
{
    const bvh *binary = c->binary;
    wbvh *out = c->out;
    if (binary->node_count == 0)
        return true;
    size_t max_nodes = binary->node_count; /* one wide node per binary inner node at most (+1 for a leaf root) */
    size_t max_blocks = binary->prim_count;
    out->nodes = memory_alloc_large(max_nodes * sizeof(wbvh_node));
    if (c->block_bytes > 0)
        out->blocks = memory_alloc_large(max_blocks * c->block_bytes);
    /* work list: (binary node, wide node) pairs still to fill; at most one per wide node */
    uint32_t *todo_binary = malloc(max_nodes * sizeof(uint32_t)), *todo_wide = malloc(max_nodes * sizeof(uint32_t));
    if (!out->nodes || (c->block_bytes > 0 && !out->blocks) || !todo_binary || !todo_wide) {
        free(todo_binary);
        free(todo_wide);
        return tess_error_set(err, "wbvh: out of memory for %zu nodes", max_nodes);
    }
    const aabb root = binary->nodes[0].bounds;
    out->coord_abs_max = 0.f;
    const float extremes[6] = {root.lo.x, root.lo.y, root.lo.z, root.hi.x, root.hi.y, root.hi.z};
    for (int k = 0; k < 6; k++)
        out->coord_abs_max = fabsf(extremes[k]) > out->coord_abs_max ? fabsf(extremes[k]) : out->coord_abs_max;
    size_t todo = 0;
    out->node_count = 1;
    todo_binary[todo] = 0;
    todo_wide[todo++] = 0;
    while (todo > 0) {
        todo--;
        uint32_t b = todo_binary[todo], w = todo_wide[todo];
        wbvh_node *node = &out->nodes[w];
        memset(node, 0, sizeof *node);
        uint32_t kids[WBVH_WIDTH];
        int n = gather_children(binary, b, kids);
        for (int i = 0; i < WBVH_WIDTH; i++) {
            if (i >= n) { /* empty slot: an inverted box, and masked out anyway */
                node->lo_x[i] = node->lo_y[i] = node->lo_z[i] = INFINITY;
                node->hi_x[i] = node->hi_y[i] = node->hi_z[i] = -INFINITY;
                continue;
            }
            const bvh_node *k = &binary->nodes[kids[i]];
            node->lo_x[i] = k->bounds.lo.x, node->lo_y[i] = k->bounds.lo.y, node->lo_z[i] = k->bounds.lo.z;
            node->hi_x[i] = k->bounds.hi.x, node->hi_y[i] = k->bounds.hi.y, node->hi_z[i] = k->bounds.hi.z;
            node->child_mask |= (uint8_t)(1u << i);
            node->slot_mask |= (uint8_t)(1u << i);
            if (k->count > 0 && (out->kind == WBVH_POINTS || out->kind == WBVH_MESH)) {
                /* a range of the kind's points / triangles */
                node->child[i] = k->first;
                node->leaf_blocks[i] = (uint8_t)k->count;
            } else if (k->count > 0) {
                node->child[i] = emit_leaf(c, k, &node->leaf_blocks[i]);
            } else {
                node->child[i] = out->node_count++;
                todo_binary[todo] = kids[i];
                todo_wide[todo++] = node->child[i];
            }
        }
    }
    free(todo_binary);
    free(todo_wide);
    return true;
}

static bool build(wbvh *out, wbvh_kind kind, const bvh *binary, size_t block_bytes, fill_lane_fn fill,
                  const void *source, const uint32_t *prim_ids, tess_error *err)
{
    memset(out, 0, sizeof *out);
    out->kind = kind;
    /* blocks (points) never outnumber primitives: the bound keeps every leaf reference exact */
    if (binary->prim_count >= WBVH_MAX_LEAF_FIRST)
        return tess_error_set(err, "wbvh: %u primitives in one geometry (fewer than %u fit its tree; split it)",
                              binary->prim_count, WBVH_MAX_LEAF_FIRST);
    collapse c = {binary, out, block_bytes, fill, source, prim_ids};
    if (!run_collapse(&c, err)) {
        wbvh_finish(out);
        return false;
    }
    return true;
}

static size_t block_bytes_of(wbvh_kind kind)
{
    switch (kind) {
    case WBVH_SPHERES: return sizeof(wbvh_sphere_block);
    case WBVH_PRIMS:
    case WBVH_INSTANCES: return sizeof(wbvh_prim_block);
    case WBVH_POINTS:
    case WBVH_MESH: return 0;
    }
    return sizeof(wbvh_prim_block);
}

bool wbvh_build_mesh(wbvh *out, const bvh *binary, const geometry_ops *ops, const void *data,
                     const geometry_mesh_arrays *arrays, tess_error *err)
{
    for (uint32_t i = 0; i < binary->node_count; i++)
        if (binary->nodes[i].count > BVH_LEAF_DEFAULT)
            return tess_error_set(err, "wbvh: a leaf of %u triangles (at most %d)", binary->nodes[i].count,
                                  BVH_LEAF_DEFAULT);
    if (!build(out, WBVH_MESH, binary, 0, NULL, NULL, NULL, err))
        return false;
    out->mesh = *arrays;
    out->ops = ops;
    out->data = data;
    return true;
}

bool wbvh_build(wbvh *out, const bvh *binary, const geometry_ops *ops, const void *data, const uint32_t *prim_ids,
                tess_error *err)
{
    wbvh_kind kind = ops->leaf == GEOMETRY_LEAF_SPHERES ? WBVH_SPHERES : WBVH_PRIMS;
    fill_lane_fn fill = kind == WBVH_PRIMS ? fill_prim_id : ops->fill_lane;
    if (!build(out, kind, binary, block_bytes_of(kind), fill, data, prim_ids, err))
        return false;
    out->ops = ops;
    out->data = data;
    return true;
}

/* Crop ranges of every child slot, children before parents (a child node's
 * index is above its parent's: the collapse numbers them as it goes down). */
static bool crop_ranges(wbvh *w, tess_error *err)
{
    size_t slots = (size_t)w->node_count * WBVH_WIDTH;
    w->crop_lo = malloc((slots + 1) * sizeof *w->crop_lo);
    w->crop_hi = malloc((slots + 1) * sizeof *w->crop_hi);
    if (!w->crop_lo || !w->crop_hi)
        return tess_error_set(err, "wbvh: out of memory for the crop ranges of %u nodes", w->node_count);
    const float *value = w->points.crop_value;
    for (uint32_t k = w->node_count; k-- > 0;) {
        const wbvh_node *n = &w->nodes[k];
        for (int i = 0; i < WBVH_WIDTH; i++) {
            float lo = INFINITY, hi = -INFINITY;
            if (n->slot_mask >> i & 1u) {
                if (n->leaf_blocks[i]) {
                    for (uint32_t p = n->child[i]; p < n->child[i] + n->leaf_blocks[i]; p++)
                        lo = value[p] < lo ? value[p] : lo, hi = value[p] > hi ? value[p] : hi;
                } else {
                    const size_t c = (size_t)n->child[i] * WBVH_WIDTH;
                    for (int j = 0; j < WBVH_WIDTH; j++)
                        lo = w->crop_lo[c + j] < lo ? w->crop_lo[c + j] : lo,
                        hi = w->crop_hi[c + j] > hi ? w->crop_hi[c + j] : hi;
                }
            }
            w->crop_lo[(size_t)k * WBVH_WIDTH + i] = lo;
            w->crop_hi[(size_t)k * WBVH_WIDTH + i] = hi;
        }
    }
    return true;
}

bool wbvh_build_points(wbvh *out, const bvh *binary, const geometry_points *points, tess_error *err)
{
    for (uint32_t i = 0; i < binary->node_count; i++)
        if (binary->nodes[i].count > WBVH_POINTS_LEAF_MAX)
            return tess_error_set(err, "wbvh: a leaf of %u points (at most %d)", binary->nodes[i].count,
                                  WBVH_POINTS_LEAF_MAX);
    if (!build(out, WBVH_POINTS, binary, 0, NULL, NULL, NULL, err))
        return false;
    out->points = *points;
    if (points->crop_value && !crop_ranges(out, err)) {
        wbvh_finish(out);
        return false;
    }
    return true;
}

/* An instance level's parent and leaf_node indices (wbvh.h), all stale. */
static bool index_instances(wbvh *w, uint32_t instance_count, tess_error *err)
{
    w->instance_count = instance_count;
    w->parent = malloc(((size_t)w->node_count + 1) * sizeof *w->parent);
    w->stale = malloc((size_t)w->node_count + 1);
    w->leaf_node = malloc(((size_t)instance_count + 1) * sizeof *w->leaf_node);
    if (!w->parent || !w->stale || !w->leaf_node)
        return tess_error_set(err, "wbvh: out of memory indexing %u instances", instance_count);
    memset(w->stale, 1, (size_t)w->node_count);
    for (uint32_t i = 0; i < instance_count; i++)
        w->leaf_node[i] = UINT32_MAX;
    if (w->node_count > 0)
        w->parent[0] = UINT32_MAX;
    const wbvh_prim_block *blocks = w->blocks;
    for (uint32_t k = 0; k < w->node_count; k++) {
        const wbvh_node *n = &w->nodes[k];
        for (int i = 0; i < WBVH_WIDTH; i++) {
            if (!(n->slot_mask >> i & 1u))
                continue;
            if (!n->leaf_blocks[i]) {
                w->parent[n->child[i]] = k;
                continue;
            }
            for (uint32_t blk = n->child[i]; blk < n->child[i] + n->leaf_blocks[i]; blk++)
                for (int lane = 0; lane < WBVH_BLOCK; lane++)
                    if (blocks[blk].prim_id[lane] < instance_count)
                        w->leaf_node[blocks[blk].prim_id[lane]] = k;
        }
    }
    return true;
}

bool wbvh_build_instances(wbvh *out, const bvh *binary, const wbvh_instance *instances, const atomic_uchar *hidden,
                          tess_error *err)
{
    if (!build(out, WBVH_INSTANCES, binary, sizeof(wbvh_prim_block), fill_prim_id, NULL, NULL, err))
        return false;
    out->instances = instances;
    out->hidden = hidden;
    if (!index_instances(out, binary->prim_count, err)) {
        wbvh_finish(out);
        return false;
    }
    return true;
}

static void set_slot(wbvh_node *n, int i, aabb b)
{
    n->lo_x[i] = b.lo.x, n->lo_y[i] = b.lo.y, n->lo_z[i] = b.lo.z;
    n->hi_x[i] = b.hi.x, n->hi_y[i] = b.hi.y, n->hi_z[i] = b.hi.z;
    if (aabb_is_empty(b))
        n->child_mask &= (uint8_t)~(1u << i);
    else
        n->child_mask |= (uint8_t)(1u << i);
}

/* The refit's union of boxes. Plain compares, not aabb_grow's fminf/fmaxf
 * (library calls for their NaN rules, which a refit of finite or empty boxes
 * does not need): the refit of 100k instances spent a third of its time in
 * them. */
static inline float min_f(float a, float b) { return b < a ? b : a; }
static inline float max_f(float a, float b) { return b > a ? b : a; }
static inline aabb grow(aabb b, aabb o)
{
    return (aabb){v3(min_f(b.lo.x, o.lo.x), min_f(b.lo.y, o.lo.y), min_f(b.lo.z, o.lo.z)),
                  v3(max_f(b.hi.x, o.hi.x), max_f(b.hi.y, o.hi.y), max_f(b.hi.z, o.hi.z))};
}

static aabb node_box(const wbvh_node *n)
{
    aabb b = aabb_empty();
    for (int i = 0; i < WBVH_WIDTH; i++)
        if (n->child_mask >> i & 1u)
            b = grow(b, (aabb){v3(n->lo_x[i], n->lo_y[i], n->lo_z[i]), v3(n->hi_x[i], n->hi_y[i], n->hi_z[i])});
    return b;
}

/* Recompute node k's slots from its children's boxes and its leaves'
 * instances (hidden ones left out). */
static void refit_node(wbvh *w, uint32_t k, const aabb *instance_bounds)
{
    const wbvh_prim_block *blocks = w->blocks;
    wbvh_node *n = &w->nodes[k];
    for (int i = 0; i < WBVH_WIDTH; i++) {
        if (!(n->slot_mask >> i & 1u))
            continue;
        aabb b = aabb_empty();
        if (n->leaf_blocks[i]) {
            for (uint32_t blk = n->child[i]; blk < n->child[i] + n->leaf_blocks[i]; blk++)
                for (int lane = 0; lane < WBVH_BLOCK; lane++) {
                    uint32_t id = blocks[blk].prim_id[lane];
                    if (id != RAY_INVALID_ID && !atomic_load_explicit(&w->hidden[id], memory_order_relaxed))
                        b = grow(b, instance_bounds[id]);
                }
        } else {
            b = node_box(&w->nodes[n->child[i]]);
        }
        set_slot(n, i, b);
    }
}

void wbvh_mark_instances(wbvh *w, uint32_t first, uint32_t count)
{
    if (!w->stale || first >= w->instance_count)
        return;
    uint32_t end = count > w->instance_count - first ? w->instance_count : first + count;
    for (uint32_t id = first; id < end; id++)
        /* a stale node's ancestors are stale already: stop there */
        for (uint32_t k = w->leaf_node[id]; k != UINT32_MAX && !w->stale[k]; k = w->parent[k])
            w->stale[k] = 1;
}

bool wbvh_refit_stale(wbvh *w, const aabb *instance_bounds)
{
    if (!w->stale || w->node_count == 0 || !w->stale[0]) /* anything stale has the root stale */
        return false;
    /* children always have larger indices than their parents (the collapse
     * numbers them as it goes down), so one backward sweep sees every child
     * before its parent */
    for (uint32_t k = w->node_count; k-- > 0;)
        if (w->stale[k]) {
            refit_node(w, k, instance_bounds);
            w->stale[k] = 0;
        }
    return true;
}

void wbvh_refit_instances(wbvh *w, const aabb *instance_bounds)
{
    for (uint32_t k = w->node_count; k-- > 0;)
        refit_node(w, k, instance_bounds);
    if (w->stale)
        memset(w->stale, 0, (size_t)w->node_count);
}

void wbvh_finish(wbvh *w)
{
    if (!w)
        return;
    if (w->borrowed) {
        memset(w, 0, sizeof *w);
        return;
    }
    free(w->crop_lo);
    free(w->crop_hi);
    free(w->nodes);
    free(w->blocks);
    free(w->parent);
    free(w->leaf_node);
    free(w->stale);
    memset(w, 0, sizeof *w);
}

size_t wbvh_bytes(const wbvh *w)
{
    size_t bytes = (size_t)w->node_count * sizeof(wbvh_node) + (size_t)w->block_count * block_bytes_of(w->kind);
    if (w->stale) /* the instance level's refit indices */
        bytes += (size_t)w->node_count * (sizeof *w->parent + sizeof *w->stale) +
                 (size_t)w->instance_count * sizeof *w->leaf_node;
    if (w->crop_lo)
        bytes += (size_t)w->node_count * WBVH_WIDTH * 2 * sizeof(float);
    return bytes;
}
