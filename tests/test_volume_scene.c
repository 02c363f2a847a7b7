/* test_volume_scene.c - volumes in scene files (engine/load/volume_json.c,
 * docs/scene-format.md "Volumes"): a generated 32^3 ball (8-bit, value 200
 * inside a radius-10 sphere falling to 0 outside) shown as an iso-surface
 * and rendered directly, the iso-value changed by a value record without a
 * rebuild, and each mistake named. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "engine/frame/txn.h"
#include "engine/geometry/volume/iso_kind.h"
#include "support.h"

#define N 32

static void write_ball(const char *dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/ball.raw", dir);
    FILE *f = fopen(path, "wb");
    cr_assert(f);
    for (int z = 0; z < N; z++)
        for (int y = 0; y < N; y++)
            for (int x = 0; x < N; x++) {
                double r = sqrt((x - 15.5) * (x - 15.5) + (y - 15.5) * (y - 15.5) + (z - 15.5) * (z - 15.5));
                double v = 200.0 * (1.0 - (r - 6.0) / 8.0);
                unsigned char b = (unsigned char)(v < 0.0 ? 0.0 : v > 200.0 ? 200.0 : v);
                fputc(b, f);
            }
    fclose(f);
    snprintf(path, sizeof path, "%s/ball.txt", dir);
    f = fopen(path, "w");
    cr_assert(f);
    fprintf(f, "file: ball.raw\ndims: 32 x 32 x 32\ntype: uint8\nspacing: 1 1 1\norigin: -15.5 -15.5 -15.5\n");
    fclose(f);
}

static scene *load(const char *dir, const char *volumes, tess_error *err)
{
    char path[512], text[2048];
    snprintf(path, sizeof path, "%s/scene.json", dir);
    snprintf(text, sizeof text,
             "{\"camera\": {\"eye\": [0, 0, 60], \"look_at\": [0, 0, 0], \"fov_deg\": 30},"
             " \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}], \"volumes\": [%s]}",
             volumes);
    return scene_parse_json(path, text, strlen(text), err);
}

static vec3 pixel_at(const scene *s, const accel *a, int x, int y)
{
    camera_desc c = {.eye = v3(0.f, 0.f, 60.f), .look_at = v3(0.f, 0.f, 0.f), .up = v3(0.f, 1.f, 0.f), .fov_deg = 30.f};
    render_view v = {.scene = s, .accel = a, .camera = camera_basis_make(&c, 65, 65), .shading = RENDER_SHADE_PHONG};
    float *rgb = calloc(65 * 65 * 3, sizeof *rgb);
    render_image(&v, 2, rgb, NULL);
    vec3 p = v3(rgb[3 * (y * 65 + x)], rgb[3 * (y * 65 + x) + 1], rgb[3 * (y * 65 + x) + 2]);
    free(rgb);
    return p;
}

Test(volume_scene, an_iso_surface_and_its_value_record)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "volscene");
    write_ball(dir);
    tess_error err = {{0}};
    scene *s = load(dir, "{\"file\": \"ball.txt\", \"iso\": [{\"value\": 100, \"color\": [1, 0, 0]}]}", &err);
    cr_assert(s, "%s", err.msg);
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    /* value 100 lies at r = 6 + 8 (1 - 100/200) = 10 */
    ray r = {v3(0.f, 0.f, 60.f), v3(0.f, 0.f, -1.f), 0.f, INFINITY};
    hit h;
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert_float_eq(h.t, 50.f, 0.1f, "the surface at r = 10: t %g", (double)h.t);
    vec3 c = pixel_at(s, a, 32, 32);
    cr_assert_gt(c.x, 0.5f, "the centre is the red surface, lit");
    cr_assert_lt(c.y, 0.1f);
    /* value 180: r = 6.8 */
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    txn_record rec = txn_value(0, 1, 180.f);
    cr_assert(txn_apply(&rec, &st, &err), "%s", err.msg);
    frame_state_sync_accel(&st, a);
    cr_assert(accel_intersect(a, &r, &h));
    cr_assert_float_eq(h.t, 53.2f, 0.1f, "after the record: t %g", (double)h.t);
    frame_state_finish(&st);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

Test(volume_scene, direct_rendering_is_composited_over_the_background)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "volscene-dvr");
    write_ball(dir);
    tess_error err = {{0}};
    scene *s = load(dir,
                    "{\"file\": \"ball.txt\", \"dvr\": {\"transfer\": {\"colors\": [[0, 0, 1, 0], [1, 0, 1, 0]],"
                    " \"opacity\": [[0, 0], [1, 0.2]], \"range\": [0, 200]}, \"step\": 0.5}}",
                    &err);
    cr_assert(s, "%s", err.msg);
    cr_assert_eq(s->medium_count, 1u);
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    vec3 centre = pixel_at(s, a, 32, 32), corner = pixel_at(s, a, 1, 1);
    cr_assert_gt(centre.y, 0.3f, "green glow through the ball's middle: %g", (double)centre.y);
    cr_assert_float_eq(corner.y, s->background.y, 1e-6f, "outside the ball: the background");
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

Test(volume_scene, mistakes_name_the_field)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "volscene-bad");
    write_ball(dir);
    const struct {
        const char *entry, *message;
    } cases[] = {
        {"{\"file\": \"ball.txt\"}", "field 'volumes[0]': give 'iso' (iso-surfaces), 'dvr' (volume rendering) or both"},
        {"{\"file\": \"ball.txt\", \"iso\": [{\"color\": [1, 0, 0]}]}", "field 'volumes[0].iso[0].value': required field is missing"},
        {"{\"file\": \"ball.txt\", \"iso\": []}", "field 'volumes[0].iso': 0 iso-surfaces (1 to 16)"},
        {"{\"file\": \"ball.txt\", \"iso\": [{\"value\": 1, \"method\": \"newton\"}]}", "field 'volumes[0].iso[0].method': unknown value 'newton'"},
        {"{\"file\": \"ball.txt\", \"dvr\": {\"transfer\": \"viridis\"}}", "field 'volumes[0].dvr.transfer': a transfer function needs opacity points"},
        {"{\"file\": \"ball.txt\", \"dvr\": {\"transfer\": \"ct-bone\", \"step\": 0}}", "field 'volumes[0].dvr.step': must be in"},
        {"{\"file\": \"ball.txt\", \"macrocell\": 2.5, \"iso\": [{\"value\": 1}]}", "field 'volumes[0].macrocell': must be a whole number of cells"},
        {"{\"file\": \"nothing.txt\", \"iso\": [{\"value\": 1}]}", "field 'volumes[0].file': "},
        {"{\"file\": \"ball.txt\", \"iso\": [{\"value\": 1, \"material\": \"gold\"}]}", "field 'volumes[0].iso[0].material': no material of that name"},
        {"{\"file\": \"ball.txt\", \"levels\": 3}", "field 'volumes[0].levels': unknown field"},
        {"{\"file\": \"ball.txt\", \"iso\": [{\"value\": 1, \"opacity\": 1.5}]}", "field 'volumes[0].iso[0].opacity': "},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        tess_error err = {{0}};
        scene *s = load(dir, cases[i].entry, &err);
        cr_expect_null(s, "case %zu loaded", i);
        scene_destroy(s);
        cr_expect(strstr(err.msg, cases[i].message), "case %zu: '%s' lacks '%s'", i, err.msg, cases[i].message);
    }
    support_remove_tmp_dir(dir);
}

/* A transfer record changes every directly rendered volume at the sync. */
Test(volume_scene, a_transfer_record_changes_the_volume_rendering)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "volscene-tf");
    write_ball(dir);
    tess_error err = {{0}};
    scene *s = load(dir, "{\"file\": \"ball.txt\", \"dvr\": {\"transfer\": \"mri-soft\"}}", &err);
    cr_assert(s, "%s", err.msg);
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    vec3 before = pixel_at(s, a, 32, 32);
    frame_state st;
    frame_state_init(&st, renderer_by_name("raytracer"), false, 1, s->instance_count);
    txn_record rec = txn_transfer("ct-bone");
    cr_assert(txn_apply(&rec, &st, &err), "%s", err.msg);
    frame_state_sync_accel(&st, a);
    vec3 after = pixel_at(s, a, 32, 32);
    cr_assert(before.x != after.x || before.y != after.y || before.z != after.z, "the picture did not change");
    frame_state_finish(&st);
    accel_destroy(a);
    scene_destroy(s);
    support_remove_tmp_dir(dir);
}

/* An iso-surface's "opacity" is where the view starts: through a red
 * surface at r = 10 of opacity 0.4 the green one at r = 6.8 shows; opaque,
 * it does not (tessera render, the pipeline that starts from the scene). */
Test(volume_scene, an_iso_surface_starts_with_its_opacity)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "volscene-opacity");
    write_ball(dir);
    float green[2];
    for (int translucent = 0; translucent < 2; translucent++) {
        char text[2048];
        snprintf(text, sizeof text,
                 "{\"camera\": {\"eye\": [0, 0, 60], \"look_at\": [0, 0, 0], \"fov_deg\": 30},"
                 " \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}],"
                 " \"volumes\": [{\"file\": \"ball.txt\", \"iso\": [{\"value\": 100, \"color\": [1, 0, 0]%s},"
                 " {\"value\": 180, \"color\": [0, 1, 0]}]}]}",
                 translucent ? ", \"opacity\": 0.4" : "");
        support_write_file(dir, "scene.json", text);
        char out[8192];
        int code = support_tessera(dir, 120, out, sizeof out,
                                   "render --scene %s/scene.json --size 65x65 --threads 2 --out %s/iso.exr");
        cr_assert_eq(code, 0, "%s", out);
        int w, h;
        float *rgb = support_read_image(dir, "iso.exr", &w, &h);
        cr_assert_eq(w, 65);
        green[translucent] = rgb[3 * (32 * 65 + 32) + 1];
        cr_assert_gt(rgb[3 * (32 * 65 + 32)], translucent ? 0.1f : 0.5f, "the red surface is in front");
        free(rgb);
    }
    cr_expect_lt(green[0], 0.01f, "opaque: the inner surface is hidden (%g)", (double)green[0]);
    cr_expect_gt(green[1], 0.2f, "opacity 0.4: the inner surface shows through (%g)", (double)green[1]);
    support_remove_tmp_dir(dir);
}

/* The scene counts its volumes and their samples, and the run's summary line says so (it said
 * "2 triangles, 0 spheres, 0 particles" for the MRI head); a scene without volumes is not
 * told it has none. */
Test(volume_scene, the_summary_line_counts_volumes)
{
    char dir[256];
    support_make_tmp_dir(dir, sizeof dir, "volsummary");
    write_ball(dir);
    tess_error err = {{0}};
    scene *s = load(dir,
                    "{\"file\": \"ball.txt\", \"iso\": [{\"value\": 100}, {\"value\": 150}]},"
                    " {\"file\": \"ball.txt\", \"dvr\": {\"transfer\": \"mri-soft\"}}",
                    &err);
    cr_assert(s, "%s", err.msg);
    cr_expect_eq(s->volume_count, 2u, "two entries, the first with two iso-surfaces");
    cr_expect_eq(s->volume_voxels, 2u * N * N * N);
    scene_destroy(s);
    support_write_file(dir, "scene.json",
                       "{\"camera\": {\"eye\": [0, 0, 60], \"look_at\": [0, 0, 0], \"fov_deg\": 30},"
                       " \"lights\": [{\"type\": \"directional\", \"direction\": [0, 0, 1]}], \"volumes\": ["
                       "{\"file\": \"ball.txt\", \"iso\": [{\"value\": 100}, {\"value\": 150}]},"
                       " {\"file\": \"ball.txt\", \"dvr\": {\"transfer\": \"mri-soft\"}}]}");
    char out[8192];
    int code = support_tessera(dir, 60, out, sizeof out, "render --scene %s/scene.json --size 8x8 --out %s/a.png");
    cr_expect_eq(code, 0, "%s", out);
    cr_expect(strstr(out, ": 0 triangles, 0 spheres, 0 particles, 2 volumes (0.0655 M voxels), 1 light; loaded in"),
              "%s", out);
    code = support_tessera(dir, 60, out, sizeof out, "render --size 8x8 --out %s/b.png");
    cr_expect_eq(code, 0, "%s", out);
    cr_expect(strstr(out, ": 9218 triangles, 7 spheres, 0 particles, 2 lights; loaded in"), "%s", out);
    support_remove_tmp_dir(dir);
}
