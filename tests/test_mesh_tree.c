/* test_mesh_tree.c - a mesh put in its tree's order (mesh_tree.h): the
 * in-place permutations keep every triangle's corners and attributes, the
 * tree's leaves are ranges that cover each triangle that can be hit once,
 * the ones that cannot be hit come last, and a second accel reuses the
 * tree without reordering again. Meshes are generated here. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/accel/intersect.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/geometry/triangles/mesh_tree.h"
#include "engine/scene/scene.h"

static uint64_t rng_state;
static uint32_t rng_u32(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (uint32_t)((rng_state * 0x2545F4914F6CDD1Dull) >> 32);
}
static float rng_unit(void) { return (float)(rng_u32() >> 8) * (1.f / 16777216.f); }

/* nv random vertices (with normals and colours), nt triangles over them;
 * every 7th triangle degenerate (a repeated corner) when `degenerate`. */
static mesh *random_mesh(uint32_t nv, uint32_t nt, bool degenerate)
{
    mesh *m = mesh_create();
    cr_assert(m && mesh_reserve_vertices(m, nv) && mesh_enable_normals(m) && mesh_enable_colors(m));
    for (uint32_t v = 0; v < nv; v++) {
        cr_assert(mesh_add_vertex(m, rng_unit() * 10.f, rng_unit() * 10.f, rng_unit() * 10.f));
        for (int k = 0; k < 3; k++) {
            m->normals[3 * v + (uint32_t)k] = rng_unit();
            m->colors[3 * v + (uint32_t)k] = rng_unit();
        }
    }
    cr_assert(mesh_reserve_triangles(m, nt) && mesh_enable_triangle_materials(m));
    for (uint32_t t = 0; t < nt; t++) {
        uint32_t a = rng_u32() % nv, b = rng_u32() % nv, c = rng_u32() % nv;
        if (degenerate && t % 7 == 3)
            c = a;
        cr_assert(mesh_add_triangle(m, a, b, c));
        m->triangle_material[t] = t; /* names the triangle: follows it through every move */
    }
    return m;
}

/* What a triangle is, whatever the numbering: its corners' attributes. */
typedef struct corner_values {
    float v[3][9]; /* per corner: position, normal, colour */
    uint32_t material;
} corner_values;

static corner_values triangle_values(const mesh *m, uint32_t t)
{
    corner_values out;
    for (int c = 0; c < 3; c++) {
        uint32_t v = m->indices[3 * (size_t)t + (size_t)c];
        memcpy(out.v[c], m->positions + 3 * (size_t)v, 3 * sizeof(float));
        memcpy(out.v[c] + 3, m->normals + 3 * (size_t)v, 3 * sizeof(float));
        memcpy(out.v[c] + 6, m->colors + 3 * (size_t)v, 3 * sizeof(float));
    }
    out.material = m->triangle_material[t];
    return out;
}

static corner_values *all_values(const mesh *m)
{
    corner_values *all = malloc(m->triangle_count * sizeof *all);
    cr_assert(all);
    for (uint32_t t = 0; t < m->triangle_count; t++)
        all[t] = triangle_values(m, t);
    return all;
}

Test(mesh_tree, permuting_triangles_moves_each_with_its_corners_and_material)
{
    rng_state = 0x1234567ull;
    const uint32_t nt = 5000;
    mesh *m = random_mesh(1000, nt, false);
    corner_values *before = all_values(m);
    uint32_t *order = malloc(nt * sizeof *order);
    cr_assert(order);
    for (uint32_t i = 0; i < nt; i++)
        order[i] = i;
    for (uint32_t i = nt - 1; i > 0; i--) { /* Fisher-Yates: cycles of every length */
        uint32_t j = rng_u32() % (i + 1), tmp = order[i];
        order[i] = order[j];
        order[j] = tmp;
    }
    cr_assert(mesh_permute_triangles(m, order, 2));
    for (uint32_t i = 0; i < nt; i++) {
        corner_values now = triangle_values(m, i);
        cr_assert(memcmp(&now, &before[order[i]], sizeof now) == 0, "triangle %u is not the old triangle %u", i,
                  order[i]);
    }
    free(order);
    free(before);
    mesh_destroy(m);
}

Test(mesh_tree, renumbering_vertices_keeps_triangles_and_numbers_by_first_use)
{
    rng_state = 0xBADC0FFEEull;
    mesh *m = random_mesh(3000, 2000, false); /* some vertices unused */
    corner_values *before = all_values(m);
    uint32_t nv = m->vertex_count;
    cr_assert(mesh_renumber_vertices(m, 2));
    cr_assert_eq(m->vertex_count, nv);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        corner_values now = triangle_values(m, t);
        cr_assert(memcmp(&now, &before[t], sizeof now) == 0, "triangle %u changed", t);
    }
    /* walking the corners, each vertex met for the first time is the next number */
    uint32_t next = 0;
    for (size_t c = 0; c < 3 * (size_t)m->triangle_count; c++) {
        cr_assert_leq(m->indices[c], next, "corner %zu uses vertex %u before %u", c, m->indices[c], next);
        if (m->indices[c] == next)
            next++;
    }
    cr_assert_lt(next, nv, "this mesh has unused vertices, numbered after the used ones");
    free(before);
    mesh_destroy(m);
}

/* Leaves of the tree below node `n`: mark each triangle they hold. */
static void mark_leaves(const wbvh *w, uint32_t n, uint32_t *seen)
{
    const wbvh_node *node = &w->nodes[n];
    for (int i = 0; i < WBVH_WIDTH; i++) {
        if (!(node->slot_mask >> i & 1u))
            continue;
        if (node->leaf_blocks[i]) {
            cr_assert_leq(node->leaf_blocks[i], BVH_LEAF_DEFAULT);
            for (uint32_t t = node->child[i]; t < node->child[i] + node->leaf_blocks[i]; t++)
                seen[t]++;
        } else {
            mark_leaves(w, node->child[i], seen);
        }
    }
}

Test(mesh_tree, leaves_are_ranges_covering_each_hittable_triangle_once_and_the_rest_come_last)
{
    rng_state = 0xFEEDull;
    const uint32_t nt = 4000;
    mesh *m = random_mesh(2500, nt, true);
    corner_values *before = all_values(m);
    scene *s = scene_create();
    material mat = material_default();
    int mi = scene_add_material(s, &mat);
    cr_assert(scene_add_mesh(s, m, (uint32_t)mi, "soup") >= 0);
    tess_error err = {{0}};
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    scene_mesh *sm = s->meshes[0];
    const wbvh *tree = atomic_load(&sm->tree);
    cr_assert(tree && tree->kind == WBVH_MESH);
    uint32_t *seen = calloc(nt, sizeof *seen);
    cr_assert(seen);
    mark_leaves(tree, 0, seen);
    uint32_t hittable = 0;
    for (uint32_t t = 0; t < nt; t++) {
        const uint32_t *idx = m->indices + 3 * (size_t)t;
        const float *p0 = m->positions + 3 * idx[0], *p1 = m->positions + 3 * idx[1], *p2 = m->positions + 3 * idx[2];
        bool degenerate = intersect_triangle_degenerate(v3(p0[0], p0[1], p0[2]), v3(p1[0], p1[1], p1[2]),
                                                        v3(p2[0], p2[1], p2[2]));
        if (!degenerate) {
            cr_assert_eq(t, hittable, "triangle %u can be hit but follows one that cannot", t);
            cr_assert_eq(seen[t], 1u, "triangle %u is in %u leaves", t, seen[t]);
            hittable++;
        } else {
            cr_assert_eq(seen[t], 0u, "degenerate triangle %u is in a leaf", t);
        }
    }
    /* every 7th was made degenerate; a random one may repeat a corner too */
    cr_assert_geq(nt - hittable, (nt + 3) / 7, "%u degenerate triangles", nt - hittable);
    /* the mesh holds the same triangles (materials name them), each once */
    uint8_t *found = calloc(nt, 1);
    cr_assert(found);
    for (uint32_t t = 0; t < nt; t++) {
        corner_values now = triangle_values(m, t);
        cr_assert_lt(now.material, nt);
        cr_assert(memcmp(&now, &before[now.material], sizeof now) == 0, "triangle %u lost its corners", t);
        cr_assert_eq(found[now.material]++, 0, "old triangle %u is there twice", now.material);
    }

    /* a second accel borrows the same tree; the mesh is not moved again */
    uint32_t *indices_then = malloc(3 * (size_t)nt * sizeof *indices_then);
    cr_assert(indices_then);
    memcpy(indices_then, m->indices, 3 * (size_t)nt * sizeof *indices_then);
    accel *again = accel_build(s, 1, &err);
    cr_assert(again, "%s", err.msg);
    cr_assert_eq(atomic_load(&sm->tree), tree);
    cr_assert(memcmp(indices_then, m->indices, 3 * (size_t)nt * sizeof *indices_then) == 0);
    /* both see the same hits, ids included */
    for (int i = 0; i < 2000; i++) {
        ray r = {v3(rng_unit() * 10.f, rng_unit() * 10.f, -5.f), v3(rng_unit() - 0.5f, rng_unit() - 0.5f, 1.f), 0.f,
                 INFINITY};
        hit h1, h2;
        bool b1 = accel_intersect(a, &r, &h1), b2 = accel_intersect(again, &r, &h2);
        cr_assert_eq(b1, b2);
        cr_assert(!b1 || memcmp(&h1, &h2, sizeof h1) == 0, "ray %d: the two accels disagree", i);
    }
    accel_destroy(again);
    accel_destroy(a);
    scene_destroy(s);
    free(indices_then);
    free(found);
    free(seen);
    free(before);
}
