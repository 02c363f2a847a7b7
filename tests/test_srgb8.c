/* test_srgb8.c - the 8-bit sRGB encoder (engine/base/srgb8.h) without OpenImageIO:
 * known codes, monotone over 2^16 inputs, the bulk and scan-out row entry
 * points equal to the one-value one. (Its exactness against the curve at
 * every rounding boundary, and over every float with TESSERA_EXHAUSTIVE=1,
 * is tests/test_dump.c's: the dump backend's 8-bit files use this encoder.) */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>

#include "engine/base/srgb8.h"

Test(srgb8, known_codes)
{
    cr_assert_eq(srgb8_encode(0.0f), 0);
    cr_assert_eq(srgb8_encode(1.0f), 255);
    cr_assert_eq(srgb8_encode(0.0031308f), 10); /* the knee: 12.92 * 0.0031308 * 255 = 10.31 */
    cr_assert_eq(srgb8_encode(0.0030f), 10);    /* 9.88: below the knee, on the line */
    cr_assert_eq(srgb8_encode(0.0032f), 11);    /* 10.45 above it, on the curve (1.055 x^(1/2.4) - 0.055) */
    cr_assert_eq(srgb8_encode(0.18f), 118);     /* mid grey */
    cr_assert_eq(srgb8_encode(0.5f), 188);
    cr_assert_eq(srgb8_encode(NAN), 0);
    cr_assert_eq(srgb8_encode(-1.0f), 0);
    cr_assert_eq(srgb8_encode(2.0f), 255);
}

/* 2^16 evenly spaced inputs over [0, 1]: codes never fall, every code 0..255 is reached. */
Test(srgb8, monotone_over_two_to_the_sixteen_inputs)
{
    int previous = 0;
    int seen[256] = {0};
    for (uint32_t i = 0; i < 65536; i++) {
        int code = srgb8_encode((float)i / 65535.0f);
        cr_assert_geq(code, previous, "input %u/65535: code %d after %d", (unsigned)i, code, previous);
        previous = code;
        seen[code] = 1;
    }
    for (int k = 0; k < 256; k++)
        cr_assert(seen[k], "code %d never produced", k);
}

Test(srgb8, bulk_and_row_equal_one_by_one)
{
    enum { N = 777 };
    float rgb[3 * N];
    for (int i = 0; i < 3 * N; i++)
        rgb[i] = (float)(i * 7919 % 3001) / 2900.0f - 0.01f; /* a little below 0 and above 1 too */
    uint8_t codes[3 * N];
    srgb8_encode_values(rgb, 3 * N, codes);
    for (int i = 0; i < 3 * N; i++)
        cr_assert_eq(codes[i], srgb8_encode(rgb[i]), "value %d (%g)", i, (double)rgb[i]);
    uint32_t forward[N], backward[N];
    srgb8_encode_xrgb(rgb, 1, N, forward);
    srgb8_encode_xrgb(rgb + 3 * (N - 1), -1, N, backward); /* a 180-degree row: last pixel first */
    for (int i = 0; i < N; i++) {
        uint32_t want = (uint32_t)codes[3 * i] << 16 | (uint32_t)codes[3 * i + 1] << 8 | codes[3 * i + 2];
        cr_assert_eq(forward[i], want, "pixel %d: 0x%08x, want 0x%08x", i, forward[i], want);
        cr_assert_eq(backward[N - 1 - i], want, "pixel %d backwards", i);
    }
}
