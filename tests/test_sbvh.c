/* test_sbvh.c - spatial splits (bvh_spatial.h, scene_mesh.spatial_splits) on
 * generated long thin triangles (a fan of slivers; a strip grid rotated off
 * every axis; stacked layers of both): the builder's leaf boxes contain every
 * point of the triangle parts they stand for, the references stay within
 * the budget and the SAH cost drops; through the engine, single rays and
 * packets find exactly the hits a brute-force test over the triangles finds
 * (bit-exact t, the triangle's one canonical id), next-hit walks meet each
 * crossed triangle once, the build does not depend on the thread count, the
 * structure cache keeps splits and no-splits apart, and a wrong JSON value
 * names its field. */
#define _GNU_SOURCE /* mkdtemp, setenv */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/accel/bvh.h"
#include "engine/accel/bvh_spatial.h"
#include "engine/accel/intersect.h"
#include "engine/geometry/triangles/mesh.h"
#include "engine/geometry/triangles/mesh_cache.h"
#include "engine/accel/packet.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "engine/accel/wbvh.h"

static uint64_t seed;
static float rnd(void) /* uniform in [0, 1) */
{
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return (float)(seed >> 40) / 16777216.f;
}

/* A fan of n slivers around the z axis: each triangle from near the centre
 * out to radius 10, a few thousandths of a radian wide, tilted up and down,
 * so their boxes overlap wildly while the triangles barely touch. */
static mesh *sliver_fan(uint32_t n)
{
    mesh *m = mesh_create();
    cr_assert(m);
    for (uint32_t i = 0; i < n; i++) {
        float a = 6.2831853f * (float)i / (float)n, w = 0.003f, z = 0.3f * sinf(5.f * a);
        uint32_t v = m->vertex_count;
        cr_assert(mesh_add_vertex(m, 0.2f * cosf(a), 0.2f * sinf(a), 0.f) &&
                  mesh_add_vertex(m, 10.f * cosf(a), 10.f * sinf(a), z) &&
                  mesh_add_vertex(m, 10.f * cosf(a + w), 10.f * sinf(a + w), z + 0.01f) &&
                  mesh_add_triangle(m, v, v + 1, v + 2));
    }
    return m;
}

/* A grid of cols x rows long thin quads (each 2 triangles), 40 long and
 * 0.05 wide, rotated about all three axes, lifted by `z`. */
static void add_rotated_strips(mesh *m, int cols, int rows, float z)
{
    const float ca = cosf(0.5f), sa = sinf(0.5f), cb = cosf(0.7f), sb = sinf(0.7f);
    uint32_t base = m->vertex_count;
    for (int r = 0; r <= rows; r++)
        for (int c = 0; c <= cols; c++) {
            float x = 40.f * (float)c / (float)cols - 20.f, y = 0.05f * (float)r - 0.025f * (float)rows;
            /* about z by a, then about x by b */
            float x1 = ca * x - sa * y, y1 = sa * x + ca * y, z1 = z + 0.02f * sinf(0.3f * (float)(r * c));
            cr_assert(mesh_add_vertex(m, x1, cb * y1 - sb * z1, sb * y1 + cb * z1));
        }
    for (int r = 0; r < rows; r++)
        for (int c = 0; c < cols; c++) {
            uint32_t a = base + (uint32_t)(r * (cols + 1) + c), b = a + 1, d = a + (uint32_t)cols + 1, e = d + 1;
            cr_assert(mesh_add_triangle(m, a, b, d) && mesh_add_triangle(m, b, e, d));
        }
}

/* The slivers the suite traces: the fan, and three layers of rotated strips
 * (next-hit walks cross several). */
static mesh *sliver_scene_mesh(void)
{
    mesh *m = sliver_fan(600);
    for (int layer = 0; layer < 3; layer++)
        add_rotated_strips(m, 3, 120, 0.7f * (float)layer);
    return m;
}

static scene *scene_of(mesh *m, bool splits)
{
    scene *s = scene_create();
    cr_assert(s);
    int id = scene_add_mesh(s, m, 0, "slivers");
    cr_assert_geq(id, 0);
    s->meshes[id]->spatial_splits = splits;
    return s;
}

/* The sliver scene with its accel built on `threads` threads. */
static scene *built_scene(bool splits, int threads, accel **out)
{
    scene *s = scene_of(sliver_scene_mesh(), splits);
    tess_error err = {{0}};
    *out = accel_build(s, threads, &err);
    cr_assert(*out, "%s", err.msg);
    return s;
}

/* --- the builder alone --- */

static vec3 corner(const mesh *m, uint32_t t, int k)
{
    const float *p = m->positions + 3 * (size_t)m->indices[3 * (size_t)t + (size_t)k];
    return v3(p[0], p[1], p[2]);
}

static bool box_holds(const aabb *b, double x, double y, double z)
{
    return b->lo.x <= x && x <= b->hi.x && b->lo.y <= y && y <= b->hi.y && b->lo.z <= z && z <= b->hi.z;
}

Test(sbvh, leaf_boxes_cover_every_point_of_every_triangle)
{
    mesh *m = sliver_scene_mesh();
    uint32_t *ids = malloc(m->triangle_count * sizeof *ids);
    for (uint32_t t = 0; t < m->triangle_count; t++)
        ids[t] = t;
    bvh_triangles tris = {m->positions, m->indices, ids, m->triangle_count};
    bvh b;
    tess_error err = {{0}};
    cr_assert(bvh_build_spatial(&b, &tris, &err), "%s", err.msg);
    cr_assert_gt(b.prim_count, m->triangle_count, "slivers get chopped: references %u", b.prim_count);
    cr_assert_leq(b.prim_count, bvh_spatial_reference_budget(m->triangle_count));
    cr_assert_leq(b.depth, BVH_MAX_DEPTH);
    /* leaf of each reference; every triangle in one leaf at least */
    uint32_t *leaf_of = malloc(b.prim_count * sizeof *leaf_of);
    uint32_t *seen = calloc(m->triangle_count, sizeof *seen);
    for (uint32_t i = 0; i < b.node_count; i++) {
        const bvh_node *n = &b.nodes[i];
        if (n->count == 0)
            continue;
        cr_assert_leq(n->count, BVH_LEAF_DEFAULT);
        for (uint32_t k = n->first; k < n->first + n->count; k++) {
            leaf_of[k] = i;
            seen[b.prim_order[k]]++;
        }
    }
    for (uint32_t t = 0; t < m->triangle_count; t++)
        cr_assert_geq(seen[t], 1u, "triangle %u in no leaf", t);
    /* points all over each triangle (corners, edges, inside, in double):
     * some leaf holding the triangle holds the point */
    uint32_t *first_ref = malloc(m->triangle_count * sizeof *first_ref);
    for (uint32_t k = b.prim_count; k-- > 0;)
        first_ref[b.prim_order[k]] = k;
    seed = 11;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        vec3 c[3] = {corner(m, t, 0), corner(m, t, 1), corner(m, t, 2)};
        for (int s = 0; s < 40; s++) {
            double u = s < 3 ? (s == 1) : s < 12 ? rnd() : rnd() * 0.5, v = s < 3 ? (s == 2) : s < 12 ? 0.0 : rnd() * 0.5;
            double w = 1.0 - u - v;
            double x = w * c[0].x + u * c[1].x + v * c[2].x, y = w * c[0].y + u * c[1].y + v * c[2].y,
                   z = w * c[0].z + u * c[1].z + v * c[2].z;
            bool held = false;
            for (uint32_t k = first_ref[t]; k < b.prim_count && !held; k++)
                held = b.prim_order[k] == t && box_holds(&b.nodes[leaf_of[k]].bounds, x, y, z);
            cr_assert(held, "triangle %u: point (%.9g %.9g %.9g) in no leaf box of its references", t, x, y, z);
        }
    }
    free(first_ref);
    free(seen);
    free(leaf_of);
    bvh_finish(&b);
    free(ids);
    mesh_destroy(m);
}

Test(sbvh, splits_lower_the_sah_cost_of_slivers)
{
    mesh *m = sliver_scene_mesh();
    uint32_t *ids = malloc(m->triangle_count * sizeof *ids);
    aabb *boxes = malloc(m->triangle_count * sizeof *boxes);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        ids[t] = t;
        boxes[t] = aabb_grow_point(aabb_grow_point(aabb_grow_point(aabb_empty(), corner(m, t, 0)), corner(m, t, 1)),
                                   corner(m, t, 2));
    }
    bvh plain, split;
    tess_error err = {{0}};
    cr_assert(bvh_build(&plain, boxes, m->triangle_count, 1, &err), "%s", err.msg);
    bvh_triangles tris = {m->positions, m->indices, ids, m->triangle_count};
    cr_assert(bvh_build_spatial(&split, &tris, &err), "%s", err.msg);
    double cost_plain = bvh_sah_cost(&plain), cost_split = bvh_sah_cost(&split);
    cr_assert_lt(cost_split, 0.95 * cost_plain, "SAH cost %g with splits, %g without", cost_split, cost_plain);
    bvh_finish(&plain);
    bvh_finish(&split);
    free(boxes);
    free(ids);
    mesh_destroy(m);
}

Test(sbvh, an_empty_input_gives_an_empty_tree)
{
    bvh b;
    bvh_triangles none = {NULL, NULL, NULL, 0};
    tess_error err = {{0}};
    cr_assert(bvh_build_spatial(&b, &none, &err));
    cr_assert_eq(b.node_count, 0u);
    cr_assert_eq(b.prim_count, 0u);
}

/* --- through the engine --- */

/* Closest hit by testing every stored triangle, ids canonical, ties in t to
 * the lowest id; and when `after` is given only hits after it. */
static bool brute_hit(const mesh *m, const ray *r, const hit *after, hit *out)
{
    ray_derived d = ray_derive(r);
    *out = hit_none();
    bool found = false;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        float th, u, v;
        if (!intersect_triangle(r, &d, corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), &th, &u, &v))
            continue;
        uint32_t id = m->canon ? m->canon[t] : t;
        if (after && !(th > after->t || (th == after->t && id > after->prim_id)))
            continue;
        if (th < out->t || (th == out->t && id < out->prim_id)) {
            *out = (hit){.t = th, .u = u, .v = v, .prim_id = id, .geom_id = 0};
            found = true;
        }
    }
    return found;
}

/* Distinct triangles (canonical ids) the ray crosses, by brute force. */
static int crossed_triangles(const mesh *m, const ray *r)
{
    ray_derived d = ray_derive(r);
    uint8_t *crossed = calloc(m->triangle_count, 1);
    int n = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        float th, u, v;
        if (!intersect_triangle(r, &d, corner(m, t, 0), corner(m, t, 1), corner(m, t, 2), &th, &u, &v))
            continue;
        uint32_t id = m->canon ? m->canon[t] : t;
        n += !crossed[id];
        crossed[id] = 1;
    }
    free(crossed);
    return n;
}

/* A ray from above the slivers to a random point of their plane region. */
static ray random_ray(void)
{
    vec3 org = v3(20.f * rnd() - 10.f, 20.f * rnd() - 10.f, 15.f);
    vec3 to = v3(24.f * rnd() - 12.f, 24.f * rnd() - 12.f, 3.f * rnd() - 1.5f);
    return (ray){org, v3_sub(to, org), 0.f, INFINITY};
}

Test(sbvh, single_rays_hit_what_brute_force_hits)
{
    accel *a;
    scene *s = built_scene(true, 2, &a);
    const mesh *m = s->meshes[0]->mesh;
    cr_assert_not_null(m->canon, "the slivers are stored with repeated copies");
    cr_assert_gt(m->duplicate_count, 0u);
    cr_assert_eq(scene_triangle_count(s), 600u + 3u * 720u, "counted once each");
    seed = 5;
    int hits = 0;
    for (int i = 0; i < 20000; i++) {
        ray r = random_ray();
        hit got, want;
        bool g = accel_intersect(a, &r, &got), w = brute_hit(m, &r, NULL, &want);
        cr_assert_eq(g, w, "ray %d: tree %d, brute force %d", i, g, w);
        if (!w)
            continue;
        hits++;
        cr_assert(got.t == want.t && got.prim_id == want.prim_id, "ray %d: tree t %.9g id %u, brute %.9g id %u", i,
                  (double)got.t, got.prim_id, (double)want.t, want.prim_id);
        cr_assert_eq(m->canon[got.prim_id], got.prim_id, "the id is a first copy");
        cr_assert(accel_occluded(a, &r));
    }
    cr_assert_gt(hits, 5000);
    accel_destroy(a);
    scene_destroy(s);
}

Test(sbvh, packets_match_single_rays_bit_for_bit)
{
    accel *a;
    scene *s = built_scene(true, 1, &a);
    static ray_packet p;
    seed = 9;
    for (int k = 0; k < 300; k++) {
        /* 64 rays from one point through an 8 x 8 patch: they stay together into the leaves */
        vec3 org = v3(20.f * rnd() - 10.f, 20.f * rnd() - 10.f, 15.f);
        vec3 to = v3(24.f * rnd() - 12.f, 24.f * rnd() - 12.f, 0.f);
        ray rays[PACKET_MAX_RAYS];
        packet_reset(&p, PACKET_MAX_RAYS, PACKET_COMMON_ORIGIN);
        for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++) {
            vec3 at = v3_add(to, v3(0.01f * (float)(i % 8), 0.01f * (float)(i / 8), 0.f));
            rays[i] = (ray){org, v3_sub(at, org), 0.f, INFINITY};
            packet_set_ray(&p, i, &rays[i]);
        }
        accel_intersect_packet(a, packet_whole(&p));
        for (uint32_t i = 0; i < PACKET_MAX_RAYS; i++) {
            hit one, in_packet = packet_get_hit(&p, i);
            accel_intersect(a, &rays[i], &one);
            cr_assert(memcmp(&one, &in_packet, sizeof one) == 0, "packet %d ray %u: t %.9g id %u vs %.9g id %u", k, i,
                      (double)in_packet.t, in_packet.prim_id, (double)one.t, one.prim_id);
        }
    }
    accel_destroy(a);
    scene_destroy(s);
}

Test(sbvh, next_hit_walks_meet_each_crossed_triangle_once)
{
    accel *a;
    scene *s = built_scene(true, 2, &a);
    const mesh *m = s->meshes[0]->mesh;
    seed = 21;
    int multi = 0;
    for (int i = 0; i < 3000; i++) {
        ray r = random_ray();
        hit got, want;
        bool more = accel_intersect(a, &r, &got);
        cr_assert_eq(more, brute_hit(m, &r, NULL, &want));
        int layers = 0;
        while (more) {
            layers++;
            cr_assert_lt(layers, 64, "ray %d: a walk that does not end", i);
            hit before = got;
            more = accel_intersect_after(a, &r, &before, &got);
            bool w = brute_hit(m, &r, &before, &want);
            cr_assert_eq(more, w, "ray %d layer %d: tree %d, brute force %d", i, layers, more, w);
            if (more)
                cr_assert(got.t == want.t && got.prim_id == want.prim_id, "ray %d layer %d: %.9g/%u vs %.9g/%u", i,
                          layers, (double)got.t, got.prim_id, (double)want.t, want.prim_id);
        }
        cr_assert_eq(layers, crossed_triangles(m, &r), "ray %d: one layer per triangle crossed", i);
        multi += layers > 1;
    }
    cr_assert_gt(multi, 100, "walks crossed several layers");
    accel_destroy(a);
    scene_destroy(s);
}

Test(sbvh, the_build_does_not_depend_on_the_thread_count)
{
    scene *s1 = scene_of(sliver_scene_mesh(), true), *s2 = scene_of(sliver_scene_mesh(), true);
    tess_error err = {{0}};
    accel *a1 = accel_build(s1, 1, &err), *a2 = accel_build(s2, 2, &err);
    cr_assert(a1 && a2, "%s", err.msg);
    const mesh *m1 = s1->meshes[0]->mesh, *m2 = s2->meshes[0]->mesh;
    cr_assert_eq(m1->triangle_count, m2->triangle_count);
    cr_assert_eq(m1->duplicate_count, m2->duplicate_count);
    cr_assert(memcmp(m1->indices, m2->indices, 3 * sizeof(uint32_t) * m1->triangle_count) == 0);
    cr_assert(memcmp(m1->positions, m2->positions, 3 * sizeof(float) * m1->vertex_count) == 0);
    cr_assert(memcmp(m1->canon, m2->canon, sizeof(uint32_t) * m1->triangle_count) == 0);
    const wbvh *w1 = s1->meshes[0]->tree, *w2 = s2->meshes[0]->tree;
    cr_assert_eq(w1->node_count, w2->node_count);
    cr_assert(memcmp(w1->nodes, w2->nodes, w1->node_count * sizeof(wbvh_node)) == 0);
    accel_destroy(a1);
    accel_destroy(a2);
    scene_destroy(s1);
    scene_destroy(s2);
}

Test(sbvh, a_mesh_without_splits_has_no_canon)
{
    accel *a;
    scene *s = built_scene(false, 2, &a);
    cr_assert_null(s->meshes[0]->mesh->canon);
    cr_assert_null(s->meshes[0]->tree->mesh.canon);
    cr_assert_eq(s->meshes[0]->mesh->triangle_count, 600u + 3u * 720u);
    accel_destroy(a);
    scene_destroy(s);
}

/* --- scene files and the structure cache --- */

static char dir[64];

static void cache_setup(void)
{
    snprintf(dir, sizeof dir, "/tmp/tessera_test_sbvh_XXXXXX");
    cr_assert(mkdtemp(dir));
    char cache[96];
    snprintf(cache, sizeof cache, "%s/cache", dir);
    setenv("TESSERA_CACHE_DIR", cache, 1);
    setenv("TESSERA_CACHE_MIN_BYTES", "0", 1);
    unsetenv("TESSERA_CACHE");
}

static void cache_teardown(void)
{
    char cmd[96];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    cr_assert_eq(system(cmd), 0);
}

static void write_ply(const mesh *m, const char *path)
{
    FILE *f = fopen(path, "w");
    cr_assert(f);
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex %u\nproperty float x\nproperty float y\nproperty float z\n"
               "element face %u\nproperty list uchar int vertex_indices\nend_header\n",
            m->vertex_count, m->triangle_count);
    for (uint32_t v = 0; v < m->vertex_count; v++)
        fprintf(f, "%.9g %.9g %.9g\n", (double)m->positions[3 * v], (double)m->positions[3 * v + 1],
                (double)m->positions[3 * v + 2]);
    for (uint32_t t = 0; t < m->triangle_count; t++)
        fprintf(f, "3 %u %u %u\n", m->indices[3 * t], m->indices[3 * t + 1], m->indices[3 * t + 2]);
    cr_assert_eq(fclose(f), 0);
}

#define CACHE_RAYS 3000

/* Load, build, trace; the mesh's cache state, its repeated copies, its t values. */
static int load_and_trace(const char *path, bool splits, float *t_out, uint32_t *duplicates)
{
    scene_load_options opts = {.spatial_splits = splits};
    tess_error err = {{0}};
    scene *s = scene_load_with(path, &opts, &err);
    cr_assert(s, "%s", err.msg);
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    seed = 3;
    for (int i = 0; i < CACHE_RAYS; i++) {
        ray r = random_ray();
        hit h;
        accel_intersect(a, &r, &h);
        t_out[i] = h.t;
    }
    int state = s->meshes[0]->cache_state;
    *duplicates = s->meshes[0]->mesh->duplicate_count;
    cr_assert_eq(s->meshes[0]->spatial_splits, splits);
    accel_destroy(a);
    scene_destroy(s);
    return state;
}

Test(sbvh, the_cache_keeps_splits_and_no_splits_apart, .init = cache_setup, .fini = cache_teardown)
{
    char path[96];
    snprintf(path, sizeof path, "%s/slivers.ply", dir);
    mesh *m = sliver_scene_mesh();
    write_ply(m, path);
    mesh_destroy(m);
    static float t_built[CACHE_RAYS], t_mapped[CACHE_RAYS], t_plain[CACHE_RAYS];
    uint32_t dup_built, dup_mapped, dup_plain;
    cr_assert_eq(load_and_trace(path, true, t_built, &dup_built), MESH_CACHE_WRITTEN);
    cr_assert_eq(load_and_trace(path, true, t_mapped, &dup_mapped), MESH_CACHE_HIT);
    cr_assert_gt(dup_built, 0u);
    cr_assert_eq(dup_mapped, dup_built, "the mapped mesh keeps its repeated copies");
    cr_assert(memcmp(t_built, t_mapped, sizeof t_built) == 0);
    /* without splits: another key, so built (and written) again, never mapped from the other */
    cr_assert_eq(load_and_trace(path, false, t_plain, &dup_plain), MESH_CACHE_WRITTEN);
    cr_assert_eq(dup_plain, 0u);
    cr_assert(memcmp(t_built, t_plain, sizeof t_built) == 0, "the same surfaces either way");
    cr_assert_eq(load_and_trace(path, false, t_plain, &dup_plain), MESH_CACHE_HIT);
    cr_assert_eq(dup_plain, 0u);
}

Test(sbvh, json_field_turns_splits_on_and_a_wrong_type_names_it, .init = cache_setup, .fini = cache_teardown)
{
    char path[96];
    snprintf(path, sizeof path, "%s/slivers.ply", dir);
    mesh *m = sliver_fan(50);
    write_ply(m, path);
    mesh_destroy(m);
    char json[512], scene_path[96];
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    tess_error err = {{0}};
    snprintf(json, sizeof json, "{\"meshes\": [{\"file\": \"slivers.ply\", \"spatial_splits\": true}]}");
    scene *s = scene_parse_json(scene_path, json, strlen(json), &err);
    cr_assert(s, "%s", err.msg);
    cr_assert(s->meshes[0]->spatial_splits);
    scene_destroy(s);
    /* the caller's default, and an entry that says otherwise */
    scene_load_options on = {.spatial_splits = true};
    snprintf(json, sizeof json, "{\"meshes\": [{\"file\": \"slivers.ply\"}, {\"file\": \"slivers.ply\", "
                                "\"spatial_splits\": false}]}");
    s = scene_parse_json_with(scene_path, json, strlen(json), &on, &err);
    cr_assert(s, "%s", err.msg);
    cr_assert(s->meshes[0]->spatial_splits);
    cr_assert_not(s->meshes[1]->spatial_splits);
    scene_destroy(s);
    snprintf(json, sizeof json, "{\"meshes\": [{\"file\": \"slivers.ply\", \"spatial_splits\": 1}]}");
    s = scene_parse_json(scene_path, json, strlen(json), &err);
    cr_assert_null(s);
    cr_assert(strstr(err.msg, "spatial_splits"), "message names the field: %s", err.msg);
    cr_assert(strstr(err.msg, "boolean"), "and what it wants: %s", err.msg);
}
