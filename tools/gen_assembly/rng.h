/* rng.h - the generator's only source of randomness: splitmix64 (Steele, Lea
 * and Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014),
 * seeded by --seed. Integer arithmetic only, so a seed gives the same stream on
 * every host; the layout draws the same number of values whatever the
 * tessellation density, so the density search cannot shift the stream. */
#ifndef TESSERA_GEN_ASSEMBLY_RNG_H
#define TESSERA_GEN_ASSEMBLY_RNG_H

#include <stdint.h>

struct ga_rng {
    uint64_t state; /* advanced by a fixed odd constant per draw */
};

static inline void ga_rng_seed(struct ga_rng *rng, uint64_t seed) { rng->state = seed ^ 0x74657373657261ull; }

static inline uint64_t ga_rng_next(struct ga_rng *rng)
{
    uint64_t z = (rng->state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1), 53 bits. */
static inline double ga_rng_unit(struct ga_rng *rng) { return (double)(ga_rng_next(rng) >> 11) * 0x1.0p-53; }

/* Uniform in [lo, hi). */
static inline double ga_rng_range(struct ga_rng *rng, double lo, double hi)
{
    return lo + (hi - lo) * ga_rng_unit(rng);
}

/* Uniform integer in [lo, hi] (hi - lo small: the modulo bias is negligible). */
static inline int ga_rng_int(struct ga_rng *rng, int lo, int hi)
{
    return lo + (int)(ga_rng_next(rng) % (uint64_t)(hi - lo + 1));
}

#endif
