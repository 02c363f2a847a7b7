/* test_pipeline_config.c - the inspection part of a pipeline config: what
 * cli_pipeline_config_parse reads (renderer.transparency, renderer.caps,
 * renderer.ao, opacity, cutting_planes; docs/pipeline-config.md) reaches the
 * pipeline config unchanged, the pipeline's frame state starts from it (planes
 * normalised as clip-plane records are), and every render view the pipeline
 * builds carries its settings. Error messages naming the file and the field
 * are checked through the binary (tests/test_pipeline_cli.c): the parser
 * prints them. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/frame/pipeline.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "app/pipeline_cli.h"

static bool parse(const char *text, cli_pipeline_spec *s)
{
    cli_pipeline_spec_default(s, "null", NULL);
    return cli_pipeline_config_parse("cfg.json", text, strlen(text), s);
}

static bool same_settings(const render_settings *a, const render_settings *b)
{
    return a->min_transmittance == b->min_transmittance && a->max_layers == b->max_layers &&
           a->transparent_shadows == b->transparent_shadows && a->caps == b->caps && a->cap_style == b->cap_style &&
           a->ao_rays == b->ao_rays && a->ao_distance == b->ao_distance && a->ao_interleave == b->ao_interleave &&
           a->ao_filter_px == b->ao_filter_px && a->ao_frames == b->ao_frames &&
           a->ao_frame_base == b->ao_frame_base && a->ao_exponent == b->ao_exponent;
}

static const char full_config[] =
    "{\"opacity\": 0.5,\n"
    " \"renderer\": {\"name\": \"raytracer\",\n"
    "   \"transparency\": {\"min_transmittance\": 0.015625, \"max_layers\": 4, \"shadows\": false},\n"
    "   \"caps\": {\"on\": false, \"style\": \"hatch\"},\n"
    "   \"ao\": {\"rays\": 32, \"distance\": 2.5, \"interleave\": 2, \"filter_px\": 3, \"frames\": 4,\n"
    "          \"exponent\": 1}},\n"
    " \"cutting_planes\": [{\"point\": [0, 0.5, 0], \"normal\": [0, 2, 0]},\n"
    "                    {\"point\": [1, 0, -1], \"normal\": [3, 0, 4], \"on\": false}]}\n";

Test(pipeline_config, absent_keys_keep_the_defaults)
{
    cli_pipeline_spec s;
    cr_assert(parse("{\"threads\": 2, \"renderer\": {\"ao\": {}}}", &s));
    render_settings d = render_settings_default();
    cr_expect(same_settings(&s.settings, &d));
    cr_expect_eq(s.settings.min_transmittance, 1.f / 255.f);
    cr_expect_eq(s.settings.max_layers, 16);
    cr_expect(s.settings.transparent_shadows && s.settings.caps && s.settings.cap_style == RENDER_CAP_TINT);
    cr_expect(s.settings.ao_rays == 16 && s.settings.ao_interleave == 4 && s.settings.ao_filter_px == 5 &&
              s.settings.ao_frames == 1 && s.settings.ao_exponent == RENDER_AO_EXPONENT_DEFAULT);
    cr_expect_eq(s.settings.ao_distance, 0.f, "absent: 0.2 x the scene's diagonal (the renderer's rule)");
    cr_expect_eq(s.opacity, 1.f);
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        cr_expect(!s.clip[i].on && s.clip[i].normal.x == 0.f && s.clip[i].normal.y == 0.f &&
                      s.clip[i].normal.z == 0.f,
                  "plane %d unused", i);
}

Test(pipeline_config, every_inspection_key_is_read)
{
    cli_pipeline_spec s;
    cr_assert(parse(full_config, &s));
    cr_expect_eq(s.opacity, 0.5f);
    cr_expect_eq(s.settings.min_transmittance, 0.015625f);
    cr_expect_eq(s.settings.max_layers, 4);
    cr_expect_not(s.settings.transparent_shadows);
    cr_expect_not(s.settings.caps);
    cr_expect_eq(s.settings.cap_style, RENDER_CAP_HATCH);
    cr_expect_eq(s.settings.ao_rays, 32);
    cr_expect_eq(s.settings.ao_distance, 2.5f);
    cr_expect_eq(s.settings.ao_exponent, 1.f);
    cr_expect_eq(s.settings.ao_interleave, 2);
    cr_expect_eq(s.settings.ao_filter_px, 3);
    cr_expect_eq(s.settings.ao_frames, 4);
    /* planes as written (the pipeline normalises), "on" true unless said */
    cr_expect(s.clip[0].on && s.clip[0].point.y == 0.5f && s.clip[0].normal.y == 2.f);
    cr_expect(!s.clip[1].on && s.clip[1].point.z == -1.f && s.clip[1].normal.x == 3.f && s.clip[1].normal.z == 4.f);
    for (int i = 2; i < CLIP_MAX_PLANES; i++)
        cr_expect(!s.clip[i].on && s.clip[i].normal.y == 0.f, "plane %d unused", i);
    /* a later config's list replaces the planes, it does not add to them */
    cr_assert(cli_pipeline_config_parse("more.json", "{\"cutting_planes\": [{\"point\": [0,0,0], \"normal\": [1,0,0]}]}",
                                        strlen("{\"cutting_planes\": [{\"point\": [0,0,0], \"normal\": [1,0,0]}]}"),
                                        &s));
    cr_expect(s.clip[0].on && s.clip[0].normal.x == 1.f && !s.clip[1].on && s.clip[1].normal.x == 0.f);
    cr_expect_eq(s.settings.max_layers, 4, "what the second file does not name stays");
}

Test(pipeline_config, bad_values_are_refused)
{
    static const char *const bad[] = {
        "{\"renderer\": {\"transparency\": {\"min_transmittance\": 0}}}",
        "{\"renderer\": {\"transparency\": {\"min_transmittance\": 1}}}",
        "{\"renderer\": {\"transparency\": {\"max_layers\": 0}}}",
        "{\"renderer\": {\"transparency\": {\"max_layers\": 65}}}",
        "{\"renderer\": {\"transparency\": {\"shadows\": 1}}}",
        "{\"renderer\": {\"transparency\": {\"layers\": 3}}}",
        "{\"renderer\": {\"caps\": {\"style\": \"dots\"}}}",
        "{\"renderer\": {\"caps\": {\"on\": \"yes\"}}}",
        "{\"renderer\": {\"ao\": {\"rays\": 0}}}",
        "{\"renderer\": {\"ao\": {\"rays\": 65}}}",
        "{\"renderer\": {\"ao\": {\"distance\": 0}}}",
        "{\"renderer\": {\"ao\": {\"interleave\": 9}}}",
        "{\"renderer\": {\"ao\": {\"filter_px\": 4}}}",
        "{\"renderer\": {\"ao\": {\"filter_px\": 11}}}",
        "{\"renderer\": {\"ao\": {\"frames\": 0}}}",
        "{\"renderer\": {\"ao\": {\"frames\": 65}}}",
        "{\"renderer\": {\"ao\": {\"exponent\": 0.5}}}",
        "{\"renderer\": {\"ao\": {\"exponent\": 9}}}",
        "{\"renderer\": {\"ao\": {\"in_raytracer\": true}}}",
        "{\"opacity\": -0.1}",
        "{\"opacity\": 1.01}",
        "{\"cutting_planes\": {}}",
        "{\"cutting_planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 0, 0]}]}",
        "{\"cutting_planes\": [{\"normal\": [0, 0, 1]}]}",
        "{\"cutting_planes\": [{\"point\": [0, 0], \"normal\": [0, 0, 1]}]}",
        "{\"cutting_planes\": [{\"point\": [0, 0, 0], \"normal\": [0, 0, 1], \"off\": true}]}",
        "{\"cutting_planes\": [{\"point\": [0, 0, 1e39], \"normal\": [0, 0, 1]}]}",
        "{\"cutting_planes\": [{},{},{},{},{},{},{},{},{}]}",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        cli_pipeline_spec s;
        cr_expect_not(parse(bad[i], &s), "accepted: %s", bad[i]);
    }
}

/* ---- through a pipeline ---- */

/* A renderer that notes what every view it is given carries (then draws black): the first
 * settings pointer, and how many views differed from it or had no state. */
static _Atomic(const render_settings *) seen_settings;
static atomic_int seen_views, seen_other;

static void note_tile(const render_view *v, const pixel_sampler *s, int x0, int y0, int x1, int y1, float *rgb,
                      render_counts *counts)
{
    (void)s;
    (void)counts;
    const render_settings *first = NULL;
    atomic_compare_exchange_strong(&seen_settings, &first, v->settings);
    atomic_fetch_add(&seen_views, 1);
    if (v->settings != atomic_load(&seen_settings) || !v->state)
        atomic_fetch_add(&seen_other, 1);
    for (int y = y0; y < y1; y++)
        memset(rgb + ((size_t)y * (size_t)v->camera.width_px + (size_t)x0) * 3, 0,
               (size_t)(x1 - x0) * 3 * sizeof(float));
}

static const renderer note_renderer = {"note", RENDER_SHADE_PHONG, note_tile};

static bool drop_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)d;
    (void)img;
    (void)err;
    return true;
}

static void drop_destroy(image_display *d) { free(d); }

static const image_display_ops drop_ops = {.name = "drop", .show = drop_show, .destroy = drop_destroy};

Test(pipeline_config, the_pipeline_starts_from_the_config_and_its_views_carry_the_settings)
{
    tess_error err = {{0}};
    cli_scene cs = {"(built-in default)", scene_create_default(&err), NULL, 0.0, 0.0};
    cr_assert(cs.scene, "%s", err.msg);
    cs.accel = accel_build(cs.scene, 1, &err);
    cr_assert(cs.accel, "%s", err.msg);
    cli_pipeline_spec s;
    cr_assert(parse(full_config, &s));
    pipeline_config cfg = cli_pipeline_config(&s, &cs);
    cr_expect(same_settings(&cfg.settings, &s.settings));
    cr_expect_eq(cfg.opacity, 0.5f);
    cr_expect(memcmp(cfg.clip, s.clip, sizeof cfg.clip) == 0);
    cfg.threads = 2;
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    cfg.max_frames = 2;
    cfg.renderer = &note_renderer;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p, "%s", err.msg);
    const frame_state *st = pipeline_frame_state(p);
    cr_expect_eq(st->opacity, 0.5f);
    cr_expect(frame_state_transparent(st));
    const clip_plane *planes = frame_state_clip_planes(st);
    cr_expect(planes[0].on && planes[0].normal.x == 0.f && planes[0].normal.y == 1.f && planes[0].normal.z == 0.f,
              "(0, 2, 0) normalised");
    cr_expect(!planes[1].on && planes[1].normal.x == 0.6f && planes[1].normal.z == 0.8f, "an off plane is placed too");
    for (int i = 2; i < CLIP_MAX_PLANES; i++)
        cr_expect_not(planes[i].on);
    image_display *d = calloc(1, sizeof *d);
    cr_assert(d);
    d->ops = &drop_ops;
    camera_desc cam = cs.scene->camera;
    cr_assert(pipeline_add_channel(p, &cam, 32, 16, d, &err) == 0, "%s", err.msg);
    atomic_store(&seen_settings, NULL);
    atomic_store(&seen_views, 0);
    atomic_store(&seen_other, 0);
    cr_assert(pipeline_run(p, &err), "%s", err.msg);
    cr_expect(atomic_load(&seen_views) > 0);
    cr_expect_eq(atomic_load(&seen_other), 0, "views with other settings, or no state");
    /* every view points at the pipeline's own copy (alive while it is), holding the config's */
    const render_settings *seen = atomic_load(&seen_settings);
    cr_assert_not_null(seen);
    cr_expect(seen != &cfg.settings, "a view points at the caller's config");
    cr_expect(same_settings(seen, &s.settings));
    pipeline_destroy(p);
    accel_destroy(cs.accel);
    scene_destroy(cs.scene);
}

Test(pipeline_config, pipeline_config_validate_names_the_setting)
{
    tess_error err = {{0}};
    scene *sc = scene_create_default(&err);
    cr_assert(sc, "%s", err.msg);
    accel *a = accel_build(sc, 1, &err);
    cr_assert(a, "%s", err.msg);
    const pipeline_config ok = pipeline_config_default(sc, a);
    cr_assert(pipeline_config_validate(&ok, &err), "%s", err.msg);
    struct {
        pipeline_config cfg;
        const char *expect;
    } cases[9];
    for (int i = 0; i < 9; i++)
        cases[i].cfg = ok;
    cases[0].cfg.settings.min_transmittance = 0.f;
    cases[0].expect = "pipeline: settings.min_transmittance: 0 is not in (0, 1)";
    cases[1].cfg.settings.max_layers = 65;
    cases[1].expect = "pipeline: settings.max_layers: 65 is not in 1..64";
    cases[2].cfg.settings.ao_filter_px = 2;
    cases[2].expect = "pipeline: settings.ao_filter_px: 2 is not odd in 1..9";
    cases[3].cfg.settings.ao_distance = -1.f;
    cases[3].expect = "pipeline: settings.ao_distance: -1";
    cases[4].cfg.opacity = NAN;
    cases[4].expect = "pipeline: opacity: nan is not in [0, 1]";
    cases[5].cfg.clip[3].on = true; /* on with a zero normal */
    cases[5].expect = "pipeline: clip[3]: clip-plane: normal: zero length";
    cases[6].cfg.clip[0].normal = v3(0.f, 0.f, 1.f);
    cases[6].cfg.clip[0].point = v3(INFINITY, 0.f, 0.f);
    cases[6].expect = "pipeline: clip[0]: clip-plane: point.x: inf is not finite";
    cases[7].cfg.settings.ao_interleave = 0;
    cases[7].expect = "pipeline: settings.ao_interleave: 0 is not in 1..8";
    cases[8].cfg.settings.ao_exponent = 0.5f;
    cases[8].expect = "pipeline: settings.ao_exponent: 0.5 is not in [1, 8]";
    for (int i = 0; i < 9; i++) {
        err = (tess_error){{0}};
        cr_expect_not(pipeline_config_validate(&cases[i].cfg, &err), "case %d", i);
        cr_expect(strstr(err.msg, cases[i].expect), "case %d: '%s' lacks '%s'", i, err.msg, cases[i].expect);
        cr_expect_null(pipeline_create(&cases[i].cfg, &err), "case %d", i);
    }
    /* a plane that is off with a normal is a placed plane: valid, applied off */
    pipeline_config placed = ok;
    placed.clip[5].normal = v3(0.f, 0.f, -2.f);
    pipeline *p = pipeline_create(&placed, &err);
    cr_assert(p, "%s", err.msg);
    const clip_plane *planes = frame_state_clip_planes(pipeline_frame_state(p));
    cr_expect(!planes[5].on && planes[5].normal.z == -1.f);
    cr_expect_not(frame_state_transparent(pipeline_frame_state(p)));
    pipeline_destroy(p);
    accel_destroy(a);
    scene_destroy(sc);
}
