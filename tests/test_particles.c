/* test_particles.c - particles as a geometry kind (engine/geometry/particles/):
 * cropping by an attribute without a rebuild, next-hit walks through
 * overlapping particles, the memory a particle costs, and the set's own
 * operations. Every set is generated here. (Bit-identical hits against
 * brute force in every ISA: tests/test_kernels.c.) */
#include <criterion/criterion.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/geometry/particles/particle_kind.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "engine/frame/txn.h"
#include "support.h"
#include "app/input_pick.h"

/* A scene holding only `set` as particles (options as given), and its accel. */
static scene *particle_scene(particle_set *set, particle_kind_options opt, accel **a)
{
    scene *s = scene_create();
    material m = material_default();
    opt.material_id = (uint32_t)scene_add_material(s, &m);
    tess_error err = {{0}};
    cr_assert(particle_set_finish(set, "test", &err), "%s", err.msg);
    particle_kind *k = particle_kind_create(set, &opt, "test", &err);
    cr_assert(k, "%s", err.msg);
    int g = scene_add_geometry(s, &particle_kind_ops, k, "particles");
    cr_assert_geq(g, 0);
    cr_assert_geq(scene_add_instance(s, (uint32_t)g, NULL, SCENE_NO_PART), 0);
    *a = accel_build(s, 2, &err);
    cr_assert(*a, "%s", err.msg);
    return s;
}

static particle_kind *kind_of(const scene *s) { return (particle_kind *)s->geometries[0].data; }

/* 100 particles of radius 0.4 on the x axis at x = 0..99, "energy" = x. */
static particle_set *particle_line(void)
{
    particle_set *set = particle_set_create();
    cr_assert(set && particle_set_add_attribute(set, "energy") == 0);
    for (int i = 0; i < 100; i++) {
        float e = (float)i;
        cr_assert(particle_set_add(set, (float)i, 0.f, 0.f, &e));
    }
    return set;
}

/* The energy of what a ray along +x from x = -5 meets first (-1: nothing),
 * asked as a single ray and in a packet of 64 copies (both must agree). */
static float first_energy(const scene *s, const accel *a)
{
    ray r = {v3(-5.f, 0.f, 0.f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    hit h;
    bool found = accel_intersect(a, &r, &h);
    static ray_packet p;
    packet_reset(&p, 64, 0);
    for (uint32_t i = 0; i < 64; i++) {
        ray q = r;
        q.org.y = 0.001f * (float)i; /* not all one ray: a real packet */
        packet_set_ray(&p, i, &q);
    }
    packet_detect_facts(&p);
    accel_intersect_packet(a, packet_whole(&p));
    const particle_set *set = particle_kind_set(kind_of(s));
    for (uint32_t i = 0; i < 64; i++) {
        hit ph = packet_get_hit(&p, i);
        cr_assert_eq(ph.t != INFINITY, found, "packet ray %u disagrees with the single ray", i);
        if (found)
            cr_assert_eq(set->attributes[0].values[ph.prim_id], set->attributes[0].values[h.prim_id]);
    }
    cr_assert_eq(accel_occluded(a, &r), found);
    return found ? set->attributes[0].values[h.prim_id] : -1.f;
}

Test(particles, crop_changes_what_is_seen_without_a_rebuild)
{
    accel *a;
    particle_kind_options opt = {.radius = 0.4f, .crop_attribute = "energy", .crop = {true, 10.f, 20.f}};
    scene *s = particle_scene(particle_line(), opt, &a);
    cr_assert_float_eq(first_energy(s, a), 10.f, 0.f);
    particle_kind_set_crop(kind_of(s), (geometry_crop){true, 30.5f, 40.f});
    cr_assert_float_eq(first_energy(s, a), 31.f, 0.f);
    particle_kind_set_crop(kind_of(s), (geometry_crop){true, 99.f, 99.f});
    cr_assert_float_eq(first_energy(s, a), 99.f, 0.f);
    particle_kind_set_crop(kind_of(s), (geometry_crop){true, 100.5f, 200.f});
    cr_assert_float_eq(first_energy(s, a), -1.f, 0.f, "a crop above every value hides everything");
    particle_kind_set_crop(kind_of(s), (geometry_crop){false, 100.5f, 200.f});
    cr_assert_float_eq(first_energy(s, a), 0.f, 0.f, "an inactive crop shows everything");
    accel_destroy(a);
    scene_destroy(s);
}

Test(particles, a_set_without_a_crop_attribute_ignores_crops)
{
    accel *a;
    particle_kind_options opt = {.radius = 0.4f};
    scene *s = particle_scene(particle_line(), opt, &a);
    particle_kind_set_crop(kind_of(s), (geometry_crop){true, 10.f, 20.f});
    cr_assert_float_eq(first_energy(s, a), 0.f, 0.f);
    cr_assert_eq(particle_kind_crop_attribute(kind_of(s)), -1);
    accel_destroy(a);
    scene_destroy(s);
}

/* Three overlapping particles on the axis: walking next hits meets every
 * entry and exit once, in order, as the analytic crossings say. */
Test(particles, next_hits_walk_every_crossing_in_order)
{
    particle_set *set = particle_set_create();
    cr_assert(set && particle_set_add_attribute(set, "r") == 0);
    const float centre[3] = {0.f, 0.5f, 3.f}, radius[3] = {1.f, 1.f, 0.25f};
    for (int i = 0; i < 3; i++)
        cr_assert(particle_set_add(set, centre[i], 0.f, 0.f, &radius[i]));
    accel *a;
    scene *s = particle_scene(set, (particle_kind_options){.radius_attribute = "r"}, &a);
    float want[6] = {-1.f, -0.5f, 1.f, 1.5f, 2.75f, 3.25f};
    ray r = {v3(-10.f, 0.f, 0.f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    hit h;
    cr_assert(accel_intersect(a, &r, &h));
    for (int k = 0; k < 6; k++) {
        cr_assert_float_eq(h.t, want[k] + 10.f, 1e-5f, "crossing %d at t %g, want %g", k, (double)h.t,
                           (double)(want[k] + 10.f));
        hit next;
        bool more = accel_intersect_after(a, &r, &h, &next);
        cr_assert_eq(more, k < 5, "after crossing %d", k);
        h = next;
    }
    accel_destroy(a);
    scene_destroy(s);
}

/* Particles read in place: positions, the tree and its crop ranges come to
 * at most 24 bytes a particle (issue 16), attributes apart. */
Test(particles, a_particle_costs_at_most_24_bytes_plus_its_attributes)
{
    particle_set *set = particle_set_create();
    cr_assert(set && particle_set_add_attribute(set, "energy") == 0);
    uint64_t state = 88172645463325252ull;
    for (int i = 0; i < 200000; i++) {
        float c[3], e;
        for (int k = 0; k < 3; k++) {
            state ^= state << 13, state ^= state >> 7, state ^= state << 17;
            c[k] = (float)(state >> 40) * (100.f / 16777216.f);
        }
        e = c[0] + c[1];
        cr_assert(particle_set_add(set, c[0], c[1], c[2], &e));
    }
    accel *a;
    particle_kind_options opt = {.radius = 0.3f, .crop_attribute = "energy"};
    scene *s = particle_scene(set, opt, &a);
    size_t n = scene_point_count(s), attributes = (size_t)n * sizeof(float);
    double per = (double)(scene_point_bytes(s) - attributes + accel_bytes(a)) / (double)n;
    cr_log_info("%.2f bytes a particle (positions %zu, tree and crop ranges %zu)", per, 12 * n, accel_bytes(a));
    cr_assert_leq(per, 24.0, "%.2f bytes a particle", per);
    cr_assert_eq(n, 200000u);
    accel_destroy(a);
    scene_destroy(s);
}

Test(particles, set_operations)
{
    particle_set *set = particle_set_create();
    cr_assert(set);
    cr_assert_eq(particle_set_add_attribute(set, "a"), 0);
    cr_assert_eq(particle_set_add_attribute(set, "a"), -1, "a name given twice");
    cr_assert_eq(particle_set_add_attribute(set, ""), -1, "an empty name");
    cr_assert_eq(particle_set_add_attribute(set, "b"), 1);
    for (int i = 0; i < 10; i++) {
        float v[2] = {(float)i, (float)-i};
        cr_assert(particle_set_add(set, (float)i, 2.f * (float)i, 0.f, v));
    }
    tess_error err = {{0}};
    cr_assert(particle_set_finish(set, "test", &err));
    cr_assert_float_eq(set->attributes[0].min, 0.f, 0.f);
    cr_assert_float_eq(set->attributes[0].max, 9.f, 0.f);
    cr_assert_float_eq(set->attributes[1].min, -9.f, 0.f);
    uint32_t order[10] = {9, 8, 7, 6, 5, 4, 3, 2, 1, 0};
    cr_assert(particle_set_permute(set, order));
    cr_assert_float_eq(set->x[0], 9.f, 0.f);
    cr_assert_float_eq(set->y[0], 18.f, 0.f);
    cr_assert_float_eq(set->attributes[1].values[0], -9.f, 0.f);
    cr_assert(particle_set_fit(set, 16));
    cr_assert_eq(set->capacity, 26u);
    cr_assert_float_eq(set->x[9], 0.f, 0.f);
    cr_assert_float_eq(set->attributes[0].values[25], 0.f, 0.f, "the spare is zeroed");
    set->attributes[1].values[3] = NAN;
    cr_assert_not(particle_set_finish(set, "pts.ply", &err));
    cr_assert_str_eq(err.msg, "pts.ply: particle 3: attribute 'b' is not finite");
    particle_set_destroy(set);
}

Test(particles, bad_radius_and_crop_attribute_are_named)
{
    particle_set *set = particle_line();
    tess_error err = {{0}};
    cr_assert(particle_set_finish(set, "test", &err));
    particle_kind_options opt = {.radius_attribute = "energy"}; /* energy 0 at particle 0 */
    cr_assert_null(particle_kind_create(set, &opt, "atoms.dump", &err));
    cr_assert_str_eq(err.msg, "atoms.dump: particle 0: radius attribute 'energy' is 0 (must be > 0)");
    set = particle_line();
    cr_assert(particle_set_finish(set, "test", &err));
    err.msg[0] = '\0';
    opt = (particle_kind_options){.radius = 1.f, .crop_attribute = "temperature"};
    cr_assert_null(particle_kind_create(set, &opt, "atoms.dump", &err));
    cr_assert_str_eq(err.msg, "atoms.dump: no attribute 'temperature' to crop by");
    set = particle_line();
    cr_assert(particle_set_finish(set, "test", &err));
    err.msg[0] = '\0';
    opt = (particle_kind_options){.radius = -1.f};
    cr_assert_null(particle_kind_create(set, &opt, "atoms.dump", &err));
    cr_assert_str_eq(err.msg, "atoms.dump: the radius must be a finite number > 0");
}

/* A crop record applied to a frame state reaches the particles at the next
 * sync (what a pipeline's serial section does), and only then. */
Test(particles, crop_records_reach_the_kind_at_the_sync)
{
    accel *a;
    particle_kind_options opt = {.radius = 0.4f, .crop_attribute = "energy"};
    scene *s = particle_scene(particle_line(), opt, &a);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    tess_error err = {{0}};
    uint64_t serial = st.picture_serial;
    txn_record r = txn_crop(0, 1, true, 50.f, 60.f);
    char text[TXN_TEXT_MAX];
    cr_assert_gt(txn_encode_text(&r, text, sizeof text), 0);
    txn_record back;
    cr_assert(txn_decode_text(text, strlen(text), TXN_TEXT_V2, &back, &err), "%s", err.msg);
    cr_assert(txn_apply(&back, &st, &err), "%s", err.msg);
    cr_assert_gt(st.picture_serial, serial);
    cr_assert_float_eq(first_energy(s, a), 0.f, 0.f, "applied but not yet synced");
    frame_state_sync_accel(&st, a);
    cr_assert_float_eq(first_energy(s, a), 50.f, 0.f);
    geometry_crop c;
    cr_assert(frame_state_crop(&st, 0, &c) && c.active && c.lo == 50.f && c.hi == 60.f);
    txn_record past = txn_crop(1, 1, true, 0.f, 1.f);
    cr_assert_not(txn_apply(&past, &st, &err), "instance 1 does not exist");
    frame_state_finish(&st);
    accel_destroy(a);
    scene_destroy(s);
}

/* What a hit reports: the attribute through the colour map (auto range over
 * the attribute), a scanner's sRGB codes decoded, or the material's colour. */
Test(particles, hits_are_coloured_by_the_attribute_or_the_file_s_rgb)
{
    accel *a;
    colormap grey;
    cr_assert(colormap_preset("greyscale", &grey));
    particle_kind_options opt = {.radius = 0.4f, .colouring = PARTICLE_COLOUR_MAP, .colour_attribute = "energy",
                                 .map = &grey};
    scene *s = particle_scene(particle_line(), opt, &a);
    const scene_geometry *g = &s->geometries[0];
    ray r = {v3(-5.f, 0.f, 0.f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    for (float x = 0.f; x < 100.f; x += 33.f) {
        r.org = v3(x, 5.f, 0.f);
        r.dir = v3(0.f, -1.f, 0.f);
        hit h;
        cr_assert(accel_intersect(a, &r, &h));
        geometry_surface surf;
        g->ops->describe(g->data, h.prim_id, &r, &h, true, &surf);
        cr_assert(surf.has_colour);
        colormap_rgba want = colormap_eval(particle_kind_colormap(kind_of(s)), x); /* energy = x; range [0, 99] */
        cr_assert_float_eq(surf.colour.x, want.r, COLORMAP_TABLE_TOLERANCE, "x %g: %g vs %g", (double)x,
                           (double)surf.colour.x, (double)want.r);
        cr_assert_float_eq(surf.geometric_n.y, 1.f, 1e-6f, "the top of the particle faces up");
    }
    accel_destroy(a);
    scene_destroy(s);
}

Test(particles, rgb_colours_are_the_file_s_srgb_codes)
{
    particle_set *set = particle_set_create();
    cr_assert(set && particle_set_add_attribute(set, "red") == 0 && particle_set_add_attribute(set, "green") == 1 &&
              particle_set_add_attribute(set, "blue") == 2);
    const float codes[3] = {255.f, 128.f, 0.f};
    cr_assert(particle_set_add(set, 0.f, 0.f, 0.f, codes));
    accel *a;
    scene *s = particle_scene(set, (particle_kind_options){.radius = 1.f, .colouring = PARTICLE_COLOUR_RGB}, &a);
    ray r = {v3(0.f, 5.f, 0.f), v3(0.f, -1.f, 0.f), 0.f, INFINITY};
    hit h;
    cr_assert(accel_intersect(a, &r, &h));
    const scene_geometry *g = &s->geometries[0];
    geometry_surface surf;
    g->ops->describe(g->data, h.prim_id, &r, &h, false, &surf);
    cr_assert(surf.has_colour);
    cr_assert_float_eq(surf.colour.x, 1.f, 1e-6f);
    cr_assert_float_eq(surf.colour.y, 0.2158605f, 1e-5f, "sRGB 128 is linear 0.2159");
    cr_assert_float_eq(surf.colour.z, 0.f, 0.f);
    accel_destroy(a);
    scene_destroy(s);
}

/* Picking a particle names it and its attributes' values (the status line). */
Test(particles, a_pick_reports_the_particle_s_attributes)
{
    accel *a;
    scene *s = particle_scene(particle_line(), (particle_kind_options){.radius = 0.4f}, &a);
    input_hit out;
    cli_input_pick(s, a, v3(42.f, 5.f, 0.f), v3(0.f, -1.f, 0.f), &out);
    cr_assert(out.hit);
    const particle_set *set = particle_kind_set(kind_of(s));
    char want[128];
    snprintf(want, sizeof want, "particle %u of 'particles': energy 42", out.prim_id);
    cr_assert_str_eq(out.what, want);
    cr_assert_float_eq(set->x[out.prim_id], 42.f, 0.f);
    cr_assert_str_eq(out.part.label, "the particles 'particles' (100)");
    accel_destroy(a);
    scene_destroy(s);
}

/* An ascii PLY of vertices only: one particle at (x, 0, 0). */
static void write_step(const char *dir, int step, float x)
{
    char path[512];
    snprintf(path, sizeof path, "%s/step_%04d.ply", dir, step);
    FILE *f = fopen(path, "w");
    cr_assert(f);
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
               "end_header\n%g 0 0\n%g 0 0\n", (double)x, (double)x + 100.0);
    fclose(f);
}

/* A scene of `steps` such files (step i at x = 10 i) as one series, in a
 * fresh temp directory (into dir), and its accel built with `threads`. */
static scene *series_scene(char *dir, size_t dir_size, const char *name, int steps, int threads, accel **a)
{
    char scene_path[512];
    support_make_tmp_dir(dir, dir_size, name);
    for (int i = 0; i < steps; i++)
        write_step(dir, i, 10.f * (float)i);
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    FILE *f = fopen(scene_path, "w");
    cr_assert(f);
    fprintf(f, "{\"particles\": [{\"files\": \"step_*.ply\", \"radius\": 0.5}]}\n");
    fclose(f);
    tess_error err = {{0}};
    scene *s = scene_load(scene_path, &err);
    cr_assert(s, "%s", err.msg);
    *a = accel_build(s, threads, &err);
    cr_assert(*a, "%s", err.msg);
    return s;
}

/* Where a ray down the x axis from x = -50 meets the series now. */
static float first_x(const accel *a)
{
    ray r = {v3(-50.f, 0.f, 0.f), v3(1.f, 0.f, 0.f), 0.f, INFINITY};
    hit h;
    cr_assert(accel_intersect(a, &r, &h));
    return -50.f + h.t + 0.5f; /* radius 0.5 */
}

/* A series of files as time steps: a time-step record swaps the step in at
 * the sync, the next one is loaded in the background, a step whose file is
 * gone leaves the shown one, and the scene file's "files" pattern sorts the
 * steps by name. */
Test(particles, time_steps_swap_at_the_sync_and_load_ahead, .timeout = 60)
{
    char dir[256];
    accel *a;
    scene *s = series_scene(dir, sizeof dir, "steps", 4, 2, &a);
    tess_error err = {{0}};
    particle_kind *k = kind_of(s);
    cr_assert_eq(particle_kind_step_count(k), 4u);
    cr_assert_float_eq(first_x(a), 0.f, 1e-4f);

    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    txn_record r = txn_time_step(2);
    cr_assert(txn_apply(&r, &st, &err), "%s", err.msg);
    cr_assert_float_eq(first_x(a), 0.f, 1e-4f, "applied, not yet synced");
    frame_state_sync_accel(&st, a);
    cr_assert_eq(particle_kind_step(k), 2u);
    cr_assert_float_eq(first_x(a), 20.f, 1e-4f);
    /* after a step the next one (3) is loaded in the background */
    while (!particle_kind_step_ready(k, 3))
        nanosleep(&(struct timespec){0, 1000000}, NULL); /* the event: the loader's state; the timeout bounds it */
    r = txn_time_step(4); /* = step 0 of 4 */
    cr_assert(txn_apply(&r, &st, &err));
    frame_state_sync_accel(&st, a);
    cr_assert_eq(particle_kind_step(k), 0u);
    cr_assert_float_eq(first_x(a), 0.f, 1e-4f);

    /* a step whose file went away: an error naming it; the step shown stays. (Step 1, next
     * after 0, is loaded ahead: wait for that, so step 2 must come from the disk.) */
    while (!particle_kind_step_ready(k, 1))
        nanosleep(&(struct timespec){0, 1000000}, NULL);
    char gone[512];
    snprintf(gone, sizeof gone, "%s/step_0002.ply", dir);
    cr_assert_eq(unlink(gone), 0);
    err.msg[0] = '\0';
    cr_assert_not(accel_set_time_step(a, 2, &err));
    cr_assert(strstr(err.msg, "step_0002.ply"), "%s", err.msg);
    cr_assert_eq(particle_kind_step(k), 0u);
    cr_assert_float_eq(first_x(a), 0.f, 1e-4f);

    frame_state_finish(&st);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

Test(particles, a_series_pattern_that_matches_nothing_is_named)
{
    char dir[256], scene_path[512];
    support_make_tmp_dir(dir, sizeof dir, "steps-none");
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    FILE *f = fopen(scene_path, "w");
    cr_assert(f);
    fprintf(f, "{\"particles\": [{\"files\": \"nothing_*.dump\"}]}\n");
    fclose(f);
    tess_error err = {{0}};
    cr_assert_null(scene_load(scene_path, &err));
    char want[1024];
    snprintf(want, sizeof want, "%s: field 'particles[0].files': no file matches '%s/nothing_*.dump'", scene_path, dir);
    cr_assert_str_eq(err.msg, want);
    support_remove_tmp_dir(dir);
}

/* A pattern whose folder does not exist matches nothing, as an empty
 * folder: an error naming the pattern, or with "optional" a skip (the
 * example scenes name ../shared/data folders that need not be there). */
Test(particles, a_series_pattern_in_a_missing_folder_matches_nothing)
{
    char dir[256], scene_path[512];
    support_make_tmp_dir(dir, sizeof dir, "steps-nofolder");
    snprintf(scene_path, sizeof scene_path, "%s/scene.json", dir);
    FILE *f = fopen(scene_path, "w");
    cr_assert(f);
    fprintf(f, "{\"particles\": [{\"files\": \"absent/deeper/step_*.dump\"}]}\n");
    fclose(f);
    tess_error err = {{0}};
    cr_assert_null(scene_load(scene_path, &err));
    char want[1024];
    snprintf(want, sizeof want, "%s: field 'particles[0].files': no file matches '%s/absent/deeper/step_*.dump'",
             scene_path, dir);
    cr_assert_str_eq(err.msg, want);
    f = fopen(scene_path, "w");
    cr_assert(f);
    fprintf(f, "{\"particles\": [{\"files\": \"absent/deeper/step_*.dump\", \"optional\": true}],"
               " \"spheres\": [{\"center\": [0, 0, 0], \"radius\": 1}]}\n");
    fclose(f);
    scene *s = scene_load(scene_path, &err);
    cr_assert_not_null(s, "%s", err.msg);
    cr_expect_eq(s->spheres.count, 1u);
    cr_expect_eq(s->geometry_count, 1u, "the skipped series added a geometry");
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

/* A "particles" entry's mistakes name the field. */
Test(particles, scene_file_mistakes_name_the_field)
{
    char dir[256], ply[512];
    support_make_tmp_dir(dir, sizeof dir, "pjson");
    snprintf(ply, sizeof ply, "%s/pts.ply", dir);
    FILE *f = fopen(ply, "w");
    cr_assert(f);
    fprintf(f, "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
               "property float e\nend_header\n0 0 0 0\n1 0 0 2\n");
    fclose(f);
    const struct {
        const char *entry, *message;
    } cases[] = {
        {"{\"file\": \"pts.ply\", \"crop\": {\"attribute\": \"temp\"}}",
         "field 'particles[0].crop.attribute': no attribute 'temp' (the file has: e)"},
        {"{\"file\": \"pts.ply\", \"radius\": \"e\"}",
         "field 'particles[0].radius': attribute 'e' has values down to 0 (a radius must be > 0)"},
        {"{\"file\": \"pts.ply\", \"color_map\": \"magma\"}",
         "field 'particles[0].color_map': needs 'color_by' (the attribute it colours)"},
        {"{\"file\": \"pts.ply\", \"color_by\": \"rgb\"}",
         "field 'particles[0].color_by': 'rgb' needs the attributes red, green and blue"},
        {"{\"file\": \"pts.ply\", \"color_by\": \"e\", \"color_map\": \"jet\"}",
         "field 'particles[0].color_map': unknown"},
        {"{\"file\": \"pts.ply\", \"crop\": {\"attribute\": \"e\", \"range\": [3, 1]}}",
         "field 'particles[0].crop.range': the low end 3 is above the high end 1"},
        {"{\"file\": \"pts.ply\", \"files\": \"p*.ply\"}",
         "field 'particles[0]': give either 'file' or 'files' (a time series)"},
        {"{\"file\": \"pts.ply\", \"size\": 2}", "field 'particles[0].size': unknown field"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[600], text[512];
        snprintf(path, sizeof path, "%s/scene.json", dir);
        snprintf(text, sizeof text, "{\"particles\": [%s]}", cases[i].entry);
        tess_error err = {{0}};
        scene *s = scene_parse_json(path, text, strlen(text), &err);
        cr_expect_null(s, "case %zu loaded", i);
        scene_destroy(s);
        cr_expect(strstr(err.msg, cases[i].message), "case %zu: '%s' lacks '%s'", i, err.msg, cases[i].message);
    }
    support_remove_tmp_dir(dir);
}

typedef struct prefetch_storm {
    particle_kind *k;
    atomic_bool stop;
} prefetch_storm;

/* The input thread asking for other steps to load ahead, all the time. */
static void *ask_ahead(void *arg)
{
    prefetch_storm *ps = arg;
    for (uint32_t i = 0; !atomic_load(&ps->stop); i++)
        particle_kind_step_ready(ps->k, i % 5);
    return NULL;
}

/* Showing a step is never starved by prefetch requests from another thread
 * (the step a serial section waits for goes first): no hang, every step
 * shown as asked. */
Test(particles, a_step_asked_for_is_not_starved_by_prefetches, .timeout = 120)
{
    char dir[256];
    accel *a;
    scene *s = series_scene(dir, sizeof dir, "steps-storm", 5, 1, &a);
    tess_error err = {{0}};
    prefetch_storm ps = {.k = kind_of(s)};
    atomic_init(&ps.stop, false);
    pthread_t t;
    cr_assert_eq(pthread_create(&t, NULL, ask_ahead, &ps), 0);
    const uint32_t order[] = {3, 1, 4, 4, 0, 2, 1, 3};
    for (size_t i = 0; i < sizeof order / sizeof order[0]; i++) {
        cr_assert(accel_set_time_step(a, order[i], &err), "%s", err.msg);
        cr_assert_eq(particle_kind_step(kind_of(s)), order[i]);
        cr_assert_float_eq(first_x(a), 10.f * (float)order[i], 1e-4f, "step %u", order[i]);
    }
    atomic_store(&ps.stop, true);
    pthread_join(t, NULL);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

/* A colormap record recolours particles at the sync, over the same range. */
Test(particles, a_colormap_record_recolours_at_the_sync)
{
    accel *a;
    particle_kind_options opt = {.radius = 0.4f, .colouring = PARTICLE_COLOUR_MAP, .colour_attribute = "energy"};
    scene *s = particle_scene(particle_line(), opt, &a);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    tess_error err = {{0}};
    txn_record r = txn_colormap(0, 1, "magma");
    cr_assert(txn_apply(&r, &st, &err), "%s", err.msg);
    frame_state_sync_accel(&st, a);
    const colormap *cm = particle_kind_colormap(kind_of(s));
    cr_assert_str_eq(cm->name, "magma");
    cr_assert_float_eq(cm->lo, 0.f, 0.f);
    cr_assert_float_eq(cm->hi, 99.f, 0.f, "the range stays the attribute's");
    const scene_geometry *g = &s->geometries[0];
    ray down = {v3(99.f, 5.f, 0.f), v3(0.f, -1.f, 0.f), 0.f, INFINITY};
    hit h;
    cr_assert(accel_intersect(a, &down, &h));
    geometry_surface surf;
    g->ops->describe(g->data, h.prim_id, &down, &h, false, &surf);
    colormap_rgba top = colormap_eval(cm, 99.f);
    cr_assert_float_eq(surf.colour.x, top.r, COLORMAP_TABLE_TOLERANCE);
    frame_state_finish(&st);
    accel_destroy(a);
    scene_destroy(s);
}
