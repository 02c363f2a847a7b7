/* test_upscale.c - render scale and its upscaling filters (engine/render/upscale.h):
 * scale 1 is a copy bit for bit; a constant image stays exactly constant;
 * bilinear reproduces a linear ramp (exactly where the weights are dyadic),
 * clamped-cubic too in the interior; clamped-cubic never leaves the range of
 * the 2 x 2 nearest texels (no ringing) and keeps a step edge steeper than
 * bilinear (10-90 % widths against their analytic values); low-res sizes
 * round as stated; row ranges computed apart equal one full call bit for bit;
 * bad arguments are refused with the problem named. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "engine/render/upscale.h"

static const upscale_filter filters[] = {UPSCALE_BILINEAR, UPSCALE_CLAMPED_CUBIC};
#define FILTER_COUNT (sizeof filters / sizeof filters[0])

/* The scales the governor and the report use, and one giving < 1 px. */
static const double scales[] = {1.0, 0.75, 0.5, 1.0 / 3.0, 0.25, 0.01};
#define SCALE_COUNT (sizeof scales / sizeof scales[0])

/* Deterministic values in [0, 1) (a 32-bit xorshift). */
static float *random_image(int w, int h, uint32_t seed)
{
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    cr_assert(rgb);
    uint32_t s = seed ? seed : 1u;
    for (size_t k = 0; k < (size_t)w * h * 3; k++) {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        rgb[k] = (float)(s >> 8) / 16777216.f;
    }
    return rgb;
}

static float *upscaled(const float *src, int sw, int sh, int dw, int dh, upscale_filter f)
{
    float *dst = malloc((size_t)dw * dh * 3 * sizeof *dst);
    cr_assert(dst);
    tess_error err = {{0}};
    cr_assert(upscale_image(src, sw, sh, dst, dw, dh, f, &err), "%dx%d -> %dx%d %s: %s", sw, sh, dw, dh,
              upscale_filter_name(f), err.msg);
    return dst;
}

/* The header's alignment, derived here on its own: output pixel x's centre
 * in source texel coordinates, clamped to [0, n_src - 1]. */
static double source_coordinate(int x, int n_src, int n_dst)
{
    double u = ((double)x + 0.5) * n_src / n_dst - 0.5;
    return u < 0.0 ? 0.0 : u > n_src - 1 ? n_src - 1 : u;
}

Test(upscale, scale_one_is_a_copy_bit_for_bit)
{
    const int sizes[][2] = {{1, 1}, {1, 7}, {13, 1}, {64, 36}, {37, 23}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        int w = sizes[s][0], h = sizes[s][1];
        float *src = random_image(w, h, (uint32_t)(s + 1));
        src[0] = INFINITY; /* even values arithmetic would change */
        src[3 * w * h - 1] = NAN;
        for (size_t f = 0; f < FILTER_COUNT; f++) {
            cr_expect_eq(upscale_low_res_px(w, 1.0), w);
            float *dst = upscaled(src, w, h, w, h, filters[f]);
            cr_expect(!memcmp(src, dst, (size_t)w * h * 3 * sizeof *dst), "%dx%d %s is not a copy", w, h,
                      upscale_filter_name(filters[f]));
            free(dst);
        }
        free(src);
    }
}

Test(upscale, constant_image_stays_exactly_constant)
{
    const int sizes[][2] = {{320, 180}, {33, 17}, {7, 1}, {1, 5}, {1, 1}};
    const float value[3] = {0.3f, 0.7071f, 1e-3f}; /* not dyadic: weights must not change them */
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (size_t k = 0; k < SCALE_COUNT; k++) {
            int w = sizes[s][0], h = sizes[s][1];
            int sw = upscale_low_res_px(w, scales[k]), sh = upscale_low_res_px(h, scales[k]);
            float *src = malloc((size_t)sw * sh * 3 * sizeof *src);
            cr_assert(src);
            for (size_t p = 0; p < (size_t)sw * sh; p++)
                memcpy(src + 3 * p, value, sizeof value);
            for (size_t f = 0; f < FILTER_COUNT; f++) {
                float *dst = upscaled(src, sw, sh, w, h, filters[f]);
                size_t bad = 0;
                for (size_t p = 0; p < (size_t)w * h; p++)
                    bad += memcmp(dst + 3 * p, value, sizeof value) != 0;
                cr_expect_eq(bad, 0, "%s %dx%d -> %dx%d: %zu pixels changed", upscale_filter_name(filters[f]), sw,
                             sh, w, h, bad);
                free(dst);
            }
            free(src);
        }
}

/* A ramp value of texel coordinates (u, v) per channel. */
static double ramp(int c, double u, double v)
{
    switch (c) {
    case 0:
        return u;
    case 1:
        return 2.0 * v;
    default:
        return 0.5 + 0.25 * u - 0.125 * v;
    }
}

/* Upscale the ramp sw x sh -> dw x dh with filter f; the largest error
 * against the analytic ramp at the output pixels' source coordinates, over
 * the interior (for the cubic: every tap inside the image, no index clamped). */
static double ramp_error(upscale_filter f, int sw, int sh, int dw, int dh)
{
    float *src = malloc((size_t)sw * sh * 3 * sizeof *src);
    cr_assert(src);
    for (int j = 0; j < sh; j++)
        for (int i = 0; i < sw; i++)
            for (int c = 0; c < 3; c++)
                src[3 * ((size_t)j * sw + i) + c] = (float)ramp(c, i, j);
    float *dst = upscaled(src, sw, sh, dw, dh, f);
    int margin = f == UPSCALE_CLAMPED_CUBIC ? 1 : 0;
    double worst = 0.0;
    int checked = 0;
    for (int y = 0; y < dh; y++)
        for (int x = 0; x < dw; x++) {
            double u = source_coordinate(x, sw, dw), v = source_coordinate(y, sh, dh);
            if (floor(u) - margin < 0 || floor(u) + 1 + margin > sw - 1 || floor(v) - margin < 0 ||
                floor(v) + 1 + margin > sh - 1)
                continue;
            checked++;
            for (int c = 0; c < 3; c++)
                worst = fmax(worst, fabs(dst[3 * ((size_t)y * dw + x) + c] - ramp(c, u, v)));
        }
    cr_assert(checked > dw * dh / 4, "the interior is too small to say anything (%d pixels)", checked);
    free(src);
    free(dst);
    return worst;
}

Test(upscale, bilinear_reproduces_a_linear_ramp)
{
    /* factors 2 and 4: t is a multiple of 1/8, every value is exact in float */
    cr_expect_eq(ramp_error(UPSCALE_BILINEAR, 16, 9, 32, 18), 0.0);
    cr_expect_eq(ramp_error(UPSCALE_BILINEAR, 16, 9, 64, 36), 0.0);
    /* factor 3 and uneven ratios: t is rounded to float; values here are < 40 */
    cr_expect_leq(ramp_error(UPSCALE_BILINEAR, 16, 9, 48, 27), 1e-5);
    cr_expect_leq(ramp_error(UPSCALE_BILINEAR, 37, 23, 100, 61), 1e-5);
}

Test(upscale, clamped_cubic_reproduces_a_linear_ramp_in_the_interior)
{
    /* Catmull-Rom reproduces polynomials of degree <= 2; the clamp does not
     * act on a ramp (it lies between its neighbours). Weights are rounded to
     * float: error ~ 1e-7 of the values (< 40). */
    cr_expect_leq(ramp_error(UPSCALE_CLAMPED_CUBIC, 16, 9, 32, 18), 2e-5);
    cr_expect_leq(ramp_error(UPSCALE_CLAMPED_CUBIC, 16, 9, 48, 27), 2e-5);
    cr_expect_leq(ramp_error(UPSCALE_CLAMPED_CUBIC, 37, 23, 100, 61), 2e-5);
}

Test(upscale, clamped_cubic_stays_inside_the_nearest_texels_range)
{
    /* the strongest form of "no ringing": on noise every output lies within
     * its 2 x 2 nearest texels' [min, max], per channel */
    const int sizes[][4] = {{16, 9, 64, 36}, {37, 23, 100, 61}, {240, 135, 320, 180}, {1, 3, 5, 7}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        int sw = sizes[s][0], sh = sizes[s][1], dw = sizes[s][2], dh = sizes[s][3];
        float *src = random_image(sw, sh, 7u + (uint32_t)s);
        float *dst = upscaled(src, sw, sh, dw, dh, UPSCALE_CLAMPED_CUBIC);
        int outside = 0;
        for (int y = 0; y < dh; y++)
            for (int x = 0; x < dw; x++) {
                int i = (int)floor(source_coordinate(x, sw, dw)), j = (int)floor(source_coordinate(y, sh, dh));
                int i1 = i + 1 < sw ? i + 1 : sw - 1, j1 = j + 1 < sh ? j + 1 : sh - 1;
                for (int c = 0; c < 3; c++) {
                    float n[4] = {src[3 * ((size_t)j * sw + i) + c], src[3 * ((size_t)j * sw + i1) + c],
                                  src[3 * ((size_t)j1 * sw + i) + c], src[3 * ((size_t)j1 * sw + i1) + c]};
                    float lo = fminf(fminf(n[0], n[1]), fminf(n[2], n[3]));
                    float hi = fmaxf(fmaxf(n[0], n[1]), fmaxf(n[2], n[3]));
                    float v = dst[3 * ((size_t)y * dw + x) + c];
                    outside += v < lo || v > hi;
                }
            }
        cr_expect_eq(outside, 0, "%dx%d -> %dx%d: %d values outside their neighbourhood", sw, sh, dw, dh, outside);
        free(src);
        free(dst);
    }
}

/* The step edge: columns < STEP_AT are 0, the rest 1, upscaled by
 * STEP_FACTOR. Between texels STEP_AT - 1 and STEP_AT (u = STEP_AT - 1 + t)
 * bilinear gives t and Catmull-Rom -t^3 + 3/2 t^2 + t/2 (weights w2 + w3);
 * outside that interval both are 0 or 1 (the cubic's lobes clamped away). */
#define STEP_SRC_W 16
#define STEP_AT 8
#define STEP_FACTOR 8

static double cubic_step(double t) { return -t * t * t + 1.5 * t * t + 0.5 * t; }

/* t in [0, 1] where the cubic step reaches `level` (it rises monotonically). */
static double cubic_step_inverse(double level)
{
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 60; k++) {
        double mid = 0.5 * (lo + hi);
        if (cubic_step(mid) < level)
            lo = mid;
        else
            hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* The 10-90 % rise of the upscaled step's middle row, in source texels:
 * where the row crosses each level, interpolated between output pixels. */
static double step_rise_texels(const float *row, int dw)
{
    double at[2] = {-1.0, -1.0};
    const double levels[2] = {0.1, 0.9};
    for (int l = 0; l < 2; l++)
        for (int x = 0; x + 1 < dw && at[l] < 0.0; x++)
            if (row[3 * x] < levels[l] && row[3 * (x + 1)] >= levels[l])
                at[l] = x + (levels[l] - row[3 * x]) / (row[3 * (x + 1)] - row[3 * x]);
    cr_assert(at[0] >= 0.0 && at[1] >= 0.0, "the step does not rise through 10 %% and 90 %%");
    return (at[1] - at[0]) / STEP_FACTOR;
}

Test(upscale, clamped_cubic_keeps_a_step_sharper_than_bilinear_without_ringing)
{
    int sw = STEP_SRC_W, sh = 3, dw = sw * STEP_FACTOR, dh = sh * STEP_FACTOR;
    float src[STEP_SRC_W * 3 * 3];
    for (int j = 0; j < sh; j++)
        for (int i = 0; i < sw; i++)
            for (int c = 0; c < 3; c++)
                src[3 * (j * sw + i) + c] = i < STEP_AT ? 0.f : 1.f;
    double rise[FILTER_COUNT];
    for (size_t f = 0; f < FILTER_COUNT; f++) {
        float *dst = upscaled(src, sw, sh, dw, dh, filters[f]);
        int overshoot = 0;
        for (int k = 0; k < dw * dh * 3; k++)
            overshoot += dst[k] < 0.f || dst[k] > 1.f;
        cr_expect_eq(overshoot, 0, "%s: %d values outside [0, 1]", upscale_filter_name(filters[f]), overshoot);
        /* away from the rise the picture is flat, exactly */
        for (int x = 0; x < dw; x++) {
            double u = source_coordinate(x, sw, dw);
            float v = dst[3 * ((size_t)(dh / 2) * dw + x)];
            if (u <= STEP_AT - 1)
                cr_expect_eq(v, 0.f, "%s: x %d (u %g) is %g, not 0", upscale_filter_name(filters[f]), x, u, v);
            if (u >= STEP_AT)
                cr_expect_eq(v, 1.f, "%s: x %d (u %g) is %g, not 1", upscale_filter_name(filters[f]), x, u, v);
        }
        rise[f] = step_rise_texels(dst + (size_t)(dh / 2) * dw * 3, dw);
        free(dst);
    }
    /* analytic: bilinear rises 10-90 % over 0.8 texel (linear between samples:
     * measured exactly); the cubic over the distance between the roots of
     * cubic_step = 0.1 and 0.9 (0.712), measured with samples 1/8 texel apart */
    double cubic_analytic = cubic_step_inverse(0.9) - cubic_step_inverse(0.1);
    cr_expect(fabs(rise[0] - 0.8) < 1e-5, "bilinear rise %g texels, analytic 0.8", rise[0]);
    cr_expect(fabs(rise[1] - cubic_analytic) < 0.01, "clamped-cubic rise %g texels, analytic %g", rise[1],
              cubic_analytic);
    cr_expect_lt(rise[1], rise[0] - 0.05, "clamped-cubic (%g texels) is not sharper than bilinear (%g)", rise[1],
                 rise[0]);
}

Test(upscale, low_res_sizes_round_as_stated)
{
    const struct {
        int size_px;
        double scale;
        int low_px;
    } cases[] = {
        {320, 0.75, 240}, {320, 0.5, 160}, {320, 0.25, 80},  {1920, 1.0 / 3.0, 640}, {1080, 1.0 / 3.0, 360},
        {180, 0.75, 135}, {7, 0.5, 4},     {5, 0.5, 3},      {3, 0.5, 2}, /* halves round up */
        {1921, 0.5, 961}, {1, 1.0, 1},     {1, 0.25, 1},     {3, 0.1, 1},   /* < 1 px becomes 1 px */
        {100, 1e-9, 1},   {16384, 1.0, 16384},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++)
        cr_expect_eq(upscale_low_res_px(cases[k].size_px, cases[k].scale), cases[k].low_px, "%d at %g: %d, not %d",
                     cases[k].size_px, cases[k].scale, upscale_low_res_px(cases[k].size_px, cases[k].scale),
                     cases[k].low_px);
    /* odd and 1-pixel outputs upscale from what they round to */
    const int outputs[][2] = {{1, 1}, {1, 9}, {9, 1}, {319, 179}, {3, 2}};
    for (size_t o = 0; o < sizeof outputs / sizeof outputs[0]; o++)
        for (size_t k = 0; k < SCALE_COUNT; k++)
            for (size_t f = 0; f < FILTER_COUNT; f++) {
                int w = outputs[o][0], h = outputs[o][1];
                int sw = upscale_low_res_px(w, scales[k]), sh = upscale_low_res_px(h, scales[k]);
                cr_expect(sw >= 1 && sw <= w && sh >= 1 && sh <= h);
                float *src = random_image(sw, sh, 3u);
                float *dst = upscaled(src, sw, sh, w, h, filters[f]);
                if (sw == 1 && sh == 1) /* one texel: every pixel is it */
                    for (int p = 0; p < w * h; p++)
                        cr_expect(!memcmp(dst + 3 * p, src, 3 * sizeof *src), "1x1 -> %dx%d pixel %d", w, h, p);
                free(src);
                free(dst);
            }
}

Test(upscale, row_ranges_computed_apart_equal_one_call)
{
    const int sizes[][4] = {{37, 23, 100, 61}, {240, 135, 320, 180}, {5, 1, 17, 3}, {64, 36, 64, 36}};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (size_t f = 0; f < FILTER_COUNT; f++) {
            int sw = sizes[s][0], sh = sizes[s][1], dw = sizes[s][2], dh = sizes[s][3];
            float *src = random_image(sw, sh, 11u + (uint32_t)s);
            float *whole = upscaled(src, sw, sh, dw, dh, filters[f]);
            tess_error err = {{0}};
            upscale_plan *p = upscale_plan_create(sw, sh, dw, dh, filters[f], &err);
            cr_assert(p, "%s", err.msg);
            size_t bytes = (size_t)dw * dh * 3 * sizeof(float);
            float *parts = malloc(bytes);
            float *scratch_a = malloc(upscale_plan_scratch_floats(p) * sizeof(float));
            float *scratch_b = malloc(upscale_plan_scratch_floats(p) * sizeof(float));
            cr_assert(parts && scratch_a && scratch_b);
            memset(parts, 0xff, bytes); /* NaN everywhere: every row must be written */
            /* ranges in a scrambled order, two scratch buffers, an empty range */
            int cut1 = dh / 3, cut2 = dh / 3 + 1, cut3 = dh - 1 > cut2 ? dh - 1 : cut2;
            upscale_plan_rows(p, src, parts, cut3, dh, scratch_a);
            upscale_plan_rows(p, src, parts, cut1, cut2, scratch_b);
            upscale_plan_rows(p, src, parts, 0, cut1, scratch_a);
            upscale_plan_rows(p, src, parts, cut2, cut2, scratch_b);
            upscale_plan_rows(p, src, parts, cut2, cut3, scratch_b);
            cr_expect(!memcmp(whole, parts, bytes), "%s %dx%d -> %dx%d: rows in parts differ",
                      upscale_filter_name(filters[f]), sw, sh, dw, dh);
            upscale_plan_destroy(p);
            free(scratch_a);
            free(scratch_b);
            free(parts);
            free(whole);
            free(src);
        }
}

Test(upscale, bad_arguments_are_refused_with_the_problem_named)
{
    tess_error err = {{0}};
    upscale_filter f = UPSCALE_BILINEAR;
    cr_expect(upscale_filter_from_name("clamped-cubic", &f, &err) && f == UPSCALE_CLAMPED_CUBIC);
    cr_expect(upscale_filter_from_name("bilinear", &f, &err) && f == UPSCALE_BILINEAR);
    cr_expect_not(upscale_filter_from_name("lanczos", &f, &err));
    cr_expect(strstr(err.msg, "'lanczos'") && strstr(err.msg, UPSCALE_FILTER_NAMES), "%s", err.msg);
    cr_expect_eq(f, UPSCALE_BILINEAR, "a refused name changed the filter");
    cr_expect_str_eq(upscale_filter_name((upscale_filter)7), "?");

    const double bad_scales[] = {0.0, -0.5, 1.0000001, 2.0, NAN, INFINITY, -INFINITY};
    for (size_t k = 0; k < sizeof bad_scales / sizeof bad_scales[0]; k++) {
        err = (tess_error){{0}};
        cr_expect_not(upscale_scale_validate(bad_scales[k], &err), "scale %g accepted", bad_scales[k]);
        cr_expect(strstr(err.msg, "(0, 1]"), "%s", err.msg);
    }
    cr_expect(upscale_scale_validate(1.0, &err) && upscale_scale_validate(1e-9, &err));

    const struct {
        int sw, sh, dw, dh;
        upscale_filter filter;
        const char *says;
    } bad[] = {
        {0, 4, 8, 8, UPSCALE_BILINEAR, "at least 1x1"},
        {4, 4, 8, -1, UPSCALE_BILINEAR, "at least 1x1"},
        {9, 4, 8, 8, UPSCALE_CLAMPED_CUBIC, "larger than the destination"},
        {4, 9, 8, 8, UPSCALE_BILINEAR, "larger than the destination"},
        {4, 4, 8, 8, (upscale_filter)7, "unknown filter"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        err = (tess_error){{0}};
        upscale_plan *p = upscale_plan_create(bad[k].sw, bad[k].sh, bad[k].dw, bad[k].dh, bad[k].filter, &err);
        cr_expect_null(p, "case %zu accepted", k);
        upscale_plan_destroy(p);
        cr_expect(strstr(err.msg, bad[k].says), "case %zu: '%s' lacks '%s'", k, err.msg, bad[k].says);
        float one[3] = {0};
        err = (tess_error){{0}};
        cr_expect_not(upscale_image(one, bad[k].sw, bad[k].sh, one, bad[k].dw, bad[k].dh, bad[k].filter, &err));
        cr_expect(strstr(err.msg, bad[k].says), "upscale_image case %zu: '%s'", k, err.msg);
    }
    upscale_plan_destroy(NULL);
}
