/* sampler.h - where in a pixel the primary rays go, and how many.
 *
 * Pixel coordinates are continuous: pixel (x, y) covers [x, x + 1) x [y, y + 1)
 * and its centre is (x + 0.5, y + 0.5), the point camera.h's mapping uses.
 *
 *   single        one ray through the pixel centre (render_tile's rays)
 *   jittered:K    K x K strata per pixel, one ray in each: sample (i, j),
 *                 0 <= i, j < K, lies at
 *                   (x + (i + u) / K,  y + (j + v) / K)
 *                 with u, v in [0, 1) drawn from a counter-based hash of
 *                 (seed, x, y, i, j) (sampler_jitter). Positions are pure
 *                 functions of those five numbers, so an image does not depend
 *                 on tile size, tile order, packet grouping or thread count.
 *
 * The pixel value of a jittered sampler is the mean of its K^2 sample
 * colours: summed in float in stratum row-major order (j outer, i inner,
 * starting from +0), then divided by (float)(K * K). */
#ifndef TESSERA_SAMPLER_H
#define TESSERA_SAMPLER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/err.h"

/* STRATUM is not named in configs: it is one frame of the governor's
 * accumulation (pipeline.h, GOVERNOR): one ray per pixel, the ray of stratum
 * `stratum` (= j * k + i) that jittered:k with the same seed traces, so k^2
 * such frames summed in stratum order give jittered:k's pixels bit for bit. */
typedef enum pixel_sampler_kind {
    PIXEL_SAMPLER_SINGLE,
    PIXEL_SAMPLER_JITTERED,
    PIXEL_SAMPLER_STRATUM,
} pixel_sampler_kind;

#define PIXEL_SAMPLER_MAX_K 16    /* strata per pixel side: up to 256 rays per pixel */
#define PIXEL_SAMPLER_DEFAULT_K 4 /* what a bare "jittered" means */
#define PIXEL_SAMPLER_DEFAULT_SEED 0u

typedef struct pixel_sampler {
    pixel_sampler_kind kind;
    int k;         /* jittered, stratum: k x k strata per pixel, 1 .. PIXEL_SAMPLER_MAX_K; single: ignored */
    uint32_t seed; /* jittered, stratum: selects the jitter pattern; single: ignored */
    int stratum;   /* stratum: which one, 0 .. k^2 - 1 (row-major: i = stratum % k, j = stratum / k) */
} pixel_sampler;

/* Longest name pixel_sampler_name writes, with its terminating NUL. */
#define PIXEL_SAMPLER_NAME_BYTES 16

static inline pixel_sampler pixel_sampler_single(void)
{
    return (pixel_sampler){PIXEL_SAMPLER_SINGLE, 1, PIXEL_SAMPLER_DEFAULT_SEED, 0};
}

static inline pixel_sampler pixel_sampler_jittered(int k, uint32_t seed)
{
    return (pixel_sampler){PIXEL_SAMPLER_JITTERED, k, seed, 0};
}

/* Stratum `stratum` (0 .. k^2 - 1) of jittered:k with `seed`, alone. */
static inline pixel_sampler pixel_sampler_stratum(int k, uint32_t seed, int stratum)
{
    return (pixel_sampler){PIXEL_SAMPLER_STRATUM, k, seed, stratum};
}

/* Parse "single", "jittered" (k = PIXEL_SAMPLER_DEFAULT_K) or "jittered:K"
 * (K decimal digits, 1 .. 16). The seed becomes PIXEL_SAMPLER_DEFAULT_SEED
 * (callers with a seed option set it afterwards). On failure *out is
 * untouched and err holds one line naming the text and what was expected. */
bool pixel_sampler_from_name(const char *name, pixel_sampler *out, tess_error *err);

/* The name from_name reads back ("single", "jittered:4"); the seed is not
 * part of it. Writes at most `size` bytes (PIXEL_SAMPLER_NAME_BYTES is enough). */
void pixel_sampler_name(const pixel_sampler *s, char *buf, size_t size);

/* False, with the reason in err, for an unknown kind, a jittered or stratum k
 * outside 1 .. PIXEL_SAMPLER_MAX_K or a stratum outside 0 .. k^2 - 1. The
 * render functions require a valid sampler. */
bool pixel_sampler_validate(const pixel_sampler *s, tess_error *err);

/* Strata per pixel side: k for jittered, 1 for single. */
static inline int pixel_sampler_strata(const pixel_sampler *s) { return s->kind == PIXEL_SAMPLER_JITTERED ? s->k : 1; }

/* 64-bit integer finalizer: Stafford's "Mix13" variant of the MurmurHash3
 * fmix64 step, as used by SplitMix64. A bijection on 64-bit words in which
 * every input bit changes each output bit with probability ~1/2. */
static inline uint64_t sampler_hash64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* The jitter (u, v), each in [0, 1) on a 2^-24 grid, of stratum (i, j) of
 * pixel (x, y): u and v are bits 63..40 and 39..16 of
 *   sampler_hash64(sampler_hash64((seed << 32 | j << 8 | i) + golden) ^ (y << 32 | x))
 * (x, y taken as 32-bit words, i, j < 256, golden = 0x9e3779b97f4a7c15). */
void sampler_jitter(uint32_t seed, int x, int y, int i, int j, float *u, float *v);

/* Continuous pixel position of sample (i, j) of pixel (x, y): for single the
 * centre (x + 0.5, y + 0.5) (i, j ignored); for jittered the point of the
 * header comment computed in float as x + (i + u) * (1 / k), and if rounding
 * put it on a stratum border, stepped inside by float steps, so that
 *   x + i / k <= *px < x + (i + 1) / k  exactly (likewise *py with y, j),
 * for 0 <= x, y < 2^19 (where a stratum is wider than a few float steps).
 * The sampler must be valid; 0 <= i, j < pixel_sampler_strata(s) (a stratum
 * sampler has one: (0, 0) stands for its own, whose position is jittered:k's
 * for that stratum). */
void pixel_sampler_position(const pixel_sampler *s, int x, int y, int i, int j, float *px, float *py);

/* pixel_sampler_position of stratum (i, j) for every pixel of the w x h block
 * at (x0, y0), row-major into px[0 .. w*h), py[0 .. w*h) (the same values,
 * with the stratum's half of the hash computed once). */
void pixel_sampler_block_positions(const pixel_sampler *s, int x0, int y0, int w, int h, int i, int j, float *px,
                                   float *py);

#endif
