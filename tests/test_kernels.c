/* test_kernels.c - every instruction set's kernels, single rays and packets
 * of every width, give bit-identical hits; the wide BVH is complete.
 * Scenes are generated here (a random triangle soup, a closed mesh, spheres). */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "isa_skip.h"
#include "engine/scene/accel.h"
#include "engine/accel/intersect.h"
#include "engine/accel/kernels.h"
#include "engine/geometry/particles/particle_kind.h"
#include "engine/scene/scene.h"

/* xorshift64*: a fixed, portable stream so failures reproduce */
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

/* Random triangles in a cube, many small and some large and thin, plus a
 * grid floor whose edges rays will meet exactly; then spheres. */
static scene *make_scene(void)
{
    scene *s = scene_create();
    cr_assert(s);
    material m = material_default();
    int mat = scene_add_material(s, &m);
    mesh *soup = mesh_create();
    cr_assert(soup);
    for (int i = 0; i < 3000; i++) {
        vec3 c = v3(rng_range(-10.f, 10.f), rng_range(-10.f, 10.f), rng_range(-10.f, 10.f));
        float size = i % 10 == 0 ? 4.f : 0.4f;
        uint32_t base = soup->vertex_count;
        for (int k = 0; k < 3; k++)
            cr_assert(mesh_add_vertex(soup, c.x + rng_range(-size, size), c.y + rng_range(-size, size),
                                      c.z + rng_range(-size, size)));
        cr_assert(mesh_add_triangle(soup, base, base + 1, base + 2));
    }
    cr_assert(scene_add_mesh(s, soup, (uint32_t)mat, "soup") >= 0);
    mesh *grid = mesh_create();
    cr_assert(grid);
    const int n = 20;
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++)
            cr_assert(mesh_add_vertex(grid, (float)i - 10.f, -11.f, (float)j - 10.f));
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = (uint32_t)(j * (n + 1) + i), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
            cr_assert(mesh_add_triangle(grid, a, c, b) && mesh_add_triangle(grid, b, c, d));
        }
    cr_assert(scene_add_mesh(s, grid, (uint32_t)mat, "grid") >= 0);
    for (int i = 0; i < 200; i++)
        cr_assert(scene_add_sphere(s, v3(rng_range(-10.f, 10.f), rng_range(-10.f, 10.f), rng_range(-10.f, 10.f)),
                                   rng_range(0.05f, 1.f), (uint32_t)mat) >= 0);
    return s;
}

/* A ray of one of several kinds: from outside at the scene, from inside in
 * any direction, axis-parallel from grid vertices, aimed at grid vertices. */
static ray random_ray(int kind)
{
    ray r;
    r.t_near = 0.f;
    r.t_far = FLT_MAX;
    switch (kind % 4) {
    case 0:
        r.org = v3(rng_range(-30.f, 30.f), rng_range(-30.f, 30.f), 30.f);
        r.dir = v3(rng_range(-1.f, 1.f), rng_range(-1.f, 1.f), -1.f);
        break;
    case 1:
        r.org = v3(rng_range(-5.f, 5.f), rng_range(-5.f, 5.f), rng_range(-5.f, 5.f));
        r.dir = v3(rng_range(-1.f, 1.f), rng_range(-1.f, 1.f), rng_range(-1.f, 1.f));
        r.t_far = rng_range(1.f, 40.f);
        break;
    case 2: /* straight down onto grid vertices and edges: exact ties between triangles */
        r.org = v3((float)(int)rng_range(-10.f, 10.f) + (rng_u32() & 1 ? 0.5f : 0.f), 20.f,
                   (float)(int)rng_range(-10.f, 10.f));
        r.dir = v3(0.f, -1.f, 0.f);
        break;
    default: /* aimed at a grid vertex from a random point */
        r.org = v3(rng_range(-12.f, 12.f), rng_range(-5.f, 12.f), rng_range(-12.f, 12.f));
        r.dir = v3_sub(v3((float)(int)rng_range(-10.f, 10.f), -11.f, (float)(int)rng_range(-10.f, 10.f)), r.org);
        break;
    }
    return r;
}

static bool same_hit(hit a, hit b) { return memcmp(&a, &b, sizeof a) == 0; }

/* The definition the kernels implement: over every primitive of every
 * instance, the hit in (t_near, t_far] that is smallest in (t, geom_id,
 * prim_id) order, by each kind's scalar reference intersector (geometry.h). */
static hit brute_force(const scene *s, const ray *r)
{
    hit best = hit_none();
    for (uint32_t i = 0; i < s->instance_count; i++) {
        const scene_instance *inst = &s->instances[i];
        const scene_geometry *g = scene_instance_geometry(s, i);
        ray local = *r;
        if (!inst->identity)
            local = (ray){affine3_point(&inst->to_object, r->org), affine3_vector(&inst->to_object, r->dir), r->t_near,
                          r->t_far};
        uint32_t n = g->ops->prim_count(g->data);
        for (uint32_t p = 0; p < n; p++) {
            float th, u, vv;
            if (g->ops->intersect(g->data, p, &local, &th, &u, &vv) && th < best.t)
                best = (hit){.t = th, .u = u, .v = vv, .prim_id = p, .geom_id = i};
        }
    }
    return best;
}

/* The scene of make_scene plus its geometries placed again by rotations,
 * non-uniform scales and translations (instances of the soup and of the
 * sphere set, which become ellipsoids). */
static scene *make_instanced_scene(void)
{
    scene *s = make_scene();
    for (int k = 0; k < 6; k++) {
        float a = rng_range(0.f, 6.28f), b = rng_range(0.f, 6.28f);
        float sx = rng_range(0.3f, 2.f), sy = rng_range(0.3f, 2.f), sz = rng_range(0.3f, 2.f);
        float ca = cosf(a), sa = sinf(a), cb = cosf(b), sb = sinf(b);
        /* R = Rz(b) Ry(a), then S, then a translation */
        affine3 m = {{cb * ca * sx, -sb * sy, cb * sa * sz, rng_range(-15.f, 15.f),
                      sb * ca * sx, cb * sy, sb * sa * sz, rng_range(-15.f, 15.f),
                      -sa * sx, 0.f, ca * sz, rng_range(-15.f, 15.f)}};
        uint32_t geometry = k % 3 == 2 ? s->instances[s->sphere_instance].geometry : 0u; /* soup or spheres */
        cr_assert(scene_add_instance(s, geometry, &m, SCENE_NO_PART) >= 0);
    }
    return s;
}

static void matches_brute_force(scene *s);

Test(kernels, every_isa_matches_brute_force_bit_for_bit, .timeout = 120)
{
    rng_state = 0x9E3779B97F4A7C15ull;
    matches_brute_force(make_scene());
}

Test(kernels, every_isa_matches_brute_force_through_transformed_instances, .timeout = 120)
{
    rng_state = 0x2545F4914F6CDD1Dull;
    matches_brute_force(make_instanced_scene());
}

/* make_scene plus a particle set (GEOMETRY_LEAF_POINTS: read in place, up
 * to 16 per leaf) with a radius per particle from an attribute and a crop
 * by another, placed as it is and again by a rotation and scale. */
static scene *make_particle_scene(bool crop_active)
{
    scene *s = make_scene();
    particle_set *set = particle_set_create();
    cr_assert(set);
    int r_attr = particle_set_add_attribute(set, "r"), e_attr = particle_set_add_attribute(set, "energy");
    cr_assert(r_attr == 0 && e_attr == 1);
    for (int i = 0; i < 4000; i++) {
        float values[2] = {rng_range(0.02f, 0.6f), rng_range(-1.f, 1.f)};
        /* clusters and a few exact duplicates: ties in t between particles */
        vec3 c = v3(rng_range(-10.f, 10.f), rng_range(-10.f, 10.f), rng_range(-10.f, 10.f));
        cr_assert(particle_set_add(set, c.x, c.y, c.z, values));
        if (i % 97 == 0)
            cr_assert(particle_set_add(set, c.x, c.y, c.z, values));
    }
    tess_error err = {{0}};
    cr_assert(particle_set_finish(set, "test", &err), "%s", err.msg);
    particle_kind_options opt = {.radius_attribute = "r", .crop_attribute = "energy",
                                 .crop = {crop_active, -0.3f, 0.5f}};
    particle_kind *k = particle_kind_create(set, &opt, "test", &err);
    cr_assert(k, "%s", err.msg);
    int g = scene_add_geometry(s, &particle_kind_ops, k, "particles");
    cr_assert_geq(g, 0);
    cr_assert_geq(scene_add_instance(s, (uint32_t)g, NULL, SCENE_NO_PART), 0);
    affine3 m = {{0.f, -1.5f, 0.f, 3.f, 1.5f, 0.f, 0.f, -2.f, 0.f, 0.f, 0.7f, 1.f}};
    cr_assert_geq(scene_add_instance(s, (uint32_t)g, &m, SCENE_NO_PART), 0);
    return s;
}

Test(kernels, particles_match_brute_force_in_every_isa, .timeout = 120)
{
    rng_state = 0x51ED2701u;
    matches_brute_force(make_particle_scene(false));
}

Test(kernels, cropped_particles_match_brute_force_in_every_isa, .timeout = 120)
{
    rng_state = 0x51ED2702u;
    matches_brute_force(make_particle_scene(true));
}

/* Single rays and packets of every width, every ISA, against brute_force;
 * takes the scene. */
static void matches_brute_force(scene *s)
{
    tess_error err = {{0}};
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    const int rays = 8000;
    ray *list = malloc(sizeof(ray) * rays);
    hit *reference = malloc(sizeof(hit) * rays);
    bool *occluded = malloc(sizeof(bool) * rays);
    cr_assert(list && reference && occluded);
    for (int i = 0; i < rays; i++)
        list[i] = random_ray(i);
    /* strictly increasing scan order above makes "first found" the lowest ids on equal t */
    int on_placed = 0; /* hits on instances placed by a transform */
    for (int i = 0; i < rays; i++) {
        reference[i] = brute_force(s, &list[i]);
        occluded[i] = reference[i].t != INFINITY;
        on_placed += occluded[i] && !s->instances[reference[i].geom_id].identity;
    }
    bool placed = false;
    for (uint32_t i = 0; i < s->instance_count; i++)
        placed |= !s->instances[i].identity;
    cr_assert(!placed || on_placed > 200, "only %d rays hit a transformed instance", on_placed);
    const char *isas[] = {"sse2", "avx2", "avx512"};
    int tested = 0;
    for (size_t k = 0; k < sizeof isas / sizeof isas[0]; k++) {
        if (isa_skip_note(isas[k]))
            continue;
        cr_assert(accel_use_isa(a, isas[k]), "%s: usable but refused", isas[k]);
        tested++;
        long mismatches = 0;
        for (int i = 0; i < rays; i++) {
            hit h;
            accel_intersect(a, &list[i], &h);
            if (!same_hit(h, reference[i]) && mismatches < 5)
                cr_log_warn("ray %d (kind %d): got t=%a geom %u prim %u, want t=%a geom %u prim %u", i, i % 4, (double)h.t,
                            h.geom_id, h.prim_id, (double)reference[i].t, reference[i].geom_id, reference[i].prim_id);
            mismatches += !same_hit(h, reference[i]);
            mismatches += accel_occluded(a, &list[i]) != occluded[i];
        }
        /* packets of every width 1..64 with random active masks */
        static ray_packet p;
        int next = 0;
        for (uint32_t width = 1; next < rays; width = width % 64 + 1) {
            uint32_t count = width;
            if ((uint32_t)(rays - next) < count)
                count = (uint32_t)(rays - next);
            packet_reset(&p, count, 0);
            for (uint32_t i = 0; i < count; i++)
                packet_set_ray(&p, i, &list[next + (int)i]);
            uint64_t active = ((uint64_t)rng_u32() << 32 | rng_u32()) & packet_span_mask(0, count);
            p.active = active;
            packet_detect_facts(&p);
            uint64_t occ = accel_occluded_packet(a, packet_whole(&p));
            accel_intersect_packet(a, packet_whole(&p));
            for (uint32_t i = 0; i < count; i++) {
                const hit *want = &reference[next + (int)i];
                if (active >> i & 1u) {
                    mismatches += !same_hit(packet_get_hit(&p, i), *want);
                    mismatches += (bool)(occ >> i & 1u) != occluded[next + (int)i];
                } else {
                    hit none = hit_none();
                    mismatches += !same_hit(packet_get_hit(&p, i), none); /* inactive rays untouched */
                    mismatches += (occ >> i & 1u) != 0;
                }
            }
            next += (int)count;
        }
        cr_log_info("%s: %d rays single and in packets of 1..64: %ld mismatches", isas[k], rays, mismatches);
        cr_expect_eq(mismatches, 0, "%s kernels differ from the scalar reference in %ld results", isas[k], mismatches);
    }
    cr_expect(tested >= 1);
    free(list);
    free(reference);
    free(occluded);
    accel_destroy(a);
    scene_destroy(s);
}

Test(kernels, packets_of_primary_rays_match_single_rays)
{
    rng_state = 12345;
    scene *s = make_scene();
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    camera_desc c = {v3(25.f, 18.f, 30.f), v3(0.f, -2.f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    camera_basis b = camera_basis_make(&c, 96, 64);
    static ray_packet p;
    long mismatches = 0, hits = 0;
    for (int y = 0; y < 64; y += 8)
        for (int x = 0; x < 96; x += 8) {
            packet_primary(&p, &b, x, y, 8, 8);
            cr_assert(p.flags & PACKET_COMMON_ORIGIN);
            ray single[64];
            for (uint32_t i = 0; i < p.count; i++)
                single[i] = packet_get_ray(&p, i);
            accel_intersect_packet(a, packet_whole(&p));
            for (uint32_t i = 0; i < p.count; i++) {
                hit h;
                hits += accel_intersect(a, &single[i], &h);
                mismatches += !same_hit(h, packet_get_hit(&p, i));
            }
        }
    cr_log_info("%ld of %d primary rays hit", hits, 96 * 64);
    cr_expect(hits > 500, "the camera should see the scene: %ld hits", hits);
    cr_expect_eq(mismatches, 0);
    accel_destroy(a);
    scene_destroy(s);
}

Test(kernels, unknown_isa_is_refused)
{
    rng_state = 1;
    scene *s = make_scene();
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a);
    const char *before = accel_isa_name(a);
    cr_expect(!accel_use_isa(a, "neon"));
    cr_expect_str_eq(accel_isa_name(a), before);
    accel_destroy(a);
    scene_destroy(s);
}

/* TESSERA_ISA_MAX caps what tessera may use as a CPU without the ISAs above
 * the cap would: kernels_for gives NULL above it, kernels_select and
 * accel_use_isa pass them by, and kernels_usable says why. Whatever this CPU
 * has, the verdict is the same: the cap is never exceeded. (Each Criterion
 * test runs in a process of its own, so setenv here touches no other test.) */
Test(kernels, the_isa_cap_holds_whatever_the_cpu)
{
    static const char *const caps[] = {"sse2", "avx2", "avx512"};
    rng_state = 1;
    scene *s = make_scene();
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    for (int c = 0; c < KERNEL_ISA_COUNT; c++) {
        cr_assert_eq(setenv("TESSERA_ISA_MAX", caps[c], 1), 0);
        cr_expect(kernels_check_env(&err), "%s", err.msg);
        cr_expect_leq(kernels_isa_by_name(kernels_select()->isa_name), c, "cap %s: selected %s", caps[c],
                      kernels_select()->isa_name);
        cr_expect(kernels_for(KERNEL_ISA_SSE2), "cap %s: SSE2 (the x86-64 baseline) is always usable", caps[c]);
        for (int isa = c + 1; isa < KERNEL_ISA_COUNT; isa++) {
            char why[96];
            cr_expect_null(kernels_for((kernel_isa)isa), "cap %s: %s usable", caps[c], kernels_isa_name((kernel_isa)isa));
            cr_expect(!accel_use_isa(a, kernels_isa_name((kernel_isa)isa)), "cap %s: accel took %s", caps[c],
                      kernels_isa_name((kernel_isa)isa));
            cr_expect(!kernels_usable((kernel_isa)isa, why, sizeof why));
            /* the CPU may lack it too; else the cap is named */
            cr_expect(strstr(why, "lacks") || strstr(why, "TESSERA_ISA_MAX="), "why: '%s'", why);
        }
        /* a forced ISA above the cap falls back to the best under it */
        cr_assert_eq(setenv("TESSERA_ISA", "avx512", 1), 0);
        cr_expect_leq(kernels_isa_by_name(kernels_select()->isa_name), c);
        cr_assert_eq(unsetenv("TESSERA_ISA"), 0);
    }
    cr_assert_eq(setenv("TESSERA_ISA_MAX", "sse2", 1), 0);
    cr_expect_str_eq(kernels_select()->isa_name, "sse2");
    cr_expect(accel_use_isa(a, "sse2"));
    /* unset or empty: no cap, the best the CPU runs */
    cr_assert_eq(setenv("TESSERA_ISA_MAX", "", 1), 0);
    const char *best = kernels_select()->isa_name;
    cr_assert_eq(unsetenv("TESSERA_ISA_MAX"), 0);
    cr_expect_str_eq(kernels_select()->isa_name, best);
    accel_destroy(a);
    scene_destroy(s);
}

Test(kernels, a_bad_isa_variable_is_named)
{
    tess_error err = {{0}};
    cr_assert_eq(setenv("TESSERA_ISA_MAX", "avx1024", 1), 0);
    cr_expect(!kernels_check_env(&err));
    cr_expect(strstr(err.msg, "TESSERA_ISA_MAX=avx1024") && strstr(err.msg, "sse2, avx2, avx512"), "%s", err.msg);
    cr_assert_eq(unsetenv("TESSERA_ISA_MAX"), 0);
    err.msg[0] = '\0';
    cr_assert_eq(setenv("TESSERA_ISA", "neon", 1), 0);
    cr_expect(!kernels_check_env(&err));
    cr_expect(strstr(err.msg, "TESSERA_ISA=neon"), "%s", err.msg);
    cr_assert_eq(unsetenv("TESSERA_ISA"), 0);
    err.msg[0] = '\0';
    cr_expect(kernels_check_env(&err), "%s", err.msg);
}

Test(kernels, packet_facts_and_derived_flags)
{
    static ray_packet p;
    camera_desc c = {v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    camera_basis b = camera_basis_make(&c, 64, 64);
    packet_primary(&p, &b, 0, 0, 8, 8); /* top-left tile: every direction has -x, +y, -z */
    cr_expect_eq(p.count, 64u);
    cr_expect_eq(p.active, ~0ull);
    cr_expect(p.flags & PACKET_COMMON_ORIGIN);
    cr_expect(p.flags & PACKET_NORMALIZED);
    cr_expect(p.flags & PACKET_CONSTANT_SIGNS);
    packet_primary(&p, &b, 28, 28, 8, 8); /* straddles the optical axis: signs differ */
    cr_expect(!(p.flags & PACKET_CONSTANT_SIGNS));
    uint32_t facts = p.flags;
    packet_detect_facts(&p);
    cr_expect_eq(p.flags, facts, "detection agrees with what the generator knew");
    /* derived inverse directions: computed once, zero components as +-FLT_MAX */
    packet_reset(&p, 2, 0);
    ray r0 = {v3(0.f, 0.f, 0.f), v3(0.f, -0.f, 2.f), 0.f, 1.f}, r1 = {v3(1.f, 0.f, 0.f), v3(4.f, 1.f, -1.f), 0.f, 1.f};
    packet_set_ray(&p, 0, &r0);
    packet_set_ray(&p, 1, &r1);
    packet_detect_facts(&p);
    cr_expect(!(p.flags & PACKET_COMMON_ORIGIN));
    packet_derive_inv_dir(&p);
    cr_expect(p.flags & PACKET_HAVE_INV_DIR);
    cr_expect_eq(p.inv_dir_x[0], FLT_MAX);
    cr_expect_eq(p.inv_dir_y[0], -FLT_MAX);
    cr_expect_eq(p.inv_dir_z[0], 0.5f);
    cr_expect_eq(p.inv_dir_x[1], 0.25f);
    p.inv_dir_x[1] = 7.f; /* a second call must not recompute */
    packet_derive_inv_dir(&p);
    cr_expect_eq(p.inv_dir_x[1], 7.f);
    /* tracing invalidates values derived from hits */
    p.flags |= PACKET_HAVE_HIT_POSITION | PACKET_HAVE_GEOMETRIC_NORMAL | PACKET_HAVE_SHADING_NORMAL;
    rng_state = 3;
    scene *s = make_scene();
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a);
    packet_derive_inv_dir(&p);
    p.inv_dir_x[1] = 0.25f;
    accel_intersect_packet(a, packet_whole(&p));
    cr_expect(!(p.flags & (PACKET_HAVE_HIT_POSITION | PACKET_HAVE_GEOMETRIC_NORMAL | PACKET_HAVE_SHADING_NORMAL)));
    /* a sub-packet touches only its range */
    packet_reset(&p, 64, 0);
    for (uint32_t i = 0; i < 64; i++) {
        ray r = random_ray((int)i);
        packet_set_ray(&p, i, &r);
    }
    accel_intersect_packet(a, (packet_range){&p, 16, 32});
    for (uint32_t i = 0; i < 64; i++)
        if (i < 16 || i >= 32)
            cr_expect_eq(p.prim_id[i], RAY_INVALID_ID, "ray %u outside the range was traced", i);
    accel_destroy(a);
    scene_destroy(s);
}

Test(kernels, primary_directions_match_the_camera_bit_for_bit)
{
    camera_desc c = {v3(1.5f, 2.f, 7.f), v3(-0.3f, 0.1f, 0.2f), v3(0.1f, 1.f, 0.f), 47.f};
    camera_basis b = camera_basis_make(&c, 83, 61); /* odd sizes: partial tiles at the edges */
    static ray_packet p;
    long differ = 0;
    for (int isa = 0; isa < KERNEL_ISA_COUNT; isa++) {
        const kernel_table *k = kernels_for((kernel_isa)isa);
        if (!k) {
            isa_skip_note(kernels_isa_name((kernel_isa)isa));
            continue;
        }
        for (int y = 0; y < 61; y += 8)
            for (int x = 0; x < 83; x += 8) {
                int w = 83 - x < 8 ? 83 - x : 8, h = 61 - y < 8 ? 61 - y : 8;
                packet_reset(&p, (uint32_t)(w * h), 0);
                k->primary_directions(&p, &b, x, y, w, h);
                for (int i = 0; i < w * h; i++) {
                    vec3 want = v3_normalize(camera_pixel_direction(&b, x + i % w, y + i / w));
                    vec3 got = v3(p.dir_x[i], p.dir_y[i], p.dir_z[i]);
                    differ += memcmp(&want, &got, sizeof want) != 0;
                }
            }
    }
    cr_expect_eq(differ, 0, "%ld primary directions differ from the scalar camera", differ);
}

/* accel_set_single_rays (tessera bench --single-rays) traces a packet's
 * rays one by one: the same hits, occlusion and next hits as the packet
 * kernels, inactive rays untouched. */
Test(kernels, packets_traced_one_by_one_match_the_packet_kernels)
{
    rng_state = 777;
    scene *s = make_scene();
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    static ray_packet in_packets, one_by_one;
    long mismatches = 0, hits = 0, second_hits = 0;
    for (int round = 0; round < 200; round++) {
        uint32_t count = 1 + rng_u32() % 64;
        packet_reset(&in_packets, count, 0);
        for (uint32_t i = 0; i < count; i++) {
            ray r = random_ray((int)(rng_u32() % 4));
            packet_set_ray(&in_packets, i, &r);
        }
        in_packets.active = ((uint64_t)rng_u32() << 32 | rng_u32()) & packet_span_mask(0, count);
        packet_detect_facts(&in_packets);
        one_by_one = in_packets;
        accel_set_single_rays(a, false);
        uint64_t occ_packet = accel_occluded_packet(a, packet_whole(&in_packets));
        accel_intersect_packet(a, packet_whole(&in_packets));
        accel_set_single_rays(a, true);
        uint64_t occ_single = accel_occluded_packet(a, packet_whole(&one_by_one));
        accel_intersect_packet(a, packet_whole(&one_by_one));
        mismatches += occ_packet != occ_single;
        for (uint32_t i = 0; i < count; i++) {
            mismatches += !same_hit(packet_get_hit(&in_packets, i), packet_get_hit(&one_by_one, i));
            hits += packet_get_hit(&in_packets, i).t != INFINITY;
        }
        /* the next surface along each ray that hit: next-hit bounds */
        ray_packet *both[2] = {&in_packets, &one_by_one};
        for (int k = 0; k < 2; k++) {
            ray_packet *p = both[k];
            hit first[PACKET_MAX_RAYS];
            for (uint32_t i = 0; i < count; i++)
                first[i] = packet_get_hit(p, i);
            ray rays[PACKET_MAX_RAYS];
            for (uint32_t i = 0; i < count; i++)
                rays[i] = packet_get_ray(p, i);
            uint64_t active = p->active;
            packet_reset(p, count, 0);
            p->active = 0;
            for (uint32_t i = 0; i < count; i++) {
                rays[i].t_far = FLT_MAX;
                packet_set_ray(p, i, &rays[i]);
                if ((active >> i & 1u) && first[i].t != INFINITY) {
                    packet_set_after(p, i, &first[i]);
                    p->active |= 1ull << i;
                }
            }
            packet_detect_facts(p);
            accel_set_single_rays(a, k == 1);
            accel_intersect_packet(a, packet_whole(p));
        }
        for (uint32_t i = 0; i < count; i++) {
            mismatches += !same_hit(packet_get_hit(&in_packets, i), packet_get_hit(&one_by_one, i));
            second_hits += packet_get_hit(&in_packets, i).t != INFINITY;
        }
    }
    cr_log_info("one by one: %ld first hits, %ld next hits, %ld mismatches", hits, second_hits, mismatches);
    cr_expect(hits > 500 && second_hits > 100, "too few hits to compare: %ld, %ld", hits, second_hits);
    cr_expect_eq(mismatches, 0);
    accel_destroy(a);
    scene_destroy(s);
}
