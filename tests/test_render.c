/* test_render.c - images against analytic results, thread-count determinism,
 * the framing rule, and reference images.
 *
 * Reference images (tests/ref/NAME.png) are compared in 8-bit sRGB: every channel
 * within REF_MAX_CHANNEL_DIFF and the mean absolute channel difference below
 * REF_MAX_MEAN_DIFF. TESSERA_UPDATE_REFS=1 rewrites them instead (after a change
 * that is meant to alter pictures: look at them before committing). */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"
#include "engine/load/scene_load.h"
#include "wall/dump.h"

#define REF_MAX_CHANNEL_DIFF 2   /* 8-bit levels: allows libm/rounding differences between machines */
#define REF_MAX_MEAN_DIFF 0.02   /* 8-bit levels averaged over all channels */

static const float pi = 3.14159265358979323846f;
static const double pi_d = 3.14159265358979323846;

/* Render a scene with a camera into a fresh buffer (caller frees). */
static float *render_scene(const scene *s, camera_desc cam, int w, int h, int threads, bool shadows)
{
    tess_error err = {{0}};
    accel *a = accel_build(s, threads, &err);
    cr_assert(a, "accel_build: %s", err.msg);
    float *rgb = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(rgb);
    render_view v = {s, a, camera_basis_make(&cam, w, h), shadows, RENDER_SHADE_PHONG, NULL, NULL};
    render_image(&v, threads, rgb, NULL);
    accel_destroy(a);
    return rgb;
}

static scene *empty_scene(vec3 background)
{
    scene *s = scene_create();
    cr_assert(s);
    s->background = background;
    s->ambient = v3(0.f, 0.f, 0.f);
    return s;
}

static int add_lambert(scene *s, vec3 albedo, float ambient)
{
    material m = material_default();
    m.model = MATERIAL_LAMBERT;
    m.diffuse = albedo;
    m.ambient = ambient;
    int id = scene_add_material(s, &m);
    cr_assert(id >= 0);
    return id;
}

/* A square in the plane y = height, side 2*half, normal +Y. */
static void add_floor(scene *s, float half, float height, int material_id)
{
    mesh *m = mesh_create();
    cr_assert(m);
    cr_assert(mesh_add_vertex(m, -half, height, -half) && mesh_add_vertex(m, half, height, -half) &&
              mesh_add_vertex(m, half, height, half) && mesh_add_vertex(m, -half, height, half));
    cr_assert(mesh_add_triangle(m, 0, 2, 1) && mesh_add_triangle(m, 0, 3, 2));
    cr_assert(scene_add_mesh(s, m, (uint32_t)material_id, "floor") >= 0);
}

Test(render, sphere_silhouette_area_matches_projection)
{
    /* A sphere of radius r at distance D on the optical axis subtends a cone of
     * half-angle asin(r/D); on the image plane at unit distance it is a disc of
     * radius tan(asin(r/D)), and one pixel is (2 tan(fov/2) / H)^2 of area. */
    const int w = 400, h = 300;
    const float r = 1.f, dist = 5.f, fov = 40.f;
    scene *s = empty_scene(v3(1.f, 0.f, 1.f));
    int mat = add_lambert(s, v3(0.5f, 0.5f, 0.5f), 1.f);
    s->ambient = v3(0.2f, 0.2f, 0.2f);
    cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 0.f), r, (uint32_t)mat) >= 0);
    camera_desc cam = {v3(0.f, 0.f, dist), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), fov};
    float *rgb = render_scene(s, cam, w, h, 2, true);
    long hits = 0;
    for (long i = 0; i < (long)w * h; i++)
        hits += !(rgb[3 * i] == 1.f && rgb[3 * i + 1] == 0.f && rgb[3 * i + 2] == 1.f);
    double disc_radius = tan(asin((double)r / dist));
    double pixel_side = 2.0 * tan(0.5 * fov * pi_d / 180.0) / h;
    double expected = pi_d * disc_radius * disc_radius / (pixel_side * pixel_side);
    double rel = fabs(hits - expected) / expected;
    cr_expect(rel < 0.003, "silhouette %ld px, expected %.1f px (relative error %.4f)", hits, expected, rel);
    free(rgb);
    scene_destroy(s);
}

/* Shade of the pixel at the image centre, looking straight down at a floor. */
static vec3 floor_centre_shade(const light *l, vec3 albedo, float camera_height)
{
    scene *s = empty_scene(v3(0.f, 0.f, 0.f));
    add_floor(s, 100.f, 0.f, add_lambert(s, albedo, 0.f));
    cr_assert(scene_add_light(s, l) >= 0);
    camera_desc cam = {v3(0.f, camera_height, 0.f), v3(0.f, 0.f, 0.f), v3(0.f, 0.f, -1.f), 30.f};
    /* odd size: the centre pixel's ray is exactly the optical axis */
    float *rgb = render_scene(s, cam, 9, 9, 1, true);
    size_t c = 3 * (4 * 9 + 4);
    vec3 out = v3(rgb[c], rgb[c + 1], rgb[c + 2]);
    free(rgb);
    scene_destroy(s);
    return out;
}

Test(render, lambert_plane_follows_cosine_law)
{
    const vec3 albedo = v3(0.8f, 0.5f, 0.25f);
    const float intensity = 1.7f;
    for (int deg = 0; deg <= 85; deg += 5) {
        float th = (float)deg * pi / 180.f;
        light l = {.kind = LIGHT_DIRECTIONAL, .direction = v3(sinf(th), cosf(th), 0.f), .color = v3(1.f, 1.f, 1.f),
                   .intensity = intensity, .casts_shadows = true};
        vec3 got = floor_centre_shade(&l, albedo, 3.f);
        float expect = intensity * cosf(th);
        cr_expect_float_eq(got.x, albedo.x * expect, 1e-5f, "theta %d: red %g vs %g", deg, got.x, albedo.x * expect);
        cr_expect_float_eq(got.y, albedo.y * expect, 1e-5f, "theta %d: green", deg);
        cr_expect_float_eq(got.z, albedo.z * expect, 1e-5f, "theta %d: blue", deg);
    }
}

Test(render, point_light_falls_off_with_inverse_square)
{
    const vec3 albedo = v3(1.f, 1.f, 1.f);
    for (int k = 1; k <= 4; k++) {
        float height = (float)k;
        light l = {.kind = LIGHT_POINT, .position = v3(0.f, height, 0.f), .color = v3(1.f, 1.f, 1.f),
                   .intensity = 10.f, .casts_shadows = true};
        /* the camera sits above the light; the light is a point and casts no image */
        vec3 got = floor_centre_shade(&l, albedo, 10.f);
        cr_expect_float_eq(got.x, 10.f / (height * height), 1e-5f, "height %g: %g", height, got.x);
    }
}

Test(render, light_below_the_plane_gives_only_ambient)
{
    light l = {.kind = LIGHT_DIRECTIONAL, .direction = v3(0.f, -1.f, 0.f), .color = v3(1.f, 1.f, 1.f),
               .intensity = 1.f, .casts_shadows = true};
    vec3 got = floor_centre_shade(&l, v3(1.f, 1.f, 1.f), 3.f);
    cr_expect_eq(got.x, 0.f);
}

Test(render, sphere_casts_a_shadow_on_the_floor)
{
    scene *s = empty_scene(v3(0.f, 0.f, 0.f));
    int mat = add_lambert(s, v3(1.f, 1.f, 1.f), 1.f);
    add_floor(s, 100.f, 0.f, mat);
    cr_assert(scene_add_sphere(s, v3(0.f, 2.f, 0.f), 0.5f, (uint32_t)mat) >= 0);
    light l = {.kind = LIGHT_DIRECTIONAL, .direction = v3(0.f, 1.f, 0.f), .color = v3(1.f, 1.f, 1.f),
               .intensity = 1.f, .casts_shadows = true};
    cr_assert(scene_add_light(s, &l) >= 0);
    s->ambient = v3(0.1f, 0.1f, 0.1f);
    /* look at the floor from the side, below the sphere's height, so the
     * sphere is out of view and the shadow disc at the origin is visible */
    camera_desc cam = {v3(0.f, 1.f, 4.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    const int w = 65, h = 65;
    float *rgb = render_scene(s, cam, w, h, 2, true);
    size_t centre = 3 * (32 * w + 32);
    cr_expect_float_eq(rgb[centre], 0.1f, 1e-6f, "floor under the sphere is in shadow: %g", rgb[centre]);
    size_t corner = 3 * ((h - 1) * w + 0); /* bottom-left: floor near the camera, lit */
    cr_expect_float_eq(rgb[corner], 1.1f, 1e-5f, "open floor is lit: %g", rgb[corner]);
    free(rgb);
    rgb = render_scene(s, cam, w, h, 2, false);
    cr_expect_float_eq(rgb[centre], 1.1f, 1e-5f, "without shadow rays the same point is lit");
    free(rgb);
    scene_destroy(s);
}

Test(render, default_scene_is_identical_for_any_thread_count)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "%s", err.msg);
    const int w = 123, h = 77; /* not a multiple of the tile size */
    float *ref = render_scene(s, s->camera, w, h, 1, true);
    const int counts[] = {2, 3, 7};
    for (size_t k = 0; k < sizeof counts / sizeof counts[0]; k++) {
        float *img = render_scene(s, s->camera, w, h, counts[k], true);
        cr_expect(memcmp(ref, img, (size_t)w * h * 3 * sizeof(float)) == 0, "%d threads differ from 1", counts[k]);
        free(img);
    }
    free(ref);
    scene_destroy(s);
}

Test(render, framing_puts_every_corner_inside_with_margin)
{
    vec3 lo = v3(-1.f, 2.f, -0.5f), hi = v3(3.f, 2.5f, 1.5f);
    const int w = 1920, h = 1080;
    camera_desc c = camera_frame_bounds(lo, hi, CAMERA_DEFAULT_VIEW_DIR, 40.f, w, h);
    camera_basis b = camera_basis_make(&c, w, h);
    float widest = 0.f;
    for (int k = 0; k < 8; k++) {
        vec3 p = v3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
        vec3 r = v3_sub(p, b.eye);
        float depth = v3_dot(r, b.forward);
        float sx = v3_dot(r, b.right) / v3_dot(b.right, b.right) / depth;
        float sy = v3_dot(r, b.up) / v3_dot(b.up, b.up) / depth;
        cr_expect(fabsf(sx) <= 1.f && fabsf(sy) <= 1.f, "corner %d projects outside: %g %g", k, sx, sy);
        widest = fmaxf(widest, fmaxf(fabsf(sx), fabsf(sy)));
    }
    /* the binding corner sits near the edge: 1/1.05 of the way at the distance
     * rule's margin (a little more, as corners nearer the eye move outwards) */
    cr_expect(widest > 0.9f && widest < 1.f, "binding corner at %g of the half-width", widest);
    vec3 view = v3_normalize(v3_sub(c.eye, c.look_at));
    vec3 want = v3_normalize(CAMERA_DEFAULT_VIEW_DIR);
    cr_expect_float_eq(v3_dot(view, want), 1.f, 1e-6f);
    cr_expect_eq(c.up.y, 1.f);
}

Test(render, framing_switches_up_to_z_when_looking_along_y)
{
    camera_desc c = camera_frame_bounds(v3(0.f, 0.f, 0.f), v3(1.f, 1.f, 1.f), v3(0.f, 1.f, 0.001f), 40.f, 64, 64);
    cr_expect_eq(c.up.z, 1.f);
    tess_error err = {{0}};
    cr_expect(camera_validate(&c, &err), "%s", err.msg);
}

/* Compare an image with a reference PNG in tests/ref, or rewrite it. */
static void check_reference(const char *name, const float *rgb, int w, int h)
{
    char ref_path[256], got_path[256];
    snprintf(ref_path, sizeof ref_path, "ref/%s.png", name);
    tess_error err = {{0}};
    const char *update = getenv("TESSERA_UPDATE_REFS");
    if (update && !strcmp(update, "1")) {
        cr_assert(dump_write_rgb(ref_path, w, h, rgb, &err), "%s", err.msg);
        cr_log_warn("rewrote %s", ref_path);
        return;
    }
    int rw, rh;
    uint8_t *ref;
    cr_assert(dump_read_rgb8(ref_path, &rw, &rh, &ref, &err), "%s", err.msg);
    cr_assert_eq(rw, w);
    cr_assert_eq(rh, h);
    long total = 0;
    int worst = 0;
    for (long i = 0; i < 3L * w * h; i++) {
        int d = abs((int)dump_srgb_encode_u8(rgb[i]) - (int)ref[i]);
        total += d;
        worst = d > worst ? d : worst;
    }
    double mean = (double)total / (3.0 * w * h);
    if (worst > REF_MAX_CHANNEL_DIFF || mean > REF_MAX_MEAN_DIFF) {
        snprintf(got_path, sizeof got_path, "/tmp/tessera-%s-got.png", name);
        dump_write_rgb(got_path, w, h, rgb, &err);
        cr_assert(false, "%s: max channel difference %d (limit %d), mean %.4f (limit %.3f); this run's image: %s", ref_path,
                worst, REF_MAX_CHANNEL_DIFF, mean, REF_MAX_MEAN_DIFF, got_path);
    }
    free(ref);
}

Test(render, default_scene_matches_reference)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "%s", err.msg);
    const int w = 240, h = 135;
    float *rgb = render_scene(s, s->camera, w, h, 2, true);
    check_reference("default_240x135", rgb, w, h);
    free(rgb);
    scene_destroy(s);
}

Test(render, example_scenes_match_references)
{
    /* two JSON scenes with their own cameras, and a mesh file framed by the peer rule */
    const char *files[] = {"spheres.json", "cornell_like.json", "data/cube.ply"};
    const char *names[] = {"spheres", "cornell_like", "cube_ply_framed"};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        char path[256];
        snprintf(path, sizeof path, "../configs/scenes/%s", files[k]);
        tess_error err = {{0}};
        scene *s = scene_load(path, &err);
        cr_assert(s, "%s", err.msg);
        const int w = 160, h = 120;
        camera_desc cam = s->camera;
        if (!s->has_camera) {
            vec3 lo, hi;
            scene_bounds(s, &lo, &hi);
            cam = camera_frame_bounds(lo, hi, CAMERA_DEFAULT_VIEW_DIR, CAMERA_DEFAULT_FOV_DEG, w, h);
        }
        float *rgb = render_scene(s, cam, w, h, 2, true);
        char ref[64];
        snprintf(ref, sizeof ref, "%s_%dx%d", names[k], w, h);
        check_reference(ref, rgb, w, h);
        free(rgb);
        scene_destroy(s);
    }
}

/* The packet renderer claims the results of render_shade on each ray alone:
 * check it bit for bit, both shading models, with shadows and point lights. */
Test(render, packets_shade_exactly_like_single_rays)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "%s", err.msg);
    accel *a = accel_build(s, 2, &err);
    cr_assert(a, "%s", err.msg);
    const int w = 97, h = 53;
    float *rgb = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(rgb);
    const render_shading models[] = {RENDER_SHADE_PHONG, RENDER_SHADE_EYELIGHT};
    for (size_t k = 0; k < 2; k++) {
        render_view v = {s, a, camera_basis_make(&s->camera, w, h), true, models[k], NULL, NULL};
        render_counts counts = {0};
        render_image(&v, 2, rgb, &counts);
        long differ = 0;
        uint64_t shadow_rays = 0, hits = 0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                ray r = {v.camera.eye, v3_normalize(camera_pixel_direction(&v.camera, x, y)), 0.f, FLT_MAX};
                hit hh;
                hits += accel_intersect(a, &r, &hh);
                vec3 c = render_shade(&v, &r, &shadow_rays);
                const float *got = rgb + 3 * ((size_t)y * w + x);
                differ += memcmp(&c.x, &got[0], sizeof(float)) || memcmp(&c.y, &got[1], sizeof(float)) ||
                          memcmp(&c.z, &got[2], sizeof(float));
            }
        cr_expect_eq(differ, 0, "shading model %zu: %ld pixels differ from render_shade", k, differ);
        cr_expect_eq(counts.primary_rays, (uint64_t)w * h);
        cr_expect_eq(counts.primary_hits, hits);
        cr_expect_eq(counts.shadow_rays, shadow_rays, "shadow rays: packets %llu, single %llu",
                     (unsigned long long)counts.shadow_rays, (unsigned long long)shadow_rays);
    }
    free(rgb);
    accel_destroy(a);
    scene_destroy(s);
}
