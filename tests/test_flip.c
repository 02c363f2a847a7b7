/* test_flip.c - LDR-FLIP (metrics/flip.h), its pooling and plain
 * differences (metrics/image_stats.h) and the error map picture
 * (metrics/error_map.h): exact zeros for identical images, the value NVlabs'
 * implementation gives for a known pair, monotone responses to noise
 * amplitude and viewing distance, thread-count independence, bad input. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "flip_pair.h"
#include "metrics/error_map.h"
#include "metrics/flip.h"
#include "metrics/image_stats.h"
#include "wall/dump.h"

TestSuite(flip, .timeout = 120);

/* A deterministic uniform value in [-1, 1]. */
static double lcg_signed(uint32_t *seed)
{
    *seed = *seed * 1664525u + 1013904223u;
    return (double)(*seed >> 8) / (double)(1u << 23) - 1.0;
}

/* A test image: smooth ramps and a checker of 4-pixel squares, linear RGB in [0, 1]. */
static float *pattern(int w, int h)
{
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    cr_assert(rgb);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            float *p = rgb + 3 * ((size_t)y * w + x);
            float checker = ((x / 4 + y / 4) & 1) ? 0.3f : 0.0f;
            p[0] = 0.1f + 0.6f * (float)x / (float)w;
            p[1] = 0.2f + 0.5f * (float)y / (float)h;
            p[2] = 0.15f + checker;
        }
    return rgb;
}

/* `src` plus uniform noise of `amplitude` (linear), independent per value, clamped to [0, 1]. */
static float *noisy(const float *src, int w, int h, double amplitude, uint32_t seed)
{
    size_t n = (size_t)w * h * 3;
    float *rgb = malloc(n * sizeof *rgb);
    cr_assert(rgb);
    for (size_t i = 0; i < n; i++) {
        double v = src[i] + amplitude * lcg_signed(&seed);
        rgb[i] = (float)(v < 0.0 ? 0.0 : v > 1.0 ? 1.0 : v);
    }
    return rgb;
}

static double flip_mean(const float *a, const float *b, int w, int h, double ppd)
{
    float *map = malloc((size_t)w * h * sizeof *map);
    cr_assert(map);
    tess_error err = {{0}};
    cr_assert(flip_ldr_map(a, b, w, h, ppd, 2, map, &err), "%s", err.msg);
    stats_pooled s;
    cr_assert(stats_pool(map, (size_t)w * h, &s, &err), "%s", err.msg);
    free(map);
    return s.mean;
}

Test(flip, identical_images_give_exactly_zero)
{
    const int w = 70, h = 50;
    float *a = pattern(w, h), *b = noisy(a, w, h, 0.3, 7); /* any content: b is the "identical" pair with itself */
    float *map = malloc((size_t)w * h * sizeof *map);
    tess_error err = {{0}};
    const float *images[] = {a, b};
    for (int k = 0; k < 2; k++) {
        cr_assert(flip_ldr_map(images[k], images[k], w, h, FLIP_DEFAULT_PPD, 2, map, &err), "%s", err.msg);
        for (int i = 0; i < w * h; i++)
            cr_assert(map[i] == 0.0f, "pixel %d: %g, not 0", i, map[i]);
        stats_pooled s;
        cr_assert(stats_pool(map, (size_t)w * h, &s, &err));
        cr_expect(s.mean == 0.0 && s.median == 0.0 && s.q3 == 0.0);
        stats_rgb_diff d;
        stats_rgb_diff_compute(images[k], images[k], (size_t)w * h, &d);
        cr_expect(d.rmse == 0.0 && isinf(d.psnr_db) && d.psnr_db > 0 && d.differing_pixels == 0);
    }
    free(map);
    free(a);
    free(b);
}

/* Optionally write the pair as PNGs for running NVlabs' tool on it (flip_pair.h). */
static void write_pair_if_asked(const uint8_t *ref, const uint8_t *test)
{
    const char *dir = getenv("TESSERA_FLIP_WRITE_PAIR");
    if (!dir)
        return;
    const uint8_t *codes[] = {ref, test};
    const char *names[] = {"flip_pair_ref.png", "flip_pair_test.png"};
    for (int k = 0; k < 2; k++) {
        float lin[FLIP_PAIR_W * FLIP_PAIR_H * 3];
        for (int i = 0; i < FLIP_PAIR_W * FLIP_PAIR_H * 3; i++)
            lin[i] = flip_pair_linear(codes[k][i]);
        char path[512];
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        tess_error err = {{0}};
        cr_assert(dump_write_rgb(path, FLIP_PAIR_W, FLIP_PAIR_H, lin, &err), "%s", err.msg);
    }
}

Test(flip, known_pair_gives_the_reference_implementations_mean)
{
    static uint8_t ref[FLIP_PAIR_W * FLIP_PAIR_H * 3], test[FLIP_PAIR_W * FLIP_PAIR_H * 3];
    flip_pair_codes(ref, test);
    write_pair_if_asked(ref, test);
    static float a[FLIP_PAIR_W * FLIP_PAIR_H * 3], b[FLIP_PAIR_W * FLIP_PAIR_H * 3];
    for (int i = 0; i < FLIP_PAIR_W * FLIP_PAIR_H * 3; i++) {
        a[i] = flip_pair_linear(ref[i]);
        b[i] = flip_pair_linear(test[i]);
    }
    double mean = flip_mean(a, b, FLIP_PAIR_W, FLIP_PAIR_H, FLIP_DEFAULT_PPD);
    cr_expect(fabs(mean - FLIP_PAIR_NVLABS_MEAN) <= FLIP_PAIR_TOLERANCE, "mean %.7f, NVlabs %.6f", mean,
              FLIP_PAIR_NVLABS_MEAN);
}

Test(flip, error_grows_with_noise_amplitude)
{
    const int w = 64, h = 48;
    float *a = pattern(w, h);
    static const double amplitudes[] = {0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.4};
    double last = 0.0;
    for (size_t k = 0; k < sizeof amplitudes / sizeof amplitudes[0]; k++) {
        float *b = noisy(a, w, h, amplitudes[k], 99); /* same seed: the same noise, scaled */
        double mean = flip_mean(a, b, w, h, FLIP_DEFAULT_PPD);
        cr_expect(mean > last, "amplitude %g: mean %.6f, not above %.6f at the amplitude before", amplitudes[k], mean,
                  last);
        last = mean;
        free(b);
    }
    free(a);
}

Test(flip, more_pixels_per_degree_hide_fine_noise)
{
    const int w = 64, h = 64;
    float *a = malloc((size_t)w * h * 3 * sizeof *a);
    for (int i = 0; i < w * h * 3; i++)
        a[i] = 0.2f; /* mid grey (linear): noise of one pixel is the finest detail there is */
    float *b = noisy(a, w, h, 0.1, 5);
    static const double ppds[] = {10.0, 30.0, FLIP_DEFAULT_PPD, 150.0, 400.0};
    double last = INFINITY;
    for (size_t k = 0; k < sizeof ppds / sizeof ppds[0]; k++) {
        double mean = flip_mean(a, b, w, h, ppds[k]);
        cr_expect(mean < last, "ppd %g: mean %.6f, not below %.6f at fewer pixels per degree", ppds[k], mean, last);
        last = mean;
    }
    free(a);
    free(b);
}

Test(flip, same_map_for_any_thread_count)
{
    const int w = 40, h = 300; /* several bands of rows */
    float *a = pattern(w, h), *b = noisy(a, w, h, 0.1, 3);
    float *one = malloc((size_t)w * h * sizeof *one), *many = malloc((size_t)w * h * sizeof *many);
    tess_error err = {{0}};
    cr_assert(flip_ldr_map(a, b, w, h, FLIP_DEFAULT_PPD, 1, one, &err), "%s", err.msg);
    static const int threads[] = {2, 3, 7};
    for (size_t k = 0; k < 3; k++) {
        cr_assert(flip_ldr_map(a, b, w, h, FLIP_DEFAULT_PPD, threads[k], many, &err), "%s", err.msg);
        cr_expect(memcmp(one, many, (size_t)w * h * sizeof *one) == 0, "%d threads give another map", threads[k]);
    }
    free(one);
    free(many);
    free(a);
    free(b);
}

Test(flip, tiny_images_and_map_values_in_range)
{
    /* 1x1, a single row and a single column: the filters' edge repetition covers them */
    static const int sizes[][2] = {{1, 1}, {17, 1}, {1, 9}, {3, 2}};
    for (size_t k = 0; k < 4; k++) {
        int w = sizes[k][0], h = sizes[k][1];
        float *a = pattern(w, h), *b = noisy(a, w, h, 0.5, 11);
        float *map = malloc((size_t)w * h * sizeof *map);
        tess_error err = {{0}};
        cr_assert(flip_ldr_map(a, b, w, h, FLIP_DEFAULT_PPD, 2, map, &err), "%dx%d: %s", w, h, err.msg);
        for (int i = 0; i < w * h; i++)
            cr_expect(map[i] >= 0.0f && map[i] <= 1.0f, "%dx%d pixel %d: %g", w, h, i, map[i]);
        free(map);
        free(a);
        free(b);
    }
}

Test(flip, filter_radii_match_the_reference)
{
    /* NVlabs' tool at its default 67.02 ppd: spatial radius 10, feature radius 9 */
    cr_expect_eq(flip_spatial_radius_px(FLIP_DEFAULT_PPD), 10);
    cr_expect_eq(flip_feature_radius_px(FLIP_DEFAULT_PPD), 9);
    cr_expect(fabs(FLIP_DEFAULT_PPD - 67.0206) < 1e-4);
    cr_expect(fabs(flip_ppd_of_viewer(0.7, 3840.0 / 0.7) - FLIP_DEFAULT_PPD) < 1e-9);
}

Test(flip, values_outside_the_display_range_are_clamped)
{
    const int w = 8, h = 8;
    float a[8 * 8 * 3], b[8 * 8 * 3];
    for (int i = 0; i < w * h * 3; i++) {
        a[i] = i % 2 ? 1.0f : 0.0f;
        b[i] = i % 2 ? 7.5f : (i % 3 ? -2.0f : NAN); /* above 1 is 1; below 0 and NaN are 0 */
    }
    float map[8 * 8];
    tess_error err = {{0}};
    cr_assert(flip_ldr_map(a, b, w, h, FLIP_DEFAULT_PPD, 1, map, &err), "%s", err.msg);
    for (int i = 0; i < w * h; i++)
        cr_expect(map[i] == 0.0f, "pixel %d: %g", i, map[i]);
}

Test(flip, bad_arguments_are_errors)
{
    float px[3] = {0.5f, 0.5f, 0.5f}, map[1];
    tess_error err = {{0}};
    cr_expect(!flip_ldr_map(px, px, 0, 1, FLIP_DEFAULT_PPD, 1, map, &err));
    cr_expect(strstr(err.msg, "0x1"), "%s", err.msg);
    err.msg[0] = '\0';
    cr_expect(!flip_ldr_map(px, px, 1, 1, 0.5, 1, map, &err));
    cr_expect(strstr(err.msg, "pixels per degree"), "%s", err.msg);
    err.msg[0] = '\0';
    cr_expect(!flip_ldr_map(px, px, 1, 1, NAN, 1, map, &err));
    cr_expect(strstr(err.msg, "pixels per degree"), "%s", err.msg);
}

Test(flip, pooling_and_plain_differences)
{
    const float values[] = {5.0f, 1.0f, 4.0f, 2.0f, 3.0f};
    stats_pooled s;
    tess_error err = {{0}};
    cr_assert(stats_pool(values, 5, &s, &err));
    cr_expect(s.mean == 3.0 && s.median == 3.0 && s.q3 == 4.0, "%g %g %g", s.mean, s.median, s.q3);
    const float four[] = {0.0f, 1.0f, 2.0f, 10.0f};
    cr_assert(stats_pool(four, 4, &s, &err));
    cr_expect(s.median == 1.5 && s.q3 == 4.0, "type-7 percentiles: %g %g", s.median, s.q3); /* 2 + 0.25 * 8 */
    cr_expect(!stats_pool(values, 0, &s, &err));

    const float a[6] = {0.0f, 0.0f, 0.0f, 0.5f, 0.5f, 0.5f};
    const float b[6] = {0.1f, 0.1f, 0.1f, 0.5f, 0.5f, 0.5f};
    stats_rgb_diff d;
    stats_rgb_diff_compute(a, b, 2, &d);
    double rmse = sqrt(3.0 * (double)0.1f * (double)0.1f / 6.0);
    cr_expect(fabs(d.rmse - rmse) < 1e-12, "rmse %g, expected %g", d.rmse, rmse);
    cr_expect(fabs(d.psnr_db - 10.0 * log10(1.0 / (rmse * rmse))) < 1e-9);
    cr_expect_eq(d.differing_pixels, 1);
    const float negative_zero[3] = {-0.0f, 0.0f, 0.0f}, zero[3] = {0.0f, 0.0f, 0.0f};
    stats_rgb_diff_compute(negative_zero, zero, 1, &d);
    cr_expect_eq(d.differing_pixels, 1, "-0 and +0 are not bit-identical");
}

Test(flip, error_map_picture_has_the_legend_under_the_map)
{
    const int w = 50, h = 30;
    float *error = malloc((size_t)w * h * sizeof *error);
    for (int i = 0; i < w * h; i++)
        error[i] = (float)(i % w) / (float)(w - 1);
    float *rgb = NULL;
    int out_h = 0;
    tess_error err = {{0}};
    cr_assert(error_map_render(error, w, h, &rgb, &out_h, &err), "%s", err.msg);
    cr_expect_eq(out_h, h + error_map_legend_height_px(w));
    cr_expect_eq(error_map_legend_height_px(100), 20);
    cr_expect_eq(error_map_legend_height_px(1920), 120);
    /* 0 is near black, 1 pale yellow: red and green high, blue lower */
    cr_expect(rgb[0] < 0.01f && rgb[1] < 0.01f && rgb[2] < 0.01f, "%g %g %g", rgb[0], rgb[1], rgb[2]);
    const float *end = rgb + 3 * (size_t)(w - 1);
    cr_expect(end[0] > 0.9f && end[1] > 0.9f && end[2] < end[0], "%g %g %g", end[0], end[1], end[2]);
    /* the colour ramp rises in luminance from left to right */
    double srgb_lo[3], srgb_hi[3];
    for (int k = 0; k < 10; k++) {
        error_map_color_srgb(k / 10.0, srgb_lo);
        error_map_color_srgb((k + 1) / 10.0, srgb_hi);
        double lum_lo = 0.2126 * srgb_lo[0] + 0.7152 * srgb_lo[1] + 0.0722 * srgb_lo[2];
        double lum_hi = 0.2126 * srgb_hi[0] + 0.7152 * srgb_hi[1] + 0.0722 * srgb_hi[2];
        cr_expect(lum_hi > lum_lo, "the colour map is not ordered at %g", k / 10.0);
    }
    free(rgb);
    cr_expect(!error_map_render(error, 0, h, &rgb, &out_h, &err));
    free(error);
}
