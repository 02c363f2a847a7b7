/* image_stats.h (metrics) - numbers that summarise how two images differ:
 * pooling an error map (mean, median, third quartile) and the plain
 * per-value differences of two RGB images (RMSE, PSNR, differing pixels). */
#ifndef TESSERA_IMAGE_STATS_H
#define TESSERA_IMAGE_STATS_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/base/err.h"

/* Pooled values of an error map. Percentiles are the plain (unweighted)
 * order statistics, interpolated linearly at p * (n - 1) of the sorted values
 * (Hyndman and Fan's type 7, numpy's default). NVlabs' FLIP tool prints
 * error-weighted percentiles instead; its mean is the same quantity. */
typedef struct stats_pooled {
    double mean;   /* summed in double */
    double median; /* 50th percentile */
    double q3;     /* 75th percentile */
} stats_pooled;

/* Pool values[0 .. n), n >= 1 (a sorted copy is made: false with err when
 * memory runs out). */
bool stats_pool(const float *values, size_t n, stats_pooled *out, tess_error *err);

/* Differences of two RGB float images of `pixels` pixels (3 values each),
 * taken on the values as given (for tessera compare: linear RGB, not
 * clamped). */
typedef struct stats_rgb_diff {
    double rmse;             /* sqrt of the mean of squared differences over all 3 * pixels values */
    double psnr_db;          /* 10 log10(1 / rmse^2): peak 1.0; +inf when rmse == 0 */
    size_t differing_pixels; /* pixels whose 3 floats are not bit-identical */
} stats_rgb_diff;

void stats_rgb_diff_compute(const float *a, const float *b, size_t pixels, stats_rgb_diff *out);

#endif
