/* test_volume_series.c - a volume as a time series ("files": a pattern;
 * engine/geometry/volume/iso_kind.h TIME STEPS, engine/base/series.h): small float NRRD
 * volumes written here, step k a ball of its own radius, shown as two
 * iso-surfaces and rendered directly; a time step swaps every one of them
 * at the sync; a step of another layout or a broken file is an error
 * naming the file and the step shown stays; destroying with the loader at
 * work neither hangs nor leaks (ASan). */
#include <criterion/criterion.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "engine/base/series.h"
#include "engine/frame/txn.h"
#include "engine/render/dvr_medium.h"
#include "engine/geometry/volume/iso_kind.h"
#include "support.h"

/* samples per axis: sample (i, j, k) at (i, j, k) - 8, so the centre and
 * the axes through it are samples and the field along an axis is exact */
#define N 17
#define HALF 8
/* the field outside: r - d clamped here, so macrocells far from the ball
 * are constant (the iso-surface's box follows the radius) */
#define FLOOR -1.0
/* a transfer function whose opacity is 0.2 a voxel where the value is > 0
 * (inside the ball) and 0 elsewhere, on a fixed range every step shares */
#define OPACITY_INSIDE 0.2
static const char *const entry_fmt =
    "{\"files\": \"%s\", \"macrocell\": 2,"
    " \"iso\": [{\"value\": 0}, {\"value\": -0.5}],"
    " \"dvr\": {\"transfer\": {\"map\": \"viridis\", \"opacity\": [[0, 0], [0.5, 0], [0.5005, 0.2], [1, 0.2]],"
    " \"range\": [-1, 1]}, \"step\": 0.0625}}";

/* Write step file `name` (.nhdr and its .raw): nz slices of the ball of
 * radius r (nz = N but for a step of another layout). */
static void write_step_file(const char *dir, const char *name, double r, int nz)
{
    char path[600];
    snprintf(path, sizeof path, "%s/%s.raw", dir, name);
    FILE *f = fopen(path, "wb");
    cr_assert(f);
    for (int k = 0; k < nz; k++)
        for (int j = 0; j < N; j++)
            for (int i = 0; i < N; i++) {
                double x = i - HALF, y = j - HALF, z = k - HALF;
                double v = r - sqrt(x * x + y * y + z * z);
                float s = (float)(v > FLOOR ? v : FLOOR);
                cr_assert_eq(fwrite(&s, sizeof s, 1, f), 1u);
            }
    fclose(f);
    snprintf(path, sizeof path, "%s/%s.nhdr", dir, name);
    f = fopen(path, "w");
    cr_assert(f);
    fprintf(f,
            "NRRD0005\ntype: float\ndimension: 3\nspace: left-posterior-superior\nsizes: %d %d %d\n"
            "space directions: (1,0,0) (0,1,0) (0,0,1)\nspace origin: (-8,-8,-8)\nendian: little\n"
            "encoding: raw\ndata file: %s.raw\n",
            N, N, nz, name);
    fclose(f);
}

static const double radius[] = {3.0, 4.5, 6.0, 2.5};
#define STEPS 4

/* A scene of STEPS steps (step k: radius[k]) in a fresh temp directory. */
static scene *series_scene(char *dir, size_t dir_size, const char *name)
{
    support_make_tmp_dir(dir, dir_size, name);
    for (int k = 0; k < STEPS; k++) {
        char step[32];
        snprintf(step, sizeof step, "step_%04d", k);
        write_step_file(dir, step, radius[k], N);
    }
    char path[600], entry[1024], text[2048];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    snprintf(entry, sizeof entry, entry_fmt, "step_*.nhdr");
    snprintf(text, sizeof text, "{\"volumes\": [%s]}", entry);
    tess_error err = {{0}};
    scene *s = scene_parse_json(path, text, strlen(text), &err);
    cr_assert(s, "%s", err.msg);
    return s;
}

/* Where the ray down the z axis from z = 60 meets iso-surface `instance`
 * (0: value 0, 1: value -0.5); -1 when it misses. */
static float hit_z(const accel *a, uint32_t instance, float x)
{
    ray r = {v3(x, 0.f, 60.f), v3(0.f, 0.f, -1.f), 0.f, INFINITY};
    hit h;
    if (!accel_intersect_instance(a, instance, &r, NULL, &h))
        return -1.f;
    return 60.f - h.t;
}

/* The transmittance of the medium along the z axis (the whole box). */
static float transmittance(const scene *s)
{
    cr_assert_eq(s->medium_count, 1u);
    const dvr_volume *d = dvr_medium_volume(s->media[0].data);
    const double org[3] = {0.0, 0.0, 60.0}, dir[3] = {0.0, 0.0, -1.0};
    float rgb[3], T;
    cr_assert(dvr_integrate(d, org, dir, 0.0, INFINITY, 0.0, rgb, &T));
    return T;
}

static const iso_kind *iso_of(const scene *s, uint32_t g) { return s->geometries[g].data; }

/* What step k shows: both iso-surfaces where the ball of radius[k] puts
 * them, and the medium's transmittance (1 - a)^(2 r) (a path of 2 r voxels
 * through opacity a a voxel; the step of 1/16 voxel leaves at most 1/16
 * voxel of path wrong at each end). */
static void expect_step(const scene *s, const accel *a, int k)
{
    double r = radius[k];
    cr_expect_float_eq(hit_z(a, 0, 0.f), (float)r, 1e-3f, "step %d: iso 0 at z %g", k, (double)hit_z(a, 0, 0.f));
    cr_expect_float_eq(hit_z(a, 1, 0.f), (float)(r + 0.5), 1e-3f, "step %d: iso -0.5 at z %g", k,
                       (double)hit_z(a, 1, 0.f));
    double want = pow(1.0 - OPACITY_INSIDE, 2.0 * r);
    double got = transmittance(s);
    cr_expect(fabs(got / want - 1.0) < 0.03, "step %d: transmittance %g, want %g", k, got, want);
    float lo, hi;
    iso_kind_range(iso_of(s, 0), &lo, &hi);
    cr_expect_float_eq(hi, (float)r, 1e-6f, "step %d: the value range is the step's", k);
    /* from the 8 corners inwards: the walk leaps over macrocells far from the
     * surface (its leap field must be the step's: one left from a smaller
     * ball jumps over the bigger one's surface near the corners) */
    for (int c = 0; c < 8; c++) {
        vec3 d = v3_normalize(v3(c & 1 ? 1.f : -1.f, c & 2 ? 1.f : -1.f, c & 4 ? 1.f : -1.f));
        ray ry = {v3_scale(d, -30.f), d, 0.f, INFINITY};
        hit h;
        cr_assert(accel_intersect_instance(a, 0, &ry, NULL, &h), "step %d corner %d: no hit", k, c);
        float dist = 30.f - h.t; /* from the centre, along the diagonal */
        cr_expect(fabsf(dist - (float)r) < 0.15f, "step %d corner %d: the surface at %g from the centre, want %g",
                  k, c, (double)dist, r);
    }
}

static void wait_ready(const scene *s, uint32_t step)
{
    /* the event: the loader's state (the test's timeout bounds the wait) */
    while (!scene_step_ready(s, step))
        nanosleep(&(struct timespec){0, 1000000}, NULL);
}

/* A time-step record swaps every iso-surface and the medium at the sync,
 * all to the same step; the next step is loaded ahead; steps go back too. */
Test(volume_series, iso_surfaces_and_dvr_follow_the_step, .timeout = 60)
{
    char dir[256];
    scene *s = series_scene(dir, sizeof dir, "vseries");
    tess_error err = {{0}};
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    cr_assert_eq(scene_time_steps(s), (uint32_t)STEPS);
    cr_assert_eq(s->geometries[0].ops->controls->step_count(s->geometries[0].data), (uint32_t)STEPS);
    cr_assert_eq(s->media[0].ops->controls->step_count(s->media[0].data), (uint32_t)STEPS);
    expect_step(s, a, 0);
    cr_assert_float_eq(hit_z(a, 0, 5.f), -1.f, 0.f, "the ball of radius 3 is not at x = 5");

    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    txn_record rec = txn_time_step(2);
    cr_assert(txn_apply(&rec, &st, &err), "%s", err.msg);
    expect_step(s, a, 0); /* applied, not yet synced */
    frame_state_sync_accel(&st, a);
    expect_step(s, a, 2);
    /* the iso-surface's box grew with the ball (the accel rebuilt its tree) */
    cr_assert(hit_z(a, 0, 5.f) > 0.f, "the ball of radius 6 is at x = 5");

    wait_ready(s, 3); /* loaded ahead after step 2 */
    rec = txn_time_step(3);
    cr_assert(txn_apply(&rec, &st, &err));
    frame_state_sync_accel(&st, a);
    expect_step(s, a, 3);
    cr_assert_float_eq(hit_z(a, 0, 5.f), -1.f, 0.f, "the box shrank again");

    rec = txn_time_step(1); /* backwards: loaded at the sync */
    cr_assert(txn_apply(&rec, &st, &err));
    frame_state_sync_accel(&st, a);
    expect_step(s, a, 1);

    frame_state_finish(&st);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

/* A step of another layout: an error naming the file and what differs; a
 * step whose file is broken: its error; neither is shown, nothing crashes,
 * and a later good step still shows. */
Test(volume_series, a_step_of_another_layout_or_broken_is_refused, .timeout = 60)
{
    char dir[256];
    scene *s = series_scene(dir, sizeof dir, "vseries-bad");
    tess_error err = {{0}};
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    /* step 2 now has 15 slices; step 3's data file is gone */
    write_step_file(dir, "step_0002", radius[2], N - 2);
    char gone[600];
    snprintf(gone, sizeof gone, "%s/step_0003.raw", dir);
    cr_assert_eq(remove(gone), 0);

    cr_assert_not(accel_set_time_step(a, 2, &err));
    cr_assert(strstr(err.msg, "step_0002.nhdr"), "%s", err.msg);
    cr_assert(strstr(err.msg, "dimensions 17 x 17 x 15 differ from the first step's 17 x 17 x 17"), "%s", err.msg);
    expect_step(s, a, 0);

    err.msg[0] = '\0';
    cr_assert_not(accel_set_time_step(a, 3, &err));
    cr_assert(strstr(err.msg, "step_0003"), "%s", err.msg);
    expect_step(s, a, 0);
    cr_assert_not(scene_step_ready(s, 3), "a failed step is not ready (and not loaded again by asking)");

    cr_assert(accel_set_time_step(a, 1, &err), "%s", err.msg);
    expect_step(s, a, 1);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

/* The scene file's mistakes with "files" name the field. */
Test(volume_series, files_mistakes_name_the_field)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "vseries-json");
    write_step_file(dir, "one", 3.0, N);
    const struct {
        const char *pattern, *message;
    } cases[] = {
        {"nothing_*.nhdr", "field 'volumes[0].files': no file matches '"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char path[600], entry[1024], text[2048];
        snprintf(path, sizeof path, "%s/scene.json", dir);
        snprintf(entry, sizeof entry, entry_fmt, cases[i].pattern);
        snprintf(text, sizeof text, "{\"volumes\": [%s]}", entry);
        tess_error err = {{0}};
        scene *s = scene_parse_json(path, text, strlen(text), &err);
        cr_expect_null(s, "case %zu loaded", i);
        scene_destroy(s);
        cr_expect(strstr(err.msg, cases[i].message), "case %zu: '%s' lacks '%s'", i, err.msg, cases[i].message);
    }
    const char *both = "{\"volumes\": [{\"file\": \"one.nhdr\", \"files\": \"o*.nhdr\", \"dvr\": {\"transfer\": \"ct-bone\"}}]}";
    char path[600];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    tess_error err = {{0}};
    cr_expect_null(scene_parse_json(path, both, strlen(both), &err));
    cr_expect(strstr(err.msg, "field 'volumes[0]': give either 'file' or 'files' (a time series)"), "%s", err.msg);
    support_remove_tmp_dir(dir);
}

/* Destroying the scene while the loader loads ahead neither hangs nor leaks
 * (the loader finishes its load and is joined; ASan checks the rest). */
Test(volume_series, destroy_while_the_loader_is_busy, .timeout = 60)
{
    char dir[256];
    for (int round = 0; round < 8; round++) {
        scene *s = series_scene(dir, sizeof dir, "vseries-busy");
        scene_step_ready(s, (uint32_t)(1 + round % 3)); /* the loader starts on it */
        if (round & 1)
            scene_step_ready(s, 2); /* and is asked for another meanwhile */
        scene_destroy(s);
        support_remove_tmp_dir(dir);
    }
}

/* ---- the series itself (engine/base/series.h) ------------------------------------ */

/* Step data that counts how many exist at once (shown + pending). */
typedef struct step_count {
    atomic_int live, most;
} step_count;

static void *count_load(void *ctx, const char *path, uint32_t step, tess_error *err)
{
    step_count *c = ctx;
    if (strcmp(path, "bad") == 0) {
        tess_error_set(err, "%s: broken on purpose", path);
        return NULL;
    }
    uint32_t *data = malloc(sizeof *data);
    cr_assert(data);
    *data = step;
    int now = atomic_fetch_add(&c->live, 1) + 1;
    for (int most = atomic_load(&c->most); now > most && !atomic_compare_exchange_weak(&c->most, &most, now);)
        ;
    return data;
}

static void count_free(void *ctx, void *data)
{
    step_count *c = ctx;
    atomic_fetch_sub(&c->live, 1);
    free(data);
}

typedef struct asker {
    series *s;
    atomic_bool stop;
} asker;

static void *ask_all_the_time(void *arg)
{
    asker *a = arg;
    for (uint32_t i = 0; !atomic_load(&a->stop); i++)
        series_ready(a->s, i % 7);
    return NULL;
}

/* At most two steps exist at once (the one shown and one pending) however
 * another thread asks ahead, each take gives the step asked for, and a
 * step that cannot be loaded gives its error and leaves the shown one. */
Test(volume_series, a_series_keeps_two_steps_at_most, .timeout = 60)
{
    const char *paths[] = {"s0", "s1", "s2", "bad", "s4", "s5", "s6"};
    step_count c;
    atomic_init(&c.live, 1); /* step 0, the owner's */
    atomic_init(&c.most, 1);
    tess_error err = {{0}};
    series *s = series_create(paths, 7, 0, count_load, count_free, &c, &err);
    cr_assert(s, "%s", err.msg);
    asker a = {.s = s};
    atomic_init(&a.stop, false);
    pthread_t t;
    cr_assert_eq(pthread_create(&t, NULL, ask_all_the_time, &a), 0);
    const uint32_t order[] = {2, 5, 6, 1, 4, 4, 0, 9 /* = 2 */};
    for (size_t i = 0; i < sizeof order / sizeof order[0]; i++) {
        void *data;
        cr_assert(series_take(s, order[i], &data, &err), "%s", err.msg);
        uint32_t want = order[i] % 7;
        if (i > 0 && order[i] == order[i - 1]) {
            cr_assert_null(data, "shown already");
            continue;
        }
        cr_assert_not_null(data);
        cr_assert_eq(*(uint32_t *)data, want);
        cr_assert_eq(series_step(s), want);
        count_free(&c, data); /* the owner shows it and frees the old one: model that by one count */
        series_done(s);
    }
    void *data;
    cr_assert_not(series_take(s, 3, &data, &err));
    cr_assert(strstr(err.msg, "bad: broken on purpose"), "%s", err.msg);
    cr_assert_eq(series_step(s), 2u);
    atomic_store(&a.stop, true);
    pthread_join(t, NULL);
    series_destroy(s);
    cr_assert_leq(atomic_load(&c.most), 2, "%d steps at once", atomic_load(&c.most));
    cr_assert_eq(atomic_load(&c.live), 1, "only the shown step is left");
}

/* A volume rendered directly only (no iso-surface): the scene's steps and
 * readiness are the medium's, and a time step changes what it renders. */
Test(volume_series, a_medium_alone_steps_too, .timeout = 60)
{
    char dir[256], path[600], text[1024];
    support_make_tmp_dir(dir, sizeof dir, "vseries-dvr");
    for (int k = 0; k < STEPS; k++) {
        char step[32];
        snprintf(step, sizeof step, "step_%04d", k);
        write_step_file(dir, step, radius[k], N);
    }
    snprintf(path, sizeof path, "%s/scene.json", dir);
    snprintf(text, sizeof text,
             "{\"volumes\": [{\"files\": \"step_*.nhdr\", \"dvr\": {\"transfer\": {\"map\": \"viridis\", \"opacity\":"
             " [[0, 0], [0.5, 0], [0.5005, 0.2], [1, 0.2]], \"range\": [-1, 1]}, \"step\": 0.0625}}]}");
    tess_error err = {{0}};
    scene *s = scene_parse_json(path, text, strlen(text), &err);
    cr_assert(s, "%s", err.msg);
    cr_assert_eq(s->geometry_count, 0u);
    cr_assert_eq(scene_time_steps(s), (uint32_t)STEPS);
    accel *a = accel_build(s, 1, &err);
    cr_assert(a, "%s", err.msg);
    double want0 = pow(1.0 - OPACITY_INSIDE, 2.0 * radius[0]), want2 = pow(1.0 - OPACITY_INSIDE, 2.0 * radius[2]);
    cr_expect(fabs(transmittance(s) / want0 - 1.0) < 0.03, "step 0: %g, want %g", (double)transmittance(s), want0);
    wait_ready(s, 2);
    cr_assert(accel_set_time_step(a, 2, &err), "%s", err.msg);
    cr_expect(fabs(transmittance(s) / want2 - 1.0) < 0.03, "step 2: %g, want %g", (double)transmittance(s), want2);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}
