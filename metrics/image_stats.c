/* image_stats.c (metrics) - pooling and plain differences (image_stats.h). */
#include "image_stats.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Type-7 percentile of sorted[0 .. n). */
static double percentile(const float *sorted, size_t n, double p)
{
    double at = p * (double)(n - 1);
    size_t lo = (size_t)floor(at);
    size_t hi = lo + 1 < n ? lo + 1 : lo;
    double frac = at - (double)lo;
    return (double)sorted[lo] + frac * ((double)sorted[hi] - (double)sorted[lo]);
}

bool stats_pool(const float *values, size_t n, stats_pooled *out, tess_error *err)
{
    memset(out, 0, sizeof *out);
    if (!values || n == 0)
        return tess_error_set(err, "stats: no values to pool");
    float *sorted = malloc(n * sizeof *sorted);
    if (!sorted)
        return tess_error_set(err, "stats: out of memory for %zu values", n);
    double sum = 0.0;
    for (size_t i = 0; i < n; i++)
        sum += values[i];
    memcpy(sorted, values, n * sizeof *sorted);
    qsort(sorted, n, sizeof *sorted, compare_floats);
    out->mean = sum / (double)n;
    out->median = percentile(sorted, n, 0.5);
    out->q3 = percentile(sorted, n, 0.75);
    free(sorted);
    return true;
}

void stats_rgb_diff_compute(const float *a, const float *b, size_t pixels, stats_rgb_diff *out)
{
    double sum_sq = 0.0;
    size_t differing = 0;
    for (size_t i = 0; i < pixels; i++) {
        const float *pa = a + 3 * i, *pb = b + 3 * i;
        if (memcmp(pa, pb, 3 * sizeof *pa) != 0)
            differing++;
        for (int c = 0; c < 3; c++) {
            double d = (double)pa[c] - (double)pb[c];
            sum_sq += d * d;
        }
    }
    double mse = pixels ? sum_sq / (3.0 * (double)pixels) : 0.0;
    out->rmse = sqrt(mse);
    out->psnr_db = mse > 0.0 ? 10.0 * log10(1.0 / mse) : INFINITY;
    out->differing_pixels = differing;
}
