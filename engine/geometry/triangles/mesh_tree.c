#include "mesh_tree.h"

#include <pthread.h>
#include <stdlib.h>

#include "engine/accel/bvh.h"
#include "engine/accel/bvh_spatial.h"
#include "mesh.h"
#include "mesh_cache.h"
#include "engine/base/progress.h"

/* Serialises first builds (rare: once per mesh); the built tree is
 * published through sm->tree with release order, read with acquire. */
static pthread_mutex_t build_lock = PTHREAD_MUTEX_INITIALIZER;

/* The tree's order of all triangles: the leaves' (kept ids in leaf order;
 * with spatial splits a triangle once per leaf holding it), then the ones
 * that can never be hit, in id order. *length: how many. */
static uint32_t *full_order(const bvh *binary, const uint32_t *kept_ids, uint32_t count, uint32_t *length)
{
    uint32_t *order = malloc(((size_t)binary->prim_count + count + 1) * sizeof *order);
    uint8_t *placed = calloc((size_t)count + 1, 1);
    if (!order || !placed) {
        free(order);
        free(placed);
        return NULL;
    }
    uint32_t n = 0;
    for (uint32_t i = 0; i < binary->prim_count; i++) {
        order[n] = kept_ids[binary->prim_order[i]];
        placed[order[n++]] = 1;
    }
    for (uint32_t t = 0; t < count; t++)
        if (!placed[t])
            order[n++] = t;
    free(placed);
    *length = n;
    return order;
}

/* The binary tree: binned SAH over the kept triangles' boxes, or with
 * spatial splits over the triangles themselves (the boxes unused). */
static bool build_binary(scene_mesh *sm, bvh *binary, const aabb *boxes, const uint32_t *kept_ids, uint32_t kept,
                         int threads, tess_error *err)
{
    if (!sm->spatial_splits)
        return bvh_build(binary, boxes, kept, threads, err);
    const mesh *m = sm->mesh;
    if (m->canon) /* a mesh in a spatial tree's order already: never built twice */
        return tess_error_set(err, "mesh '%s': its triangles are already a tree's references", sm->name);
    bvh_triangles tris = {m->positions, m->indices, kept_ids, kept};
    return bvh_build_spatial(binary, &tris, err);
}

static wbvh *build(scene_mesh *sm, int threads, tess_error *err)
{
    mesh *m = sm->mesh;
    aabb *boxes;
    uint32_t *kept_ids, kept;
    if (!geometry_hit_boxes(&geometry_triangles_ops, sm, threads, &boxes, &kept_ids, &kept)) {
        tess_error_set(err, "mesh '%s': out of memory for the bounds of %u triangles", sm->name, m->triangle_count);
        return NULL;
    }
    bvh binary;
    bool ok = build_binary(sm, &binary, boxes, kept_ids, kept, threads, err);
    free(boxes);
    if (!ok) {
        free(kept_ids);
        return NULL;
    }
    uint32_t order_length = 0;
    uint32_t *order = full_order(&binary, kept_ids, m->triangle_count, &order_length);
    free(kept_ids);
    wbvh *tree = calloc(1, sizeof *tree);
    progress report; /* triangles moved, then renumbered: two passes */
    progress_begin(&report, "ordering mesh", 2 * (uint64_t)m->triangle_count, "tri");
    /* a permutation unless spatial splits repeated some triangles */
    if (order && tree)
        ok = order_length == m->triangle_count && !m->canon ? mesh_permute_triangles(m, order, threads)
                                                            : mesh_gather_triangles(m, order, order_length, threads);
    else
        ok = false;
    progress_add(&report, m->triangle_count);
    ok = ok && mesh_renumber_vertices(m, threads);
    progress_add(&report, m->triangle_count);
    progress_end(&report);
    free(order);
    if (!ok) {
        tess_error_set(err, "mesh '%s': out of memory putting %u triangles in order", sm->name, m->triangle_count);
    } else {
        geometry_mesh_arrays arrays = {m->positions, m->indices, m->canon};
        ok = wbvh_build_mesh(tree, &binary, &geometry_triangles_ops, sm, &arrays, err);
    }
    bvh_finish(&binary);
    if (!ok) {
        free(tree);
        return NULL;
    }
    mesh_cache_store(sm, tree);
    return tree;
}

const wbvh *mesh_tree_get(scene_mesh *sm, int threads, tess_error *err)
{
    wbvh *tree = atomic_load_explicit(&sm->tree, memory_order_acquire);
    if (tree)
        return tree;
    pthread_mutex_lock(&build_lock);
    tree = atomic_load_explicit(&sm->tree, memory_order_relaxed);
    if (!tree && (tree = build(sm, threads, err)))
        atomic_store_explicit(&sm->tree, tree, memory_order_release);
    pthread_mutex_unlock(&build_lock);
    return tree;
}

void mesh_tree_release(scene_mesh *sm)
{
    wbvh *tree = atomic_exchange_explicit(&sm->tree, NULL, memory_order_acq_rel);
    if (tree) {
        wbvh_finish(tree);
        free(tree);
    }
}
