/* test_next_hit.c - next-hit queries (accel_intersect_after, PACKET_AFTER_HIT):
 * walking a ray's surfaces one by one visits every crossing of every
 * primitive exactly once, in (t, geom_id, prim_id) order, coplanar faces
 * included; single rays and packets of every width, on every instruction set,
 * give the same walk bit for bit as a brute-force list of all crossings.
 * Scenes are generated here. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "isa_skip.h"
#include "engine/scene/accel.h"
#include "engine/accel/intersect.h"
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
static float rng_range(float lo, float hi) { return lo + (hi - lo) * rng_unit(); }

static bool same_hit(hit a, hit b) { return memcmp(&a, &b, sizeof a) == 0; }

static bool hit_after(hit h, hit bound)
{
    return h.t > bound.t ||
           (h.t == bound.t && (h.geom_id > bound.geom_id || (h.geom_id == bound.geom_id && h.prim_id > bound.prim_id)));
}

static bool hit_before(hit a, hit b) { return hit_after(b, a); }

/* The definition: over every crossing of every primitive of every instance
 * (a kind's scalar `intersect` asked again from each crossing it reported,
 * so a sphere gives both), the smallest in (t, geom_id, prim_id) order that
 * comes after `bound` (NULL: no bound) within the ray's interval. */
static hit brute_next(const scene *s, const ray *r, const hit *bound)
{
    hit best = hit_none();
    for (uint32_t i = 0; i < s->instance_count; i++) {
        const scene_instance *inst = &s->instances[i];
        const scene_geometry *g = scene_instance_geometry(s, i);
        ray local = inst->identity ? *r : affine3_ray(&inst->to_object, r);
        uint32_t n = g->ops->prim_count(g->data);
        for (uint32_t p = 0; p < n; p++) {
            ray q = local;
            float t, u, v;
            while (g->ops->intersect(g->data, p, &q, &t, &u, &v)) {
                hit h = {.t = t, .u = u, .v = v, .prim_id = p, .geom_id = i};
                if ((!bound || hit_after(h, *bound)) && hit_before(h, best))
                    best = h;
                q.t_near = t;
                if (!(q.t_near < q.t_far))
                    break;
            }
        }
    }
    return best;
}

static void add_quad(mesh *m, float z, float half)
{
    uint32_t b = m->vertex_count;
    cr_assert(mesh_add_vertex(m, -half, -half, z) && mesh_add_vertex(m, half, -half, z) &&
              mesh_add_vertex(m, half, half, z) && mesh_add_vertex(m, -half, half, z));
    cr_assert(mesh_add_triangle(m, b, b + 1, b + 2) && mesh_add_triangle(m, b, b + 2, b + 3));
}

/* Coplanar stacks: three meshes with the same quad at z = 0 (one of them
 * holding it twice), parallel quads at z = -1 and -2, spheres crossing the
 * planes, and random triangles; then some of it placed again by transforms. */
static scene *make_stack_scene(bool placed)
{
    scene *s = scene_create();
    cr_assert(s);
    material mat = material_default();
    uint32_t m = (uint32_t)scene_add_material(s, &mat);
    for (int k = 0; k < 3; k++) {
        mesh *q = mesh_create();
        cr_assert(q);
        add_quad(q, 0.f, 4.f);
        if (k == 1)
            add_quad(q, 0.f, 4.f);
        add_quad(q, -1.f - (float)k, 4.f);
        cr_assert(scene_add_mesh(s, q, m, "stack") >= 0);
    }
    mesh *soup = mesh_create();
    cr_assert(soup);
    for (int i = 0; i < 400; i++) {
        vec3 c = v3(rng_range(-4.f, 4.f), rng_range(-4.f, 4.f), rng_range(-4.f, 3.f));
        uint32_t b = soup->vertex_count;
        for (int k = 0; k < 3; k++)
            cr_assert(mesh_add_vertex(soup, c.x + rng_range(-1.f, 1.f), c.y + rng_range(-1.f, 1.f),
                                      c.z + rng_range(-1.f, 1.f)));
        cr_assert(mesh_add_triangle(soup, b, b + 1, b + 2));
    }
    cr_assert(scene_add_mesh(s, soup, m, "soup") >= 0);
    for (int i = 0; i < 40; i++)
        cr_assert(scene_add_sphere(s, v3(rng_range(-4.f, 4.f), rng_range(-4.f, 4.f), rng_range(-3.f, 2.f)),
                                   rng_range(0.1f, 1.2f), m) >= 0);
    if (placed) {
        affine3 up = {{1.f, 0.f, 0.f, 0.5f, 0.f, 0.8f, -0.6f, 0.f, 0.f, 0.6f, 0.8f, 2.f}};
        cr_assert(scene_add_instance(s, 0, &up, SCENE_NO_PART) >= 0);
        affine3 squash = {{1.5f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 1.f, 0.f, 0.f, 0.5f, -0.5f}};
        cr_assert(scene_add_instance(s, s->instances[s->sphere_instance].geometry, &squash, SCENE_NO_PART) >= 0);
    }
    return s;
}

static ray random_ray(int i)
{
    ray r = {v3(rng_range(-3.f, 3.f), rng_range(-3.f, 3.f), 8.f), v3(rng_range(-.3f, .3f), rng_range(-.3f, .3f), -1.f),
             0.f, FLT_MAX};
    if (i % 3 == 0) /* straight down on the grid of the quads' diagonal: exact ties between faces */
        r = (ray){v3((float)(int)rng_range(-3.f, 3.f) * 0.5f, (float)(int)rng_range(-3.f, 3.f) * 0.5f, 8.f),
                  v3(0.f, 0.f, -1.f), 0.f, FLT_MAX};
    if (i % 5 == 1) { /* from inside, any direction, a finite interval */
        r.org = v3(rng_range(-3.f, 3.f), rng_range(-3.f, 3.f), rng_range(-3.f, 3.f));
        r.dir = v3(rng_range(-1.f, 1.f), rng_range(-1.f, 1.f), rng_range(-1.f, 1.f));
        r.t_near = rng_range(0.f, 0.5f);
        r.t_far = rng_range(2.f, 20.f);
    }
    return r;
}

#define WALK_MAX 64

/* A ray's walk by the brute force: its crossings in order; returns how many. */
static int brute_walk(const scene *s, const ray *r, hit walk[WALK_MAX])
{
    int n = 0;
    hit h = brute_next(s, r, NULL);
    while (h.t != INFINITY && n < WALK_MAX) {
        walk[n++] = h;
        h = brute_next(s, r, &walk[n - 1]);
    }
    return n;
}

static void walks_match(scene *s)
{
    tess_error err = {{0}};
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    enum { RAYS = 1500 };
    ray *list = malloc(sizeof(ray) * RAYS);
    hit(*want)[WALK_MAX] = malloc(sizeof(hit[WALK_MAX]) * RAYS);
    int *length = malloc(sizeof(int) * RAYS);
    cr_assert(list && want && length);
    long crossings = 0, ties = 0;
    for (int i = 0; i < RAYS; i++) {
        list[i] = random_ray(i);
        length[i] = brute_walk(s, &list[i], want[i]);
        crossings += length[i];
        for (int k = 1; k < length[i]; k++)
            ties += want[i][k].t == want[i][k - 1].t;
    }
    cr_assert(ties > 100, "the scene should give coplanar ties: %ld", ties);
    const char *isas[] = {"sse2", "avx2", "avx512"};
    for (size_t k = 0; k < sizeof isas / sizeof isas[0]; k++) {
        if (isa_skip_note(isas[k]))
            continue;
        cr_assert(accel_use_isa(a, isas[k]), "%s: usable but refused", isas[k]);
        long mismatches = 0;
        for (int i = 0; i < RAYS; i++) { /* single rays */
            hit h;
            int n = 0;
            bool found = accel_intersect(a, &list[i], &h);
            while (found && n < WALK_MAX) {
                mismatches += n >= length[i] || !same_hit(h, want[i][n]);
                hit prev = h;
                n++;
                found = accel_intersect_after(a, &list[i], &prev, &h);
            }
            mismatches += n != length[i];
        }
        static ray_packet p; /* packets of every width, every ray walking at its own pace */
        int next = 0;
        for (uint32_t width = 1; next < RAYS; width = width % 64 + 1) {
            uint32_t count = (uint32_t)(RAYS - next) < width ? (uint32_t)(RAYS - next) : width;
            int step[64] = {0};
            hit last[64];
            uint64_t walking = packet_span_mask(0, count);
            for (int round = 0; walking && round <= WALK_MAX; round++) {
                packet_reset(&p, count, 0);
                for (uint32_t i = 0; i < count; i++) {
                    packet_set_ray(&p, i, &list[next + (int)i]);
                    if (round > 0 && (walking >> i & 1u))
                        packet_set_after(&p, i, &last[i]);
                }
                p.active = walking;
                packet_detect_facts(&p);
                accel_intersect_packet(a, packet_whole(&p));
                for (uint32_t i = 0; i < count; i++) {
                    if (!(walking >> i & 1u))
                        continue;
                    hit h = packet_get_hit(&p, i);
                    int w = next + (int)i;
                    if (h.t == INFINITY) {
                        mismatches += step[i] != length[w];
                        walking &= ~(1ull << i);
                        continue;
                    }
                    mismatches += step[i] >= length[w] || !same_hit(h, want[w][step[i]]);
                    last[i] = h;
                    step[i]++;
                }
            }
            next += (int)count;
        }
        cr_log_info("%s: %d rays, %ld crossings (%ld coplanar ties): %ld mismatches", isas[k], RAYS, crossings, ties,
                    mismatches);
        cr_expect_eq(mismatches, 0, "%s: next-hit walks differ from the brute force in %ld places", isas[k],
                     mismatches);
    }
    free(list);
    free(want);
    free(length);
    accel_destroy(a);
    scene_destroy(s);
}

Test(next_hit, walks_every_crossing_once_in_order, .timeout = 240)
{
    rng_state = 0x51ED270B27F3A8C1ull;
    walks_match(make_stack_scene(false));
}

Test(next_hit, walks_through_transformed_instances, .timeout = 240)
{
    rng_state = 0x7A3C5E9F1B2D4C6Eull;
    walks_match(make_stack_scene(true));
}

/* Straight down through the coplanar stack: the three quads at z = 0 (four
 * faces: mesh 1 holds two) come in (geom, prim) order, then the parallel ones. */
Test(next_hit, coplanar_faces_in_id_order)
{
    rng_state = 3;
    scene *s = scene_create();
    material mat = material_default();
    uint32_t m = (uint32_t)scene_add_material(s, &mat);
    for (int k = 0; k < 3; k++) {
        mesh *q = mesh_create();
        add_quad(q, 0.f, 4.f);
        if (k == 1)
            add_quad(q, 0.f, 4.f);
        add_quad(q, -1.f - (float)k, 4.f);
        cr_assert(scene_add_mesh(s, q, m, "stack") >= 0);
    }
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    ray r = {v3(1.f, 2.f, 5.f), v3(0.f, 0.f, -1.f), 0.f, FLT_MAX};
    /* (x, y) = (1, 2) is in each quad's second triangle (b, b+2, b+3) */
    const struct { float t; uint32_t geom, prim; } expected[] = {
        {5.f, 0, 1}, {5.f, 1, 1}, {5.f, 1, 3}, {5.f, 2, 1}, {6.f, 0, 3}, {7.f, 1, 5}, {8.f, 2, 3},
    };
    hit h;
    bool found = accel_intersect(a, &r, &h);
    for (size_t i = 0; i < sizeof expected / sizeof expected[0]; i++) {
        cr_assert(found, "crossing %zu missing", i);
        cr_expect(h.t == expected[i].t && h.geom_id == expected[i].geom && h.prim_id == expected[i].prim,
                  "crossing %zu: t %g geom %u prim %u, want t %g geom %u prim %u", i, (double)h.t, h.geom_id, h.prim_id,
                  (double)expected[i].t, expected[i].geom, expected[i].prim);
        hit prev = h;
        found = accel_intersect_after(a, &r, &prev, &h);
    }
    cr_expect(!found, "nothing after the last plane");
    /* one instance alone: mesh 1's faces only */
    hit prev;
    cr_assert(accel_intersect_instance(a, 1, &r, NULL, &h));
    cr_expect(h.geom_id == 1 && h.prim_id == 1 && h.t == 5.f);
    prev = h;
    cr_assert(accel_intersect_instance(a, 1, &r, &prev, &h));
    cr_expect(h.geom_id == 1 && h.prim_id == 3 && h.t == 5.f);
    prev = h;
    cr_assert(accel_intersect_instance(a, 1, &r, &prev, &h));
    cr_expect(h.geom_id == 1 && h.prim_id == 5 && h.t == 7.f);
    prev = h;
    cr_expect(!accel_intersect_instance(a, 1, &r, &prev, &h));
    accel_destroy(a);
    scene_destroy(s);
}

/* A sphere is crossed twice: in and out. */
Test(next_hit, sphere_front_and_back)
{
    scene *s = scene_create();
    material mat = material_default();
    uint32_t m = (uint32_t)scene_add_material(s, &mat);
    cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 0.f), 1.f, m) >= 0);
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    ray r = {v3(0.f, 0.f, 5.f), v3(0.f, 0.f, -1.f), 0.f, FLT_MAX};
    hit h, prev;
    cr_assert(accel_intersect(a, &r, &h));
    cr_expect_float_eq(h.t, 4.f, 1e-6f);
    prev = h;
    cr_assert(accel_intersect_after(a, &r, &prev, &h));
    cr_expect_float_eq(h.t, 6.f, 1e-6f);
    prev = h;
    cr_expect(!accel_intersect_after(a, &r, &prev, &h));
    accel_destroy(a);
    scene_destroy(s);
}
