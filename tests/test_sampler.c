/* test_sampler.c - pixel samplers: parsing, where samples fall, the primary
 * rays built for them, and jittered images: equal to single-ray shading
 * averaged in the documented order, independent of how the image is cut into
 * tiles and threads, fixed by the seed, and converging to analytic pixel
 * coverage at sharp edges within the stated stratified-sampling bound. */
#include <criterion/criterion.h>
#include <criterion/logging.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/scene/accel.h"
#include "engine/accel/packet.h"
#include "engine/render/render.h"
#include "engine/render/sampler.h"
#include "engine/scene/scene.h"

/* ---- parsing ---- */

Test(sampler, names_parse_and_round_trip)
{
    tess_error err = {{0}};
    pixel_sampler s;
    cr_assert(pixel_sampler_from_name("single", &s, &err), "%s", err.msg);
    cr_expect_eq(s.kind, PIXEL_SAMPLER_SINGLE);
    cr_assert(pixel_sampler_from_name("jittered", &s, &err), "%s", err.msg);
    cr_expect_eq(s.kind, PIXEL_SAMPLER_JITTERED);
    cr_expect_eq(s.k, PIXEL_SAMPLER_DEFAULT_K);
    cr_expect_eq(s.seed, PIXEL_SAMPLER_DEFAULT_SEED);
    cr_assert(pixel_sampler_from_name("jittered:07", &s, &err), "%s", err.msg);
    cr_expect_eq(s.k, 7);
    for (int k = 1; k <= PIXEL_SAMPLER_MAX_K; k++) {
        char name[PIXEL_SAMPLER_NAME_BYTES];
        pixel_sampler want = pixel_sampler_jittered(k, 0), got;
        pixel_sampler_name(&want, name, sizeof name);
        cr_assert(pixel_sampler_from_name(name, &got, &err), "'%s': %s", name, err.msg);
        cr_expect(got.kind == want.kind && got.k == k, "'%s' reads back as k = %d", name, got.k);
        cr_expect(pixel_sampler_validate(&got, &err), "%s", err.msg);
    }
    char name[PIXEL_SAMPLER_NAME_BYTES];
    pixel_sampler single = pixel_sampler_single();
    pixel_sampler_name(&single, name, sizeof name);
    cr_expect_str_eq(name, "single");
}

/* Parse `text`, expect failure with every one of the (up to two) fragments in
 * the message and *out untouched. */
static void expect_parse_error(const char *text, const char *fragment, const char *fragment2)
{
    tess_error err = {{0}};
    pixel_sampler s = pixel_sampler_jittered(5, 99u);
    cr_expect(!pixel_sampler_from_name(text, &s, &err), "'%s' must be rejected", text ? text : "(null)");
    cr_expect(strstr(err.msg, fragment), "'%s': message \"%s\" should contain \"%s\"", text ? text : "(null)", err.msg,
              fragment);
    if (fragment2)
        cr_expect(strstr(err.msg, fragment2), "'%s': message \"%s\" should contain \"%s\"", text ? text : "(null)",
                  err.msg, fragment2);
    cr_expect(s.kind == PIXEL_SAMPLER_JITTERED && s.k == 5 && s.seed == 99u, "'%s': *out untouched", text);
}

Test(sampler, parse_errors_say_what_is_wrong)
{
    expect_parse_error("jittered:0", "'jittered:0': K = 0 is out of range", "1..16");
    expect_parse_error("jittered:17", "K = 17 is out of range", "1..16");
    expect_parse_error("jittered:99999999999999999999", "K = 99999999999999999999 is out of range", NULL);
    expect_parse_error("jittered:x", "'jittered:x': K 'x' is not a whole number", "jittered:K");
    expect_parse_error("jittered:4x", "K '4x' is not a whole number", NULL);
    expect_parse_error("jittered:-3", "K '-3' is not a whole number", NULL);
    expect_parse_error("jittered: 4", "is not a whole number", NULL);
    expect_parse_error("jittered:", "missing K", NULL);
    expect_parse_error("single:2", "single takes no parameter", NULL);
    expect_parse_error("stratified", "unknown pixel sampler 'stratified'", "expected single, jittered");
    expect_parse_error("Jittered", "unknown pixel sampler 'Jittered'", NULL);
    expect_parse_error("", "empty name", NULL);
    expect_parse_error(NULL, "empty name", NULL);
}

Test(sampler, validate_rejects_bad_strata)
{
    tess_error err = {{0}};
    pixel_sampler s = pixel_sampler_jittered(0, 0);
    cr_expect(!pixel_sampler_validate(&s, &err));
    cr_expect(strstr(err.msg, "k = 0 is out of range"), "%s", err.msg);
    tess_error err2 = {{0}};
    s.k = 17;
    cr_expect(!pixel_sampler_validate(&s, &err2));
    cr_expect(strstr(err2.msg, "k = 17"), "%s", err2.msg);
    s = pixel_sampler_single();
    s.k = 0; /* ignored by single */
    cr_expect(pixel_sampler_validate(&s, NULL));
}

/* ---- sample positions ---- */

/* Which stratum of k of `pixel` p is in, exactly (see sampler.c): -1 outside the pixel. */
static int stratum_of(float p, int pixel, int k)
{
    double scaled = ((double)p - (double)pixel) * (double)k;
    return scaled >= 0.0 && scaled < (double)k ? (int)floor(scaled) : -1;
}

Test(sampler, positions_stay_inside_their_strata)
{
    /* large coordinates included: there a float step is 2^-5 of a pixel, and
     * rounding to float alone would put samples on stratum borders */
    const int coords[] = {0, 1, 2, 7, 63, 1919, 4095, 65535, 262143, 524287};
    const uint32_t seeds[] = {0u, 1u, 0xdeadbeefu};
    long outside = 0, tried = 0;
    for (int k = 1; k <= PIXEL_SAMPLER_MAX_K; k++)
        for (size_t sd = 0; sd < 3; sd++) {
            pixel_sampler s = pixel_sampler_jittered(k, seeds[sd]);
            for (size_t a = 0; a < sizeof coords / sizeof coords[0]; a++)
                for (size_t b = 0; b < sizeof coords / sizeof coords[0]; b += 3)
                    for (int j = 0; j < k; j++)
                        for (int i = 0; i < k; i++) {
                            float px, py;
                            pixel_sampler_position(&s, coords[a], coords[b], i, j, &px, &py);
                            outside += stratum_of(px, coords[a], k) != i || stratum_of(py, coords[b], k) != j;
                            tried++;
                        }
        }
    cr_expect_eq(outside, 0, "%ld of %ld samples outside their stratum", outside, tried);
}

Test(sampler, block_positions_are_the_per_pixel_positions)
{
    const pixel_sampler samplers[] = {pixel_sampler_single(), pixel_sampler_jittered(5, 8u)};
    for (size_t k = 0; k < 2; k++) {
        float bx[64], by[64];
        pixel_sampler_block_positions(&samplers[k], 17, 9, 8, 5, 3, 1, bx, by);
        long differ = 0;
        for (int r = 0; r < 40; r++) {
            float px, py;
            pixel_sampler_position(&samplers[k], 17 + r % 8, 9 + r / 8, 3, 1, &px, &py);
            differ += memcmp(&px, &bx[r], sizeof px) != 0 || memcmp(&py, &by[r], sizeof py) != 0;
        }
        cr_expect_eq(differ, 0, "sampler %zu: %ld block positions differ", k, differ);
    }
}

Test(sampler, k1_jitter_stays_inside_the_pixel_and_moves)
{
    pixel_sampler s = pixel_sampler_jittered(1, 3u);
    long outside = 0, at_centre = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            float px, py;
            pixel_sampler_position(&s, x, y, 0, 0, &px, &py);
            outside += !(px >= (float)x && px < (float)(x + 1) && py >= (float)y && py < (float)(y + 1));
            at_centre += px == (float)x + 0.5f && py == (float)y + 0.5f;
        }
    cr_expect_eq(outside, 0);
    cr_expect(at_centre < 4, "%ld of 4096 samples at the exact centre: the jitter is not applied", at_centre);
    pixel_sampler single = pixel_sampler_single();
    float px, py;
    pixel_sampler_position(&single, 12, 34, 0, 0, &px, &py);
    cr_expect(px == 12.5f && py == 34.5f, "single samples the centre");
}

/* Pearson correlation of two series. */
static double correlation(const double *a, const double *b, size_t n)
{
    double ma = 0, mb = 0;
    for (size_t i = 0; i < n; i++)
        ma += a[i], mb += b[i];
    ma /= (double)n, mb /= (double)n;
    double sab = 0, saa = 0, sbb = 0;
    for (size_t i = 0; i < n; i++) {
        sab += (a[i] - ma) * (b[i] - mb);
        saa += (a[i] - ma) * (a[i] - ma);
        sbb += (b[i] - mb) * (b[i] - mb);
    }
    return sab / sqrt(saa * sbb);
}

Test(sampler, jitter_is_uniform_and_uncorrelated)
{
    /* 256 x 256 pixels, one stratum: u and v each over 32 bins (chi-square,
     * 31 degrees of freedom: 70 is p ~ 1e-4), and no correlation between u
     * and v, between neighbouring pixels, or between strata of one pixel
     * (|r| < 0.02, ~5 standard errors of 1/256). Deterministic: cannot flake. */
    enum { side = 256, n = side * side, bins = 32 };
    double *u = malloc(n * sizeof *u), *v = malloc(n * sizeof *v), *u_next = malloc(n * sizeof *u_next),
           *u_stratum = malloc(n * sizeof *u_stratum);
    cr_assert(u && v && u_next && u_stratum);
    long hist_u[bins] = {0}, hist_v[bins] = {0};
    for (int y = 0; y < side; y++)
        for (int x = 0; x < side; x++) {
            float fu, fv, gu, gv, hu, hv;
            sampler_jitter(42u, x, y, 0, 0, &fu, &fv);
            sampler_jitter(42u, x + 1, y, 0, 0, &gu, &gv);
            sampler_jitter(42u, x, y, 1, 0, &hu, &hv);
            int i = y * side + x;
            u[i] = fu, v[i] = fv, u_next[i] = gu, u_stratum[i] = hu;
            cr_assert(fu >= 0.f && fu < 1.f && fv >= 0.f && fv < 1.f);
            hist_u[(int)(fu * bins)]++;
            hist_v[(int)(fv * bins)]++;
        }
    double chi_u = 0, chi_v = 0, expect = (double)n / bins;
    for (int b = 0; b < bins; b++) {
        chi_u += (hist_u[b] - expect) * (hist_u[b] - expect) / expect;
        chi_v += (hist_v[b] - expect) * (hist_v[b] - expect) / expect;
    }
    cr_expect(chi_u < 70.0 && chi_v < 70.0, "chi-square u %.1f, v %.1f over 31 degrees of freedom", chi_u, chi_v);
    double r_uv = correlation(u, v, n), r_nb = correlation(u, u_next, n), r_st = correlation(u, u_stratum, n);
    cr_expect(fabs(r_uv) < 0.02 && fabs(r_nb) < 0.02 && fabs(r_st) < 0.02,
              "correlations: u-v %.4f, neighbour %.4f, stratum %.4f", r_uv, r_nb, r_st);
    free(u);
    free(v);
    free(u_next);
    free(u_stratum);
}

/* ---- primary rays at sub-pixel positions ---- */

static camera_basis test_camera(int w, int h)
{
    camera_desc c = {v3(0.3f, 0.2f, 5.f), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 50.f};
    return camera_basis_make(&c, w, h);
}

/* Fill a packet with an 8 x 8 block's jittered samples at (x0, y0), stratum (1, 2) of 3. */
static void jittered_block(ray_packet *p, const camera_basis *cam, int x0, int y0, float *px, float *py)
{
    pixel_sampler s = pixel_sampler_jittered(3, 5u);
    for (int r = 0; r < 64; r++)
        pixel_sampler_position(&s, x0 + r % 8, y0 + r / 8, 1, 2, &px[r], &py[r]);
    packet_primary_at(p, cam, px, py, 64);
}

Test(sampler, packet_primary_at_builds_the_single_ray_builders_rays)
{
    static ray_packet p;
    const camera_basis cam = test_camera(64, 48);
    float px[64], py[64];
    const int corners[][2] = {{0, 0}, {28, 20}, {56, 40}, {32, 0}};
    for (size_t c = 0; c < sizeof corners / sizeof corners[0]; c++) {
        jittered_block(&p, &cam, corners[c][0], corners[c][1], px, py);
        cr_expect_eq(p.count, 64u);
        long differ = 0, not_unit = 0;
        for (uint32_t i = 0; i < 64; i++) {
            ray want = packet_primary_ray_at(&cam, px[i], py[i]), got = packet_get_ray(&p, i);
            differ += memcmp(&want.dir, &got.dir, sizeof want.dir) != 0 || memcmp(&want.org, &got.org, sizeof want.org) ||
                      got.t_near != 0.f || got.t_far != FLT_MAX;
            not_unit += fabsf(v3_length(got.dir) - 1.f) > 1e-6f;
        }
        cr_expect_eq(differ, 0, "block %zu: %ld rays differ from packet_primary_ray_at", c, differ);
        cr_expect_eq(not_unit, 0);
        cr_expect_eq(p.org_x[0], cam.eye.x);
        /* the facts it claims are exactly what packet_detect_facts finds */
        uint32_t claimed = p.flags & (PACKET_COMMON_ORIGIN | PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED);
        packet_detect_facts(&p);
        uint32_t found = p.flags & (PACKET_COMMON_ORIGIN | PACKET_CONSTANT_SIGNS | PACKET_NORMALIZED);
        cr_expect_eq(claimed, found, "block %zu: facts claimed %#x, found %#x", c, claimed, found);
    }
    /* the block around the image centre straddles the optical axis (signs
     * change); a corner block does not */
    jittered_block(&p, &cam, 28, 20, px, py);
    cr_expect(!(p.flags & PACKET_CONSTANT_SIGNS), "the centre block has mixed signs");
    jittered_block(&p, &cam, 0, 0, px, py);
    cr_expect(p.flags & PACKET_CONSTANT_SIGNS, "a corner block keeps its signs");
}

Test(sampler, pixel_centres_give_packet_primarys_directions_to_an_ulp)
{
    static ray_packet centre, at;
    const camera_basis cam = test_camera(37, 23);
    float px[64], py[64];
    packet_primary(&centre, &cam, 16, 8, 8, 8);
    for (int r = 0; r < 64; r++)
        px[r] = (float)(16 + r % 8) + 0.5f, py[r] = (float)(8 + r / 8) + 0.5f;
    packet_primary_at(&at, &cam, px, py, 64);
    float worst = 0.f;
    for (int r = 0; r < 64; r++) {
        worst = fmaxf(worst, fabsf(centre.dir_x[r] - at.dir_x[r]));
        worst = fmaxf(worst, fabsf(centre.dir_y[r] - at.dir_y[r]));
        worst = fmaxf(worst, fabsf(centre.dir_z[r] - at.dir_z[r]));
    }
    cr_expect(worst <= 4.f * FLT_EPSILON, "largest component difference %g", worst);
}

/* ---- jittered images ---- */

typedef struct test_view {
    scene *scene;
    accel *accel;
    render_view view;
} test_view;

static test_view view_of(scene *s, camera_desc cam, int w, int h, render_shading shading)
{
    tess_error err = {{0}};
    test_view t = {s, accel_build(s, 2, &err), {0}};
    cr_assert(t.accel, "accel_build: %s", err.msg);
    t.view = (render_view){s, t.accel, camera_basis_make(&cam, w, h), true, shading, NULL, NULL};
    return t;
}

static test_view default_view(int w, int h, render_shading shading)
{
    tess_error err = {{0}};
    scene *s = scene_create_default(&err);
    cr_assert(s, "%s", err.msg);
    return view_of(s, s->camera, w, h, shading);
}

static void view_destroy(test_view *t)
{
    accel_destroy(t->accel);
    scene_destroy(t->scene);
}

static float *image_buffer(const render_view *v)
{
    float *rgb = calloc((size_t)v->camera.width_px * (size_t)v->camera.height_px * 3, sizeof(float));
    cr_assert(rgb);
    return rgb;
}

static size_t image_bytes(const render_view *v)
{
    return (size_t)v->camera.width_px * (size_t)v->camera.height_px * 3 * sizeof(float);
}

/* The image cut into tw x th tiles (the last row and column shorter), each
 * rendered on its own. */
static void render_in_tiles(const render_view *v, const pixel_sampler *s, int tw, int th, float *rgb,
                            render_counts *counts)
{
    const int w = v->camera.width_px, h = v->camera.height_px;
    for (int y0 = 0; y0 < h; y0 += th)
        for (int x0 = 0; x0 < w; x0 += tw)
            render_tile_sampled(v, s, x0, y0, x0 + tw < w ? x0 + tw : w, y0 + th < h ? y0 + th : h, rgb, counts);
}

Test(sampler, single_is_render_tile_bit_for_bit)
{
    test_view t = default_view(45, 29, RENDER_SHADE_PHONG);
    float *want = image_buffer(&t.view), *got = image_buffer(&t.view);
    render_counts cw = {0}, cg = {0};
    render_tile(&t.view, 0, 0, 45, 29, want, &cw);
    pixel_sampler single = pixel_sampler_single();
    render_in_tiles(&t.view, &single, 7, 5, got, &cg);
    cr_expect(memcmp(want, got, image_bytes(&t.view)) == 0, "single sampler differs from render_tile");
    cr_expect(cw.primary_rays == cg.primary_rays && cw.shadow_rays == cg.shadow_rays);
    free(want);
    free(got);
    view_destroy(&t);
}

/* Pixel (x, y) the way sampler.h defines it: render_shade on the ray of each
 * sample, summed in stratum row-major order from +0, divided by k^2. */
static vec3 reference_pixel(const render_view *v, const pixel_sampler *s, int x, int y, uint64_t *shadow_rays)
{
    const int k = pixel_sampler_strata(s);
    vec3 sum = v3(0.f, 0.f, 0.f);
    for (int j = 0; j < k; j++)
        for (int i = 0; i < k; i++) {
            float px, py;
            pixel_sampler_position(s, x, y, i, j, &px, &py);
            ray r = packet_primary_ray_at(&v->camera, px, py);
            sum = v3_add(sum, render_shade(v, &r, shadow_rays));
        }
    const float n = (float)(k * k);
    return v3(sum.x / n, sum.y / n, sum.z / n);
}

Test(sampler, jittered_pixels_are_means_of_single_ray_shading)
{
    const render_shading models[] = {RENDER_SHADE_PHONG, RENDER_SHADE_EYELIGHT};
    const int ks[] = {2, 3};
    for (size_t m = 0; m < 2; m++)
        for (size_t kk = 0; kk < 2; kk++) {
            test_view t = default_view(29, 19, models[m]);
            pixel_sampler s = pixel_sampler_jittered(ks[kk], 11u);
            float *rgb = image_buffer(&t.view);
            render_counts counts = {0};
            render_image_sampled(&t.view, &s, 2, rgb, &counts);
            long differ = 0;
            uint64_t shadow_rays = 0;
            for (int y = 0; y < 19; y++)
                for (int x = 0; x < 29; x++) {
                    vec3 c = reference_pixel(&t.view, &s, x, y, &shadow_rays);
                    const float *got = rgb + 3 * ((size_t)y * 29 + (size_t)x);
                    differ += memcmp(&c.x, &got[0], sizeof(float)) || memcmp(&c.y, &got[1], sizeof(float)) ||
                              memcmp(&c.z, &got[2], sizeof(float));
                }
            cr_expect_eq(differ, 0, "model %zu, k %d: %ld pixels differ from the mean of render_shade", m, ks[kk],
                         differ);
            cr_expect_eq(counts.primary_rays, (uint64_t)(29 * 19 * ks[kk] * ks[kk]));
            cr_expect_eq(counts.shadow_rays, shadow_rays, "shadow rays: packets %llu, single %llu",
                         (unsigned long long)counts.shadow_rays, (unsigned long long)shadow_rays);
            free(rgb);
            view_destroy(&t);
        }
}

Test(sampler, jittered_image_does_not_depend_on_tiles_or_threads)
{
    test_view t = default_view(45, 29, RENDER_SHADE_PHONG);
    pixel_sampler s = pixel_sampler_jittered(3, 2024u);
    float *whole = image_buffer(&t.view), *cut = image_buffer(&t.view);
    render_counts c_whole = {0};
    render_tile_sampled(&t.view, &s, 0, 0, 45, 29, whole, &c_whole);
    const int splits[][2] = {{5, 3}, {7, 11}, {13, 1}, {1, 9}, {16, 16}, {3, 29}};
    for (size_t k = 0; k < sizeof splits / sizeof splits[0]; k++) {
        memset(cut, 0, image_bytes(&t.view));
        render_counts c = {0};
        render_in_tiles(&t.view, &s, splits[k][0], splits[k][1], cut, &c);
        cr_expect(memcmp(whole, cut, image_bytes(&t.view)) == 0, "%dx%d tiles differ from one tile", splits[k][0],
                  splits[k][1]);
        cr_expect_eq(c.primary_rays, c_whole.primary_rays);
        cr_expect_eq(c.shadow_rays, c_whole.shadow_rays);
    }
    const int threads[] = {1, 3};
    for (size_t k = 0; k < 2; k++) {
        memset(cut, 0, image_bytes(&t.view));
        render_image_sampled(&t.view, &s, threads[k], cut, NULL);
        cr_expect(memcmp(whole, cut, image_bytes(&t.view)) == 0, "render_image_sampled on %d threads differs",
                  threads[k]);
    }
    free(whole);
    free(cut);
    view_destroy(&t);
}

Test(sampler, the_seed_fixes_the_image)
{
    test_view t = default_view(40, 24, RENDER_SHADE_PHONG);
    pixel_sampler a = pixel_sampler_jittered(2, 1u), b = pixel_sampler_jittered(2, 2u);
    float *first = image_buffer(&t.view), *again = image_buffer(&t.view), *other = image_buffer(&t.view);
    render_image_sampled(&t.view, &a, 2, first, NULL);
    render_image_sampled(&t.view, &a, 2, again, NULL);
    render_image_sampled(&t.view, &b, 2, other, NULL);
    cr_expect(memcmp(first, again, image_bytes(&t.view)) == 0, "the same seed gives the same image");
    long differ = 0;
    for (size_t i = 0; i < (size_t)40 * 24 * 3; i++)
        differ += first[i] != other[i];
    cr_expect(differ > 40, "seeds 1 and 2 differ in only %ld channel values", differ);
    free(first);
    free(again);
    free(other);
    view_destroy(&t);
}

/* A scene whose surfaces all show 1 and whose background is 0: ambient light
 * 1, Lambert albedo 1, ambient fraction 1, no lights. A pixel's value is then
 * the fraction of its samples that hit. */
static scene *coverage_scene(int *material_id)
{
    scene *s = scene_create();
    cr_assert(s);
    s->background = v3(0.f, 0.f, 0.f);
    s->ambient = v3(1.f, 1.f, 1.f);
    material m = material_default();
    m.model = MATERIAL_LAMBERT;
    m.diffuse = v3(1.f, 1.f, 1.f);
    m.ambient = 1.f;
    *material_id = scene_add_material(s, &m);
    cr_assert(*material_id >= 0);
    return s;
}

/* Stratified estimate of a pixel cut by one straight edge: only the k strata
 * (of k^2) the edge crosses are random, each a Bernoulli sample with weight
 * 1/k^2, so the pixel's standard deviation is at most sqrt(k / 4) / k^2 =
 * 1 / (2 k^1.5) (1/16 for k = 4), and the mean of N such pixels is within
 * 4 / (2 k^1.5 sqrt(N)) of the true coverage except with probability < 1e-4. */
static double edge_mean_bound(int k, int pixels) { return 4.0 / (2.0 * pow(k, 1.5) * sqrt((double)pixels)); }

Test(sampler, jittered_edge_pixels_converge_to_their_coverage)
{
    /* A triangle in the plane z = 0 facing the camera, with a vertical edge
     * that covers exactly 0.3 of every pixel of column 40: the plane is
     * parallel to the image, so pixel x maps linearly to world x. */
    const int w = 64, h = 64, k = 4, edge_column = 40;
    const double coverage = 0.3;
    const float dist = 10.f;
    camera_desc cam = {v3(0.f, 0.f, dist), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), 40.f};
    camera_basis b = camera_basis_make(&cam, w, h);
    cr_assert(b.right.y == 0.f && b.right.z == 0.f && b.right.x > 0.f, "right is +x");
    double edge_px = edge_column + coverage;
    float edge_x = (float)(dist * b.right.x * (2.0 * edge_px / w - 1.0));
    int mat;
    scene *s = coverage_scene(&mat);
    mesh *m = mesh_create();
    cr_assert(m);
    cr_assert(mesh_add_vertex(m, edge_x, -50.f, 0.f) && mesh_add_vertex(m, edge_x, 50.f, 0.f) &&
              mesh_add_vertex(m, -50.f, 0.f, 0.f) && mesh_add_triangle(m, 0, 1, 2));
    cr_assert(scene_add_mesh(s, m, (uint32_t)mat, "half-plane") >= 0);
    test_view t = view_of(s, cam, w, h, RENDER_SHADE_PHONG);
    float *rgb = image_buffer(&t.view);
    const uint32_t seeds[] = {0u, 1u, 77u};
    for (size_t sd = 0; sd < 3; sd++) {
        pixel_sampler sampler = pixel_sampler_jittered(k, seeds[sd]);
        render_image_sampled(&t.view, &sampler, 2, rgb, NULL);
        long wrong_inside = 0, wrong_outside = 0, outside_strata_bounds = 0;
        double edge_sum = 0.0, image_sum = 0.0;
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                float value = rgb[3 * ((size_t)y * w + (size_t)x)];
                image_sum += value;
                if (x < edge_column)
                    wrong_inside += value != 1.f;
                else if (x > edge_column)
                    wrong_outside += value != 0.f;
                else {
                    edge_sum += value;
                    /* stratum column 0 always hits, 2 and 3 never: 4/16 .. 8/16,
                     * strictly between background (0) and surface (1) */
                    outside_strata_bounds += !(value >= 0.25f && value <= 0.5f);
                }
            }
        cr_expect_eq(wrong_inside, 0, "seed %u: covered pixels not exactly the surface colour", seeds[sd]);
        cr_expect_eq(wrong_outside, 0, "seed %u: uncovered pixels not exactly the background", seeds[sd]);
        cr_expect_eq(outside_strata_bounds, 0, "seed %u: edge pixels outside [0.25, 0.5]", seeds[sd]);
        double bound = edge_mean_bound(k, h), edge_mean = edge_sum / h;
        cr_log_info("seed %u: edge column mean %.4f (coverage %.2f, bound %.4f)", seeds[sd], edge_mean, coverage, bound);
        cr_expect(fabs(edge_mean - coverage) <= bound, "seed %u: edge column mean %.4f, coverage %.2f +- %.4f",
                  seeds[sd], edge_mean, coverage, bound);
        double image_mean = image_sum / (w * h), want = (edge_column + coverage) / w;
        cr_expect(fabs(image_mean - want) <= bound / w, "seed %u: image mean %.5f, analytic %.5f", seeds[sd],
                  image_mean, want);
    }
    free(rgb);
    view_destroy(&t);
}

Test(sampler, jittered_sphere_area_matches_its_projection)
{
    /* A sphere of radius r at distance D on the optical axis projects to a disc
     * of radius tan(asin(r / D)) at unit distance (see test_render.c); summed
     * pixel values estimate its area in pixels. Only pixels the outline
     * crosses are random: at most the annulus of half-width sqrt(2)/2 px around
     * the outline, 2 sqrt(2) pi R + 4 pixels, each with standard deviation
     * <= 1 / (2 k^1.5); allow 4 standard deviations of the sum, plus 0.5 px^2
     * for the float arithmetic of ray generation. */
    const int w = 64, h = 64, k = 4;
    const double r = 1.0, dist = 5.0, fov = 30.0, pi = 3.14159265358979323846;
    int mat;
    scene *s = coverage_scene(&mat);
    cr_assert(scene_add_sphere(s, v3(0.f, 0.f, 0.f), (float)r, (uint32_t)mat) >= 0);
    camera_desc cam = {v3(0.f, 0.f, (float)dist), v3(0.f, 0.f, 0.f), v3(0.f, 1.f, 0.f), (float)fov};
    test_view t = view_of(s, cam, w, h, RENDER_SHADE_PHONG);
    float *rgb = image_buffer(&t.view);
    pixel_sampler sampler = pixel_sampler_jittered(k, 9u);
    render_image_sampled(&t.view, &sampler, 2, rgb, NULL);
    double area = 0.0;
    long partial = 0;
    for (long i = 0; i < (long)w * h; i++) {
        area += rgb[3 * i];
        partial += rgb[3 * i] > 0.f && rgb[3 * i] < 1.f;
    }
    double pixel_side = 2.0 * tan(0.5 * fov * pi / 180.0) / h;
    double radius_px = tan(asin(r / dist)) / pixel_side;
    double expected = pi * radius_px * radius_px;
    double boundary = 2.0 * sqrt(2.0) * pi * radius_px + 4.0;
    double bound = 4.0 * sqrt(boundary) / (2.0 * pow(k, 1.5)) + 0.5;
    cr_log_info("sphere: area %.3f px^2, projection %.3f, bound %.3f, %ld partial pixels", area, expected, bound,
                partial);
    cr_expect(fabs(area - expected) <= bound, "area %.3f px^2, projection %.3f +- %.3f", area, expected, bound);
    cr_expect(partial > pi * radius_px, "only %ld pixels are partly covered along a %.1f px outline", partial,
              2.0 * pi * radius_px);
    free(rgb);
    view_destroy(&t);
}
