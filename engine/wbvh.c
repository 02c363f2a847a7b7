#include "wbvh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "memory.h"
#include "mesh.h"
#include "ray.h"
#include "scene.h"


/* Fills one block lane from a primitive; the block was zeroed, so unused
 * lanes stay degenerate. */
typedef void (*fill_lane_fn)(void *block, int lane, uint32_t prim, const void *source);

static void fill_triangle(void *block, int lane, uint32_t prim, const void *source)
{
    wbvh_tri_block *b = block;
    const mesh *m = source;
    const uint32_t *idx = m->indices + 3 * (size_t)prim;
    const float *p0 = m->positions + 3 * (size_t)idx[0], *p1 = m->positions + 3 * (size_t)idx[1],
                *p2 = m->positions + 3 * (size_t)idx[2];
    b->v0x[lane] = p0[0], b->v0y[lane] = p0[1], b->v0z[lane] = p0[2];
    b->v1x[lane] = p1[0], b->v1y[lane] = p1[1], b->v1z[lane] = p1[2];
    b->v2x[lane] = p2[0], b->v2y[lane] = p2[1], b->v2z[lane] = p2[2];
    b->prim_id[lane] = prim;
}

static void fill_sphere(void *block, int lane, uint32_t prim, const void *source)
{
    wbvh_sphere_block *b = block;
    const sphere_set *s = source;
    b->cx[lane] = s->center_x[prim];
    b->cy[lane] = s->center_y[prim];
    b->cz[lane] = s->center_z[prim];
    b->r[lane] = s->radius[prim];
    b->prim_id[lane] = prim;
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
    /* prim_id is the last member of both block types */
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
    out->blocks = memory_alloc_large(max_blocks * c->block_bytes);
    /* work list: (binary node, wide node) pairs still to fill; at most one per wide node */
    uint32_t *todo_binary = malloc(max_nodes * sizeof(uint32_t)), *todo_wide = malloc(max_nodes * sizeof(uint32_t));
    if (!out->nodes || !out->blocks || !todo_binary || !todo_wide) {
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
            if (k->count > 0) {
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
    collapse c = {binary, out, block_bytes, fill, source, prim_ids};
    if (!run_collapse(&c, err)) {
        wbvh_finish(out);
        return false;
    }
    return true;
}

bool wbvh_build_triangles(wbvh *out, const bvh *binary, const mesh *m, const uint32_t *prim_ids, tess_error *err)
{
    return build(out, WBVH_TRIANGLES, binary, sizeof(wbvh_tri_block), fill_triangle, m, prim_ids, err);
}

bool wbvh_build_spheres(wbvh *out, const bvh *binary, const sphere_set *s, tess_error *err)
{
    return build(out, WBVH_SPHERES, binary, sizeof(wbvh_sphere_block), fill_sphere, s, NULL, err);
}

void wbvh_finish(wbvh *w)
{
    if (!w)
        return;
    free(w->nodes);
    free(w->blocks);
    memset(w, 0, sizeof *w);
}

size_t wbvh_bytes(const wbvh *w)
{
    size_t block_bytes = w->kind == WBVH_TRIANGLES ? sizeof(wbvh_tri_block) : sizeof(wbvh_sphere_block);
    return (size_t)w->node_count * sizeof(wbvh_node) + (size_t)w->block_count * block_bytes;
}
