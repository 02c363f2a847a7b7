/* flip_pair.h - the image pair whose LDR-FLIP mean NVlabs' tool was run on
 * (test_flip.c, test_compare_cli.c): 8-bit sRGB codes made with integer
 * arithmetic only, so every machine makes the same bytes. Header-only.
 *
 * The reference is a horizontal red ramp, a vertical green ramp, an 8-pixel
 * blue checker and an orange disc; the test has, in thirds from the left,
 * uniform noise of +-20 codes (fixed-seed LCG), the pattern shifted one pixel
 * right, and blue raised by 30 codes. */
#ifndef TESSERA_TESTS_FLIP_PAIR_H
#define TESSERA_TESTS_FLIP_PAIR_H

#include <math.h>
#include <stdint.h>

#define FLIP_PAIR_W 96
#define FLIP_PAIR_H 64
/* NVlabs/flip (v1.6, commit 1eb247c, its C++ tool built with g++ -O2, no
 * OpenMP) on the pair written as PNGs (TESSERA_FLIP_WRITE_PAIR=DIR makes
 * test_flip.c's known_pair test write DIR/flip_pair_ref.png and
 * DIR/flip_pair_test.png): `flip -r flip_pair_ref.png -t flip_pair_test.png`
 * at its default 67.0206 ppd printed "Mean: 0.186141" (its FLIP::evaluate map, summed in double by a
 * scratch harness outside this tree: 0.1861412; ours: 0.1861412). */
#define FLIP_PAIR_NVLABS_MEAN 0.186141
#define FLIP_PAIR_TOLERANCE 1e-4

static inline void flip_pair_base(int x, int y, uint8_t c[3])
{
    c[0] = (uint8_t)(x * 255 / (FLIP_PAIR_W - 1));
    c[1] = (uint8_t)(y * 255 / (FLIP_PAIR_H - 1));
    c[2] = ((x / 8 + y / 8) & 1) ? 200 : 40;
    if ((x - 60) * (x - 60) + (y - 30) * (y - 30) < 15 * 15) {
        c[0] = 230;
        c[1] = 120;
        c[2] = 20;
    }
}

static inline uint8_t flip_pair_clamp(int v) { return (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v); }

/* Both images as sRGB codes, 3 per pixel, top row first. */
static inline void flip_pair_codes(uint8_t *ref, uint8_t *test)
{
    uint32_t seed = 2020u;
    for (int y = 0; y < FLIP_PAIR_H; y++)
        for (int x = 0; x < FLIP_PAIR_W; x++) {
            uint8_t *r = ref + 3 * (y * FLIP_PAIR_W + x), *t = test + 3 * (y * FLIP_PAIR_W + x);
            flip_pair_base(x, y, r);
            if (x < FLIP_PAIR_W / 3) {
                for (int c = 0; c < 3; c++) {
                    seed = seed * 1664525u + 1013904223u;
                    t[c] = flip_pair_clamp(r[c] + (int)(seed >> 16) % 41 - 20);
                }
            } else if (x < 2 * FLIP_PAIR_W / 3) {
                flip_pair_base(x - 1, y, t);
            } else {
                t[0] = r[0];
                t[1] = r[1];
                t[2] = flip_pair_clamp(r[2] + 30);
            }
        }
}

/* sRGB code -> linear, as the reader decodes (IEC 61966-2-1 in double). */
static inline float flip_pair_linear(uint8_t code)
{
    double e = code / 255.0;
    return (float)(e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4));
}

#endif
