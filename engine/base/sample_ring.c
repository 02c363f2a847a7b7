/* sample_ring.c - measurements and their median (sample_ring.h). */
#include "sample_ring.h"

#include <stdlib.h>
#include <string.h>

void sample_ring_add(sample_ring *r, double x)
{
    r->v[r->count++ % SAMPLE_RING_KEPT] = x;
    r->max = r->count == 1 || x > r->max ? x : r->max;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double median_sorting(double *v, size_t n)
{
    if (n == 0)
        return 0.0;
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double sample_ring_median(const sample_ring *r)
{
    size_t n = r->count < SAMPLE_RING_KEPT ? (size_t)r->count : SAMPLE_RING_KEPT;
    double sorted[SAMPLE_RING_KEPT];
    memcpy(sorted, r->v, n * sizeof sorted[0]);
    return median_sorting(sorted, n);
}
