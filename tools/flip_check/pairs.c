/* pairs.c - image pairs of different kinds for checking `tessera compare`
 * against NVlabs' FLIP tool (tools/flip_check/check.sh, metrics/README.md).
 *
 * usage: flip_pairs OUT_DIR BASE_IMAGE
 * Writes 8-bit sRGB PNGs into OUT_DIR:
 *   ref.png     the base image as read (8-bit codes kept)
 *   noise.png   Gaussian noise of sigma 0.05 of the code range (fixed seed)
 *   blur.png    a 1 4 6 4 1 binomial blur in both directions (edges repeated)
 *   shift.png   a colour shift: R x 0.92, B + 0.06 (in code values)
 *   aa_ref.png, aa_1spp.png   640 x 360 synthetic: a rotated checker and
 *               rings, 16 x 16 box-filtered samples per pixel against one
 *               sample per pixel (aliasing)
 * Every random choice comes from one fixed seed: the same files every run. */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "engine/base/srgb.h"
#include "wall/dump.h"

#define PI 3.14159265358979323846
#define NOISE_SIGMA 0.05 /* of the code range [0, 1] */
#define AA_W 640
#define AA_H 360
#define AA_SAMPLES_PER_AXIS 16
#define CHECKER_PX 9.0   /* checker square edge */
#define CHECKER_RAD 0.3  /* checker rotation */
#define RING_PERIOD_PX 6.0

/* A 64-bit LCG (Knuth's MMIX constants): uniform in (0, 1]. */
static uint64_t lcg_state = 12345;
static double uniform01(void)
{
    lcg_state = lcg_state * 6364136223846793005ULL + 1442695040888963407ULL;
    return ((double)(lcg_state >> 11) + 1.0) * 0x1.0p-53;
}

/* Box-Muller: one standard normal value. */
static double normal(void)
{
    double u = uniform01(), v = uniform01();
    return sqrt(-2.0 * log(u)) * cos(2.0 * PI * v);
}


/* Write sRGB code values in [0, 1] (clamped, rounded to 8 bits) as a PNG:
 * dump_write_rgb takes linear RGB and encodes it again, so each value is
 * decoded from its 8-bit code first and comes back as that code. */
static int write_codes(const char *dir, const char *name, int w, int h, const float *codes)
{
    size_t n = (size_t)w * (size_t)h * 3;
    float *linear = malloc(n * sizeof *linear);
    if (!linear) {
        fprintf(stderr, "flip_pairs: out of memory\n");
        return 1;
    }
    for (size_t i = 0; i < n; i++) {
        double c = codes[i] < 0.0f ? 0.0 : codes[i] > 1.0f ? 1.0 : codes[i];
        linear[i] = (float)srgb_curve_decode(round(c * 255.0) / 255.0);
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    tess_error err = {{0}};
    bool ok = dump_write_rgb(path, w, h, linear, &err);
    free(linear);
    if (!ok) {
        fprintf(stderr, "flip_pairs: %s\n", err.msg);
        return 1;
    }
    return 0;
}

/* One direction of the binomial blur: step 1 along rows or `w` along columns. */
static void blur_pass(const float *in, float *out, int w, int h, bool vertical)
{
    static const float taps[5] = {1 / 16.f, 4 / 16.f, 6 / 16.f, 4 / 16.f, 1 / 16.f};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int c = 0; c < 3; c++) {
                float sum = 0.0f;
                for (int t = -2; t <= 2; t++) {
                    int xx = vertical ? x : x + t, yy = vertical ? y + t : y;
                    xx = xx < 0 ? 0 : xx >= w ? w - 1 : xx;
                    yy = yy < 0 ? 0 : yy >= h ? h - 1 : yy;
                    sum += taps[t + 2] * in[3 * ((size_t)yy * w + xx) + c];
                }
                out[3 * ((size_t)y * w + x) + c] = sum;
            }
}

/* The synthetic scene's linear colour at (px, py) in pixels. */
static void aa_scene(double px, double py, double rgb[3])
{
    double dx = px - AA_W / 2.0, dy = py - AA_H / 2.0;
    double u = dx * cos(CHECKER_RAD) + dy * sin(CHECKER_RAD), v = -dx * sin(CHECKER_RAD) + dy * cos(CHECKER_RAD);
    bool light = (((int)floor(u / CHECKER_PX) + (int)floor(v / CHECKER_PX)) & 1) != 0;
    double ring_r = hypot(px - 480.0, py - 180.0);
    if (ring_r < 120.0 && fmod(ring_r, RING_PERIOD_PX) < 2.0) {
        rgb[0] = 0.02, rgb[1] = 0.6, rgb[2] = 0.9;
        return;
    }
    rgb[0] = light ? 0.9 : 0.05;
    rgb[1] = light ? 0.8 : 0.1;
    rgb[2] = light ? 0.2 : 0.3;
}

/* The synthetic scene with s x s box-filtered samples per pixel, as sRGB codes. */
static void aa_render(int s, float *codes)
{
    for (int y = 0; y < AA_H; y++)
        for (int x = 0; x < AA_W; x++) {
            double sum[3] = {0, 0, 0};
            for (int sy = 0; sy < s; sy++)
                for (int sx = 0; sx < s; sx++) {
                    double rgb[3];
                    aa_scene(x + (sx + 0.5) / s, y + (sy + 0.5) / s, rgb);
                    for (int c = 0; c < 3; c++)
                        sum[c] += rgb[c];
                }
            for (int c = 0; c < 3; c++)
                codes[3 * ((size_t)y * AA_W + x) + c] = (float)srgb_curve_encode(sum[c] / (s * s));
        }
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: flip_pairs OUT_DIR BASE_IMAGE\n");
        return 2;
    }
    const char *dir = argv[1];
    int w, h;
    uint8_t *base8;
    tess_error err = {{0}};
    if (!dump_read_rgb8(argv[2], &w, &h, &base8, &err)) {
        fprintf(stderr, "flip_pairs: %s\n", err.msg);
        return 1;
    }
    size_t n = (size_t)w * (size_t)h * 3;
    float *base = calloc(n, sizeof *base), *made = calloc(n, sizeof *made), *tmp = calloc(n, sizeof *tmp);
    float *aa = calloc((size_t)AA_W * AA_H * 3, sizeof *aa);
    if (!base || !made || !tmp || !aa) {
        fprintf(stderr, "flip_pairs: out of memory\n");
        return 1;
    }
    for (size_t i = 0; i < n; i++)
        base[i] = base8[i] / 255.0f;
    int failed = write_codes(dir, "ref.png", w, h, base);
    for (size_t i = 0; i < n; i++)
        made[i] = base[i] + (float)(NOISE_SIGMA * normal());
    failed |= write_codes(dir, "noise.png", w, h, made);
    blur_pass(base, tmp, w, h, false);
    blur_pass(tmp, made, w, h, true);
    failed |= write_codes(dir, "blur.png", w, h, made);
    for (size_t i = 0; i < n; i += 3) {
        made[i] = base[i] * 0.92f;
        made[i + 1] = base[i + 1];
        made[i + 2] = base[i + 2] + 0.06f;
    }
    failed |= write_codes(dir, "shift.png", w, h, made);
    aa_render(AA_SAMPLES_PER_AXIS, aa);
    failed |= write_codes(dir, "aa_ref.png", AA_W, AA_H, aa);
    aa_render(1, aa);
    failed |= write_codes(dir, "aa_1spp.png", AA_W, AA_H, aa);
    free(base8);
    free(base);
    free(made);
    free(tmp);
    free(aa);
    return failed;
}
