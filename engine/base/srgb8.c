/* srgb8.c (wall) - see srgb8.h. */
#include "srgb8.h"

#include <math.h>
#include <pthread.h>

#include "srgb.h"

/* Encode table resolution: 2^12 buckets over [0, 1). The narrowest step
 * between two 8-bit codes is 1 / (255 * 12.92) ~= 3.04e-4 (the linear toe),
 * wider than one bucket (2.44e-4), so each bucket holds at most one rounding
 * boundary and one comparison against that boundary makes the result exact. */
#define SRGB_BUCKETS 4096

/* Written once by build_table (under srgb_once), read-only after. */
static struct {
    uint8_t bucket_code[SRGB_BUCKETS]; /* exact code of the bucket's lower end, i / SRGB_BUCKETS */
    float code_up[256];                /* [k]: smallest float whose code is > k; +inf for k = 255 */
} table;
static pthread_once_t srgb_once = PTHREAD_ONCE_INIT;

/* The reference: the sRGB curve in double, clamped, rounded to nearest. */
static int encode_exact(float linear)
{
    if (!(linear > 0.0f)) /* also NaN */
        return 0;
    if (linear >= 1.0f)
        return 255;
    double code = floor(srgb_curve_encode(linear) * 255.0 + 0.5);
    return code < 0.0 ? 0 : code > 255.0 ? 255 : (int)code;
}

static void build_table(void)
{
    for (int i = 0; i < SRGB_BUCKETS; i++)
        table.bucket_code[i] = (uint8_t)encode_exact((float)i / SRGB_BUCKETS);
    for (int k = 0; k < 255; k++) {
        /* Start at the inverse curve of code k + 0.5, then walk float by float
         * to the exact first value the reference rounds above k (the reference
         * is monotone in its input). */
        float f = (float)srgb_curve_decode((k + 0.5) / 255.0);
        while (f > 0.0f && encode_exact(nextafterf(f, 0.0f)) > k)
            f = nextafterf(f, 0.0f);
        while (encode_exact(f) <= k)
            f = nextafterf(f, 2.0f);
        table.code_up[k] = f;
    }
    table.code_up[255] = INFINITY;
}

/* One value, the table built. */
static inline uint8_t encode(float linear)
{
    if (!(linear > 0.0f)) /* also NaN */
        return 0;
    if (linear >= 1.0f)
        return 255;
    /* linear * 4096 is exact (a power of two), so the bucket index is too */
    uint8_t code = table.bucket_code[(int)(linear * (float)SRGB_BUCKETS)];
    return (uint8_t)(code + (linear >= table.code_up[code]));
}

uint8_t srgb8_encode(float linear)
{
    pthread_once(&srgb_once, build_table);
    return encode(linear);
}

void srgb8_encode_values(const float *values, size_t count, uint8_t *codes)
{
    pthread_once(&srgb_once, build_table);
    for (size_t i = 0; i < count; i++)
        codes[i] = encode(values[i]);
}

void srgb8_encode_xrgb(const float *rgb, long stride_px, int count, uint32_t *out)
{
    pthread_once(&srgb_once, build_table);
    long index = 0; /* in pixels from rgb: never a pointer outside the row */
    for (int i = 0; i < count; i++, index += stride_px) {
        const float *c = rgb + 3 * index;
        out[i] = (uint32_t)encode(c[0]) << 16 | (uint32_t)encode(c[1]) << 8 | (uint32_t)encode(c[2]);
    }
}
