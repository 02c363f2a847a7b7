/* sample_ring.h - the last SAMPLE_RING_KEPT measurements of something (a
 * duration a frame, say) and their median and maximum: what a component
 * reports of its own costs at exit (remote/encoder.c, cluster/cluster.c).
 * Plain data, no lock: the owner serialises adds and reads. */
#ifndef TESSERA_SAMPLE_RING_H
#define TESSERA_SAMPLE_RING_H

#include <stddef.h>
#include <stdint.h>

#define SAMPLE_RING_KEPT 1024

typedef struct sample_ring {
    double v[SAMPLE_RING_KEPT];
    uint64_t count; /* added so far; the ring holds the last min(count, SAMPLE_RING_KEPT) */
    double max;     /* of every sample added, not only those kept */
} sample_ring;

void sample_ring_add(sample_ring *r, double x);
/* The median of the samples kept (0 with none). */
double sample_ring_median(const sample_ring *r);
/* The median of v[0 .. n) (0 for n == 0); sorts v in place. */
double median_sorting(double *v, size_t n);

#endif
