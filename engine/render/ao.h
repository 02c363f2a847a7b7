/* ao.h - ambient-occlusion sampling: the directions AO rays take.
 *
 * THE SEQUENCE. Every direction comes from one 2D point sequence P[j],
 * j = 0, 1, 2, ...: the first two dimensions of Sobol's sequence (the van der
 * Corput radical inverse in base 2, and the generator matrix of the
 * polynomial x + 1), a (0, 2)-sequence in base 2 (Niederreiter 1992): every
 * aligned block of 2^m consecutive points is a (0, m, 2)-net, one point in
 * each of the 2^m cells of every elementary partition of the square into
 * 2^a x 2^b cells, a + b = m. Points are 32-bit integers per coordinate; the
 * sequence is linear over GF(2): P[a XOR b] = P[a] XOR P[b].
 *
 * INTERLEAVED SETS (Keller and Heidrich, "Interleaved Sampling", EGWR 2001).
 * Pixel (x, y) uses set c = (y mod K) * K + (x mod K) of K^2 sets; in frame
 * f its ray s (s < N) takes the point
 *   P[f * N + s] XOR P[c * N2] XOR AO_SEQUENCE_SHIFT,   N2 = N rounded up to a power of 2.
 * Why this shape:
 *  - within one frame a set is a digital shift of N consecutive points: for N
 *    a power of 2 a (0, log2 N, 2)-net (stratified), otherwise N consecutive
 *    points of a (0, 2)-sequence;
 *  - for N a power of 2 the K^2 sets of a frame together are the K^2 N
 *    points P[(f XOR c) N + s], i.e. (for K^2 N a power of 2) a digitally
 *    shifted (0, log2(K^2 N), 2)-net: the sets differ and fill each other's
 *    gaps, which the discontinuity filter then averages;
 *  - frame by frame a pixel walks along the whole sequence (digitally shifted,
 *    which keeps it a (0, 2)-sequence), so the mean over frames f = 0..F-1 is
 *    a quasi-Monte Carlo estimate with F N points that converges to the
 *    N -> infinity value for every pixel, with or without the filter.
 * The frame f is the pixel sampler's stratum (sampler.h): 0 for single,
 * the stratum index j k + i for jittered and stratum samplers, so the
 * governor's accumulation of stratum frames converges; with
 * render_settings.ao_frames F > 1 each stratum stands for F consecutive
 * frames, averaged (render_ao.h, FRAMES).
 *
 * DIRECTIONS. A point (u, v) maps to the unit disk by Shirley and Chiu's
 * concentric map ("A Low Distortion Map Between Disk and Square", JGT 1997),
 * which keeps the strata compact, and up to the hemisphere by
 * z = sqrt(1 - x^2 - y^2) (Malley's method): directions with density
 * cos(theta) / pi about +z, renormalised to unit length.
 *
 * Pure functions of their arguments; no state. */
#ifndef TESSERA_AO_H
#define TESSERA_AO_H

#include <stdalign.h>
#include <stdint.h>

#include "engine/base/vec3.h"

#define AO_MAX_RAYS 64       /* render_settings.ao_rays: 1 .. 64 */
#define AO_MAX_INTERLEAVE 8  /* render_settings.ao_interleave K: 1 .. 8 */
#define AO_MAX_SETS (AO_MAX_INTERLEAVE * AO_MAX_INTERLEAVE)
#define AO_MAX_FILTER_PX 9   /* render_settings.ao_filter_px: odd, 1 .. 9 */
#define AO_MAX_FRAMES 64     /* render_settings.ao_frames: 1 .. 64 */

/* A fixed digital shift of the whole sequence (both coordinates): keeps
 * every net property and moves the first point off the square's corner,
 * which the concentric map sends to the pole. Any constant works. */
#define AO_SEQUENCE_SHIFT_U 0x5bd1e995u
#define AO_SEQUENCE_SHIFT_V 0x27d4eb2fu

/* P[j] of the header comment, as two 32-bit fractions (unshifted). */
void ao_sequence(uint32_t j, uint32_t *u_bits, uint32_t *v_bits);

/* The point (u, v) in [0, 1)^2 (24-bit grid) of ray s of set c in frame f
 * for N = ray_count rays per set: the header comment's formula, shift
 * included. */
void ao_set_point(int ray_count, uint32_t frame, int set, int ray_index, float *u, float *v);

/* The cosine-distributed unit direction about +z of a point of [0, 1)^2. */
vec3 ao_cosine_direction(float u, float v);

/* An orthonormal basis (t, b, n) around a unit normal n, right-handed
 * (t x b = n): Duff, Burgess, Christensen, Hery, Kensler, Liani, Villemin,
 * "Building an Orthonormal Basis, Revisited", JCGT 6(1) 2017, listing 3. No
 * division by a small number and no branch on near-parallel axes; t and b
 * are continuous in n everywhere except across n.z = 0 (no basis can be
 * continuous on the whole sphere), which only rotates a hemisphere's
 * direction set there. */
typedef struct ao_basis {
    vec3 t, b, n;
} ao_basis;

ao_basis ao_basis_from_normal(vec3 n);

/* Local (x, y, z) -> world x t + y b + z n. */
static inline vec3 ao_basis_to_world(const ao_basis *f, vec3 local)
{
    return v3_add(v3_add(v3_scale(f->t, local.x), v3_scale(f->b, local.y)), v3_scale(f->n, local.z));
}

/* Set of pixel (x, y) (x, y >= 0) for interleave K. */
static inline int ao_pixel_set(int interleave, int x, int y)
{
    return (y % interleave) * interleave + (x % interleave);
}

/* The K^2 sets of N local directions of one frame, precomputed: direction s
 * of set c is (x, y, z)[c * N + s]. What a renderer keeps per thread and
 * refills when (K, N, frame) change. */
typedef struct ao_direction_sets {
    int interleave;  /* K, 1 .. AO_MAX_INTERLEAVE */
    int ray_count;   /* N, 1 .. AO_MAX_RAYS */
    uint32_t frame;  /* f */
    alignas(64) float x[AO_MAX_SETS * AO_MAX_RAYS];
    alignas(64) float y[AO_MAX_SETS * AO_MAX_RAYS];
    alignas(64) float z[AO_MAX_SETS * AO_MAX_RAYS]; /* > 0: above the surface */
} ao_direction_sets;

/* Fill *d for (interleave, ray_count, frame); both counts are clamped into
 * their ranges. */
void ao_direction_sets_fill(ao_direction_sets *d, int interleave, int ray_count, uint32_t frame);

static inline vec3 ao_direction_local(const ao_direction_sets *d, int set, int ray_index)
{
    int i = set * d->ray_count + ray_index;
    return v3(d->x[i], d->y[i], d->z[i]);
}

#endif
