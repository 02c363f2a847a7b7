/* test_frame_state.c - the pipeline's frame state (engine/scene/frame_state.h):
 * version and serial bumps, per-geometry arrays only when used, the accel's
 * hidden flags changed only where they differ, and through a running
 * pipeline: a record queued during frame f is seen from frame f+1 and never
 * mid-frame (shadows toggled by a record), isolate + show-all restores the
 * image bit for bit. These also run under ThreadSanitizer (make test-tsan). */
#include <criterion/criterion.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/frame/pipeline.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"

#define W 48
#define H 27
#define FRAMES 8

/* ---- unit: the state alone ---- */

static frame_state plain_state(uint32_t geometries)
{
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 1, geometries);
    camera_desc c = {v3(0.f, 0.f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    cr_assert_eq(frame_state_add_channel(&st, &c), 0);
    return st;
}

Test(frame_state, every_change_bumps_the_version_and_the_right_serial)
{
    frame_state st = plain_state(4);
    tess_error err = {{0}};
    camera_desc same = st.cameras[0], moved = same;
    moved.eye.x = 1.f;
    struct {
        txn_record r;
        int picture, overlay; /* expected bumps */
    } steps[] = {
        {txn_camera(0, &same), 0, 0},  /* the same camera: no change of the picture */
        {txn_camera(0, &moved), 1, 0},
        {txn_cursor(true, 0.f, 0.f), 0, 1},
        {txn_cursor(true, 0.f, 0.f), 0, 0}, /* the same cursor */
        {txn_status("hello"), 0, 0},    /* the pipeline bumps overlay when the drawn line changes */
        {txn_flag(TXN_SHADOWS, true), 0, 0}, /* already on */
        {txn_flag(TXN_SHADOWS, false), 1, 0},
        {txn_renderer("raytracer"), 0, 0},
        {txn_renderer("eyelight"), 1, 0},
        {txn_geoms_record(TXN_HIDE, 1, 2), 1, 0},
        {txn_geoms_record(TXN_HIDE, 1, 1), 0, 0}, /* already hidden */
        {txn_geoms_record(TXN_SHOW, 0, 1), 0, 0}, /* already shown */
        {txn_simple(TXN_SHOW_ALL), 1, 0},         /* always, as the pipeline's unhide-all did */
        {txn_highlight(0, 1, true), 1, 0},
        {txn_highlight(0, 1, true), 0, 0},
        {txn_colour(3, 1, (const float[3]){1.f, 0.f, 0.f}), 1, 0},
        {txn_colour(3, 1, (const float[3]){1.f, 0.f, 0.f}), 0, 0},
        {txn_colour(3, 1, NULL), 1, 0},
        {txn_channel_active(0, true), 0, 0},
        {txn_channel_active(0, false), 1, 0},
        {txn_threads(3), 0, 0},
        {txn_opacity_all(1.f), 0, 0}, /* already opaque */
        {txn_opacity_all(0.5f), 1, 0},
        {txn_opacity_all(0.5f), 0, 0},
        {txn_opacity(0, 2, 1.f), 0, 0}, /* parts already opaque */
        {txn_opacity(0, 2, 0.25f), 1, 0},
        {txn_opacity(1, 1, 0.25f), 0, 0},
        {txn_opacity(1, 1, 1.f), 1, 0},
        {txn_clip_plane(2, false, (const float[3]){1.f, 0.f, 0.f}, (const float[3]){0.f, 1.f, 0.f}), 0, 0},
        /* off and staying off: moved unseen */
        {txn_clip_plane(2, true, (const float[3]){1.f, 0.f, 0.f}, (const float[3]){0.f, 1.f, 0.f}), 1, 0},
        {txn_clip_plane(2, true, (const float[3]){1.f, 0.f, 0.f}, (const float[3]){0.f, 2.f, 0.f}), 0, 0},
        /* the same unit normal */
        {txn_clip_plane(2, true, (const float[3]){1.f, 0.5f, 0.f}, (const float[3]){0.f, 1.f, 0.f}), 1, 0},
        {txn_clip_plane(2, true, (const float[3]){1.f, 0.5f, 0.f}, (const float[3]){0.f, -1.f, 0.f}), 1, 0},
        {txn_clip_plane(2, false, (const float[3]){1.f, 0.5f, 0.f}, (const float[3]){0.f, -1.f, 0.f}), 1, 0},
    };
    for (size_t i = 0; i < sizeof steps / sizeof steps[0]; i++) {
        frame_state before = st;
        cr_assert(txn_apply(&steps[i].r, &st, &err), "step %zu: %s", i, err.msg);
        cr_expect_eq(st.version, before.version + 1, "step %zu (%s)", i, txn_kind_name(steps[i].r.kind));
        cr_expect_eq(st.picture_serial, before.picture_serial + (uint64_t)steps[i].picture, "step %zu (%s)", i,
                     txn_kind_name(steps[i].r.kind));
        cr_expect_eq(st.overlay_serial, before.overlay_serial + (uint64_t)steps[i].overlay, "step %zu (%s)", i,
                     txn_kind_name(steps[i].r.kind));
    }
    cr_expect_eq(st.camera_serials[0], 2u, "every camera set counts, the same one too");
    frame_state_finish(&st);
}

Test(frame_state, a_scene_pays_no_memory_for_a_feature_it_does_not_use)
{
    frame_state st = plain_state(1000);
    tess_error err = {{0}};
    txn_record nothing[] = {txn_geoms_record(TXN_SHOW, 0, 1000), txn_simple(TXN_SHOW_ALL),
                            txn_highlight(0, 1000, false), txn_colour(0, 1000, NULL), txn_flag(TXN_SHADOWS, false)};
    for (size_t i = 0; i < sizeof nothing / sizeof nothing[0]; i++)
        cr_assert(txn_apply(&nothing[i], &st, &err), "%s", err.msg);
    cr_expect(st.hidden == NULL);
    cr_expect(st.highlight == NULL);
    cr_expect(st.coloured == NULL);
    cr_expect(st.colour == NULL);
    txn_record hide = txn_geoms_record(TXN_HIDE, 5, 1);
    cr_assert(txn_apply(&hide, &st, &err));
    cr_expect(st.hidden != NULL);
    cr_expect(st.highlight == NULL, "hiding allocates no highlight flags");
    cr_expect(st.colour == NULL, "hiding allocates no colours");
    txn_record hl = txn_highlight(7, 1, true);
    cr_assert(txn_apply(&hl, &st, &err));
    cr_expect(st.highlight != NULL);
    cr_expect(st.colour == NULL, "a highlight allocates no colours");
    txn_record col = txn_colour(9, 1, (const float[3]){0.f, 1.f, 0.f});
    cr_assert(txn_apply(&col, &st, &err));
    cr_expect(st.colour != NULL);
    vec3 rgb;
    cr_expect(frame_state_colour(&st, 9, &rgb) && rgb.y == 1.f);
    cr_expect_not(frame_state_colour(&st, 8, &rgb));
    cr_expect(frame_state_highlighted(&st, 7) && !frame_state_highlighted(&st, 6));
    cr_expect_not(frame_state_highlighted(&st, 5000), "out of range is simply not highlighted");
    frame_state_finish(&st);
}

Test(frame_state, opacity_starts_opaque_and_allocates_only_below_1)
{
    frame_state st = plain_state(100);
    tess_error err = {{0}};
    cr_expect_eq(st.opacity, 1.f);
    cr_expect_not(frame_state_transparent(&st));
    cr_expect_eq(frame_state_opacity(&st, 0), 1.f);
    txn_record opaque = txn_opacity(0, 100, 1.f);
    cr_assert(txn_apply(&opaque, &st, &err), "%s", err.msg);
    cr_expect(st.part_opacity == NULL, "every part opaque: nothing allocated");
    /* the global opacity is a member: no allocation either */
    txn_record half = txn_opacity_all(0.5f);
    cr_assert(txn_apply(&half, &st, &err), "%s", err.msg);
    cr_expect(st.part_opacity == NULL);
    cr_expect(frame_state_transparent(&st));
    cr_expect_eq(frame_state_opacity(&st, 7), 0.5f);
    cr_expect_eq(frame_state_opacity(&st, 5000), 0.5f, "out of range: the global opacity alone");
    /* parts: allocated now, counted while below 1 */
    txn_record some = txn_opacity(10, 5, 0.5f);
    cr_assert(txn_apply(&some, &st, &err), "%s", err.msg);
    cr_assert(st.part_opacity != NULL);
    cr_expect_eq(st.translucent_count, 5u);
    cr_expect_eq(frame_state_opacity(&st, 12), 0.25f, "global x part");
    cr_expect_eq(frame_state_opacity(&st, 9), 0.5f);
    txn_record zero = txn_opacity(12, 4, 0.f); /* 12..14 were 0.5, 15 was 1 */
    cr_assert(txn_apply(&zero, &st, &err), "%s", err.msg);
    cr_expect_eq(st.translucent_count, 6u);
    cr_expect_eq(frame_state_opacity(&st, 15), 0.f);
    txn_record back = txn_opacity_all(1.f);
    cr_assert(txn_apply(&back, &st, &err), "%s", err.msg);
    cr_expect(frame_state_transparent(&st), "parts are still translucent");
    txn_record some_back = txn_opacity(0, 13, 1.f); /* 10..12 back to 1 */
    cr_assert(txn_apply(&some_back, &st, &err), "%s", err.msg);
    cr_expect_eq(st.translucent_count, 3u);
    txn_record rest_back = txn_opacity(13, 87, 1.f);
    cr_assert(txn_apply(&rest_back, &st, &err), "%s", err.msg);
    cr_expect_eq(st.translucent_count, 0u);
    cr_expect_not(frame_state_transparent(&st), "everything opaque again");
    for (uint32_t id = 0; id < 100; id++)
        cr_expect_eq(frame_state_opacity(&st, id), 1.f);
    /* out of range: refused with the range named, nothing changed */
    txn_record past = txn_opacity(99, 2, 0.5f);
    frame_state before = st;
    err = (tess_error){{0}};
    cr_expect_not(txn_apply(&past, &st, &err));
    cr_expect(strstr(err.msg, "opacity: instances 99..100: the scene has 100 instances (ids 0..99)"), "%s", err.msg);
    cr_expect(memcmp(&st, &before, sizeof st) == 0);
    frame_state_finish(&st);
    cr_expect(st.part_opacity == NULL && st.translucent_count == 0);
}

Test(frame_state, the_setters_keep_the_same_rules_as_the_records)
{
    frame_state st = plain_state(8);
    const clip_plane *planes = frame_state_clip_planes(&st);
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        cr_expect_not(planes[i].on, "plane %d is off after init", i);
    uint64_t v = st.version, pic = st.picture_serial;
    frame_state_set_global_opacity(&st, 0.f);
    cr_expect(st.version == v + 1 && st.picture_serial == pic + 1);
    cr_expect_eq(frame_state_opacity(&st, 3), 0.f, "0 is allowed: see-through");
    cr_assert(frame_state_set_opacity(&st, 0, 8, 0.75f));
    cr_expect_eq(st.translucent_count, 8u);
    clip_plane p = {v3(0.f, 1.f, 0.f), v3(1.f, 0.f, 0.f), true};
    frame_state_set_clip_plane(&st, CLIP_MAX_PLANES - 1, &p);
    cr_expect(planes[CLIP_MAX_PLANES - 1].on && planes[CLIP_MAX_PLANES - 1].point.y == 1.f);
    cr_expect_eq(st.picture_serial, pic + 3);
    cr_expect_eq(st.version, v + 3);
    frame_state_finish(&st);
}

/* ---- the scene the pipeline tests render ---- */
typedef struct fixture {
    scene *scene;
    accel *accel;
} fixture;

static fixture fixture_make(void)
{
    tess_error err = {{0}};
    fixture fx;
    fx.scene = scene_create_default(&err);
    cr_assert(fx.scene, "%s", err.msg);
    fx.accel = accel_build(fx.scene, 2, &err);
    cr_assert(fx.accel, "%s", err.msg);
    return fx;
}

static void fixture_free(fixture *fx)
{
    accel_destroy(fx->accel);
    scene_destroy(fx->scene);
}

Test(frame_state, the_accel_gets_only_the_flags_that_differ)
{
    fixture fx = fixture_make();
    uint32_t n = accel_geometry_count(fx.accel);
    cr_assert(n >= 3, "the default scene has %u geometries", n);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), true, 1, n);
    tess_error err = {{0}};
    txn_record iso = txn_geoms_record(TXN_ISOLATE, 1, 1);
    cr_assert(txn_apply(&iso, &st, &err));
    cr_expect_eq(frame_state_sync_accel(&st, fx.accel), 2u, "every geometry but 1 hidden: two runs, before and after it");
    for (uint32_t id = 0; id < n; id++)
        cr_expect_eq(accel_hidden(fx.accel, id), id != 1);
    cr_expect_eq(frame_state_sync_accel(&st, fx.accel), 0u, "nothing left to do");
    txn_record again = txn_geoms_record(TXN_HIDE, 0, 1), show = txn_geoms_record(TXN_SHOW, 2, 1);
    cr_assert(txn_apply(&again, &st, &err) && txn_apply(&show, &st, &err));
    cr_expect_eq(frame_state_sync_accel(&st, fx.accel), 1u, "one flag differs");
    cr_expect_not(accel_hidden(fx.accel, 2));
    txn_record all = txn_simple(TXN_SHOW_ALL), hide = txn_geoms_record(TXN_HIDE, 0, 1);
    cr_assert(txn_apply(&all, &st, &err) && txn_apply(&hide, &st, &err));
    cr_expect_eq(frame_state_sync_accel(&st, fx.accel), 2u, "unhide-all, then the one hidden since");
    for (uint32_t id = 0; id < n; id++)
        cr_expect_eq(accel_hidden(fx.accel, id), id == 0);
    accel_unhide_all(fx.accel);
    frame_state_finish(&st);
    fixture_free(&fx);
}

/* ---- through a running pipeline ---- */

/* A display that keeps a copy of every frame's pixels. */
typedef struct keep_display {
    image_display base;
    float *frames[FRAMES]; /* display thread only while running */
    int count;
} keep_display;

static bool keep_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    keep_display *k = (keep_display *)d;
    cr_assert(k->count < FRAMES && img->frame == (uint64_t)k->count);
    size_t bytes = (size_t)img->width_px * (size_t)img->height_px * 3 * sizeof(float);
    k->frames[k->count] = malloc(bytes);
    cr_assert(k->frames[k->count]);
    memcpy(k->frames[k->count++], img->rgb, bytes);
    return true;
}

static void keep_destroy(image_display *d)
{
    keep_display *k = (keep_display *)d;
    for (int i = 0; i < k->count; i++)
        free(k->frames[i]);
    free(k);
}

static const image_display_ops keep_ops = {.name = "keep", .show = keep_show, .destroy = keep_destroy};

static keep_display *keep_create(void)
{
    keep_display *k = calloc(1, sizeof *k);
    cr_assert(k);
    k->base.ops = &keep_ops;
    return k;
}

static float *reference(const fixture *fx, bool shadows)
{
    float *rgb = malloc((size_t)W * H * 3 * sizeof(float));
    cr_assert(rgb);
    render_view v = {.scene = fx->scene,
                     .accel = fx->accel,
                     .camera = camera_basis_make(&fx->scene->camera, W, H),
                     .shadows = shadows,
                     .shading = RENDER_SHADE_PHONG};
    render_image(&v, 1, rgb, NULL);
    return rgb;
}

static bool same(const float *a, const float *b) { return memcmp(a, b, (size_t)W * H * 3 * sizeof(float)) == 0; }

static pipeline *make_pipeline(const fixture *fx, int threads, keep_display **kept)
{
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx->scene, fx->accel);
    cfg.threads = threads;
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    cfg.max_frames = FRAMES;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p, "%s", err.msg);
    *kept = keep_create();
    cr_assert(pipeline_add_channel(p, &fx->scene->camera, W, H, &(*kept)->base, &err) == 0, "%s", err.msg);
    return p;
}

/* What every render thread saw of the state in each frame (a parallel animation). */
typedef struct observer {
    _Atomic uint64_t version[FRAMES][2];
    atomic_int shadows[FRAMES][2];
    uint64_t queued_at;     /* the frame whose parallel stage queued the change */
    atomic_bool queued;
} observer;

static void observe(pipeline *p, void *ctx, const frame_info *fi, int thread, int threads)
{
    (void)threads;
    observer *o = ctx;
    const frame_state *st = pipeline_frame_state(p); /* the frame's snapshot: read without locks */
    if (fi->frame < FRAMES && thread < 2) {
        atomic_store(&o->version[fi->frame][thread], st->version);
        atomic_store(&o->shadows[fi->frame][thread], st->shadows);
    }
    /* thread 1 queues the change while the frame is under way (the other thread may be rendering) */
    if (thread == 1 && fi->frame == o->queued_at) {
        txn_record off = txn_flag(TXN_SHADOWS, false);
        cr_assert(pipeline_submit(p, &off));
        atomic_store(&o->queued, true);
    }
}

Test(frame_state, a_record_queued_during_frame_f_shows_from_frame_f_plus_1_never_mid_frame)
{
    fixture fx = fixture_make();
    float *with = reference(&fx, true), *without = reference(&fx, false);
    cr_assert_not(same(with, without), "the scene must show shadows");
    keep_display *kept;
    pipeline *p = make_pipeline(&fx, 2, &kept);
    static observer o;
    memset(&o, 0, sizeof o);
    o.queued_at = 3;
    cr_assert(pipeline_add_parallel_animation(p, "observe", observe, &o));
    tess_error err = {{0}};
    cr_assert(pipeline_run(p, &err), "%s", err.msg);
    cr_assert(atomic_load(&o.queued));
    cr_assert_eq(kept->count, FRAMES);
    for (int f = 0; f < FRAMES; f++) {
        bool on = f <= (int)o.queued_at;
        cr_expect_eq(atomic_load(&o.version[f][0]), atomic_load(&o.version[f][1]), "frame %d: threads disagree", f);
        cr_expect_eq(atomic_load(&o.shadows[f][0]), on, "frame %d, thread 0", f);
        cr_expect_eq(atomic_load(&o.shadows[f][1]), on, "frame %d, thread 1", f);
        cr_expect(same(kept->frames[f], on ? with : without), "frame %d is not the %s image bit for bit", f,
                  on ? "shadowed" : "unshadowed");
    }
    cr_expect(atomic_load(&o.version[o.queued_at + 1][0]) > atomic_load(&o.version[o.queued_at][0]));
    cr_expect_not(pipeline_frame_state(p)->shadows);
    pipeline_destroy(p);
    free(with);
    free(without);
    fixture_free(&fx);
}

/* One-shots applying records in the serial section of frames 1, 2 and 4. */
static void isolate_one(pipeline *p, void *args)
{
    (void)args;
    txn_record r = txn_geoms_record(TXN_ISOLATE, 1, 1);
    cr_assert(pipeline_apply(p, &r));
}

static void show_all(pipeline *p, void *args)
{
    (void)args;
    txn_record r = txn_simple(TXN_SHOW_ALL);
    cr_assert(pipeline_apply(p, &r));
}

static void shadows_off(pipeline *p, void *args)
{
    (void)args;
    txn_record r = txn_flag(TXN_SHADOWS, false);
    cr_assert(pipeline_apply(p, &r));
}

Test(frame_state, isolate_then_show_all_restores_the_image_bit_for_bit)
{
    fixture fx = fixture_make();
    float *with = reference(&fx, true), *without = reference(&fx, false);
    keep_display *kept;
    pipeline *p = make_pipeline(&fx, 2, &kept);
    cr_assert(pipeline_at_frame(p, 1, "isolate", isolate_one, NULL, 0));
    cr_assert(pipeline_at_frame(p, 2, "show all", show_all, NULL, 0));
    cr_assert(pipeline_at_frame(p, 4, "shadows off", shadows_off, NULL, 0));
    tess_error err = {{0}};
    cr_assert(pipeline_run(p, &err), "%s", err.msg);
    cr_assert_eq(kept->count, FRAMES);
    cr_expect(same(kept->frames[0], with));
    cr_expect_not(same(kept->frames[1], with), "isolating geometry 1 changed nothing");
    cr_expect(same(kept->frames[2], with), "show-all did not restore the image bit for bit");
    cr_expect(same(kept->frames[3], with));
    for (int f = 4; f < FRAMES; f++)
        cr_expect(same(kept->frames[f], without), "frame %d: shadows applied at frame 4's barrier", f);
    for (uint32_t id = 0; id < pipeline_geometry_count(p); id++)
        cr_expect_not(pipeline_hidden(p, id), "geometry %u still hidden in the accel", id);
    /* frame 1 is the scene with only geometry 1 in it */
    uint32_t n = accel_geometry_count(fx.accel);
    for (uint32_t id = 0; id < n; id++)
        accel_set_hidden(fx.accel, id, id != 1);
    float *isolated = reference(&fx, true);
    accel_unhide_all(fx.accel);
    cr_expect(same(kept->frames[1], isolated), "frame 1 is not the isolated image bit for bit");
    pipeline_destroy(p);
    free(isolated);
    free(with);
    free(without);
    fixture_free(&fx);
}

/* Records are checked against this pipeline when queued: geometries and channels it has,
 * engine kinds only; the setters apply records and keep the serial-section rule. */
Test(frame_state, submit_checks_records_against_the_pipeline)
{
    fixture fx = fixture_make();
    keep_display *kept;
    pipeline *p = make_pipeline(&fx, 1, &kept);
    uint32_t n = pipeline_geometry_count(p);
    txn_record past = txn_geoms_record(TXN_HIDE, n - 1, 2), ch = txn_channel_active(1, false),
               tour = txn_flag(TXN_TOUR, true), bad = txn_threads(0), ok = txn_highlight(0, n, true);
    cr_expect_not(pipeline_submit(p, &past));
    cr_expect_not(pipeline_submit(p, &ch));
    cr_expect_not(pipeline_submit(p, &tour));
    cr_expect_not(pipeline_submit(p, &bad));
    cr_expect(pipeline_submit(p, &ok));
    /* those four were refused as invalid: counted apart from the queue's refusals */
    pipeline_stats st = pipeline_get_stats(p);
    cr_expect_eq(st.transactions_invalid, 4u);
    cr_expect_eq(st.transactions_rejected, 0u);
    /* the same checks without queueing or counting, the range in instances */
    tess_error err = {{0}};
    cr_expect_not(pipeline_check(p, &past, &err));
    char want[128];
    snprintf(want, sizeof want, "hide: instances %u..%u: the scene has %u instances (ids 0..%u)", n - 1, n, n, n - 1);
    cr_expect_str_eq(err.msg, want);
    cr_expect(pipeline_check(p, &ok, &err));
    cr_expect_eq(pipeline_get_stats(p).transactions_invalid, 4u);
    /* part opacity is checked against the geometries; the global one needs none */
    txn_record past_opacity = txn_opacity(n - 1, 2, 0.5f), part_opacity = txn_opacity(n - 1, 1, 0.5f),
               all_opacity = txn_opacity_all(0.5f);
    cr_expect_not(pipeline_submit(p, &past_opacity));
    cr_expect(pipeline_submit(p, &part_opacity));
    cr_expect(pipeline_submit(p, &all_opacity));
    /* not running: a record applies at once */
    txn_record iso = txn_geoms_record(TXN_ISOLATE, 0, 1);
    cr_assert(pipeline_apply(p, &iso));
    cr_expect(!pipeline_hidden(p, 0) && pipeline_hidden(p, 1));
    txn_record all = txn_simple(TXN_SHOW_ALL);
    cr_assert(pipeline_apply(p, &all));
    cr_expect_not(pipeline_hidden(p, 1));
    pipeline_destroy(p);
    fixture_free(&fx);
}
