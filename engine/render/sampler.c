#include "sampler.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define SAMPLER_STRING(x) #x
#define SAMPLER_EXPAND(x) SAMPLER_STRING(x)
/* What every parse error says is accepted. */
#define SAMPLER_EXPECTED                                                                                             \
    "expected single, jittered or jittered:K with K strata per pixel side, 1.." SAMPLER_EXPAND(PIXEL_SAMPLER_MAX_K)

/* Parse the K of "jittered:K": decimal digits only (no sign, no spaces).
 * Large numbers are capped rather than overflowed; the range check follows. */
static bool parse_strata(const char *name, const char *digits, int *k, tess_error *err)
{
    if (!*digits)
        return tess_error_set(err, "pixel sampler '%s': missing K after 'jittered:' (%s)", name, SAMPLER_EXPECTED);
    int value = 0;
    for (const char *c = digits; *c; c++) {
        if (*c < '0' || *c > '9')
            return tess_error_set(err, "pixel sampler '%s': K '%s' is not a whole number (%s)", name, digits,
                                  SAMPLER_EXPECTED);
        value = value > PIXEL_SAMPLER_MAX_K ? value : value * 10 + (*c - '0');
    }
    if (value < 1 || value > PIXEL_SAMPLER_MAX_K)
        return tess_error_set(err, "pixel sampler '%s': K = %s is out of range (strata per pixel side: 1..%d)", name,
                              digits, PIXEL_SAMPLER_MAX_K);
    *k = value;
    return true;
}

bool pixel_sampler_from_name(const char *name, pixel_sampler *out, tess_error *err)
{
    if (!name || !*name)
        return tess_error_set(err, "pixel sampler: empty name (%s)", SAMPLER_EXPECTED);
    if (strcmp(name, "single") == 0) {
        *out = pixel_sampler_single();
        return true;
    }
    if (strcmp(name, "jittered") == 0) {
        *out = pixel_sampler_jittered(PIXEL_SAMPLER_DEFAULT_K, PIXEL_SAMPLER_DEFAULT_SEED);
        return true;
    }
    static const char prefix[] = "jittered:";
    if (strncmp(name, prefix, sizeof prefix - 1) == 0) {
        int k = 0;
        if (!parse_strata(name, name + sizeof prefix - 1, &k, err))
            return false;
        *out = pixel_sampler_jittered(k, PIXEL_SAMPLER_DEFAULT_SEED);
        return true;
    }
    if (strncmp(name, "single:", 7) == 0)
        return tess_error_set(err, "pixel sampler '%s': single takes no parameter (%s)", name, SAMPLER_EXPECTED);
    return tess_error_set(err, "unknown pixel sampler '%s' (%s)", name, SAMPLER_EXPECTED);
}

void pixel_sampler_name(const pixel_sampler *s, char *buf, size_t size)
{
    if (s->kind == PIXEL_SAMPLER_JITTERED)
        snprintf(buf, size, "jittered:%d", s->k);
    else if (s->kind == PIXEL_SAMPLER_STRATUM)
        snprintf(buf, size, "stratum:%d/%d", s->stratum, s->k);
    else
        snprintf(buf, size, "single");
}

bool pixel_sampler_validate(const pixel_sampler *s, tess_error *err)
{
    if (s->kind == PIXEL_SAMPLER_SINGLE)
        return true;
    if (s->kind != PIXEL_SAMPLER_JITTERED && s->kind != PIXEL_SAMPLER_STRATUM)
        return tess_error_set(err, "pixel sampler: unknown kind %d", (int)s->kind);
    if (s->k < 1 || s->k > PIXEL_SAMPLER_MAX_K)
        return tess_error_set(err, "pixel sampler %s: k = %d is out of range (strata per pixel side: 1..%d)",
                              s->kind == PIXEL_SAMPLER_JITTERED ? "jittered" : "stratum", s->k, PIXEL_SAMPLER_MAX_K);
    if (s->kind == PIXEL_SAMPLER_STRATUM && (s->stratum < 0 || s->stratum >= s->k * s->k))
        return tess_error_set(err, "pixel sampler stratum: stratum %d is not in 0..%d (k = %d)", s->stratum,
                              s->k * s->k - 1, s->k);
    return true;
}

/* The first hashing round of sampler_jitter: everything but the pixel. */
static uint64_t stratum_key(uint32_t seed, int i, int j)
{
    const uint64_t key = (uint64_t)seed << 32 | (uint64_t)(uint8_t)j << 8 | (uint64_t)(uint8_t)i;
    return sampler_hash64(key + 0x9e3779b97f4a7c15ull);
}

/* The second round: the stratum key with the pixel, to two 24-bit fractions. */
static inline void pixel_jitter(uint64_t stratum, int x, int y, float *u, float *v)
{
    const uint64_t pixel = (uint64_t)(uint32_t)y << 32 | (uint64_t)(uint32_t)x;
    const uint64_t h = sampler_hash64(stratum ^ pixel);
    const float unit = 0x1p-24f; /* 24-bit integers times this are exact floats in [0, 1) */
    *u = (float)(uint32_t)(h >> 40) * unit;
    *v = (float)(uint32_t)((h >> 16) & 0xffffffu) * unit;
}

void sampler_jitter(uint32_t seed, int x, int y, int i, int j, float *u, float *v)
{
    pixel_jitter(stratum_key(seed, i, j), x, y, u, v);
}

/* Which side of stratum s of k of `pixel` p is on: -1 below, 0 inside
 * (s <= (p - pixel) k < s + 1), 1 above. Exact: p - pixel is a difference of
 * a float and an integer below 2^24 taken in double (no rounding), and the
 * product with k <= 16 needs at most 29 significant bits. */
static inline int stratum_side(float p, int pixel, int s, int k)
{
    double scaled = ((double)p - (double)pixel) * (double)k;
    return scaled < (double)s ? -1 : scaled >= (double)s + 1.0 ? 1 : 0;
}

/* pixel + (s + jitter) / k in float arithmetic (the division as a product
 * with inv_k = 1/k), then, if rounding put it on or past a stratum border,
 * stepped inside by whole float steps (at most a few, and rarely). */
static inline float stratum_point(int pixel, int s, int k, float inv_k, float jitter)
{
    float p = (float)pixel + ((float)s + jitter) * inv_k;
    for (int step = 0; step < 4; step++) {
        int side = stratum_side(p, pixel, s, k);
        if (__builtin_expect(side == 0, 1))
            break;
        p = nextafterf(p, side < 0 ? INFINITY : -INFINITY);
    }
    return p;
}

void pixel_sampler_position(const pixel_sampler *s, int x, int y, int i, int j, float *px, float *py)
{
    pixel_sampler_block_positions(s, x, y, 1, 1, i, j, px, py);
}

void pixel_sampler_block_positions(const pixel_sampler *s, int x0, int y0, int w, int h, int i, int j, float *px,
                                   float *py)
{
    if (s->kind == PIXEL_SAMPLER_SINGLE) {
        for (int r = 0; r < w * h; r++) {
            px[r] = (float)(x0 + r % w) + 0.5f;
            py[r] = (float)(y0 + r / w) + 0.5f;
        }
        return;
    }
    if (s->kind == PIXEL_SAMPLER_STRATUM) { /* its one stratum, whatever i, j (0, 0) say */
        i = s->stratum % s->k;
        j = s->stratum / s->k;
    }
    const uint64_t stratum = stratum_key(s->seed, i, j);
    const float inv_k = 1.f / (float)s->k;
    for (int b = 0; b < h; b++)
        for (int a = 0; a < w; a++) {
            float u, v;
            pixel_jitter(stratum, x0 + a, y0 + b, &u, &v);
            px[b * w + a] = stratum_point(x0 + a, i, s->k, inv_k, u);
            py[b * w + a] = stratum_point(y0 + b, j, s->k, inv_k, v);
        }
}
