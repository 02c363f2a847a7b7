/* test_sample_ring.c - measurements and their median (engine/base/sample_ring.h). */
#include <criterion/criterion.h>

#include "engine/base/sample_ring.h"

Test(sample_ring, the_median_of_what_is_kept_and_the_maximum_of_all)
{
    sample_ring r = {0};
    cr_assert_eq(sample_ring_median(&r), 0.0, "none: 0");
    sample_ring_add(&r, 5.0);
    sample_ring_add(&r, 1.0);
    sample_ring_add(&r, 3.0);
    cr_assert_eq(sample_ring_median(&r), 3.0, "odd count: the middle one");
    sample_ring_add(&r, 4.0);
    cr_assert_eq(sample_ring_median(&r), 3.5, "even count: the mean of the middle two");
    cr_assert_eq(r.max, 5.0);
    /* the ring keeps the last SAMPLE_RING_KEPT: 1000 large ones pushed out by small ones */
    for (int i = 0; i < SAMPLE_RING_KEPT; i++)
        sample_ring_add(&r, 1000.0);
    for (int i = 0; i < SAMPLE_RING_KEPT; i++)
        sample_ring_add(&r, (double)(i % 3)); /* 0, 1, 2, ... */
    cr_assert_eq(sample_ring_median(&r), 1.0, "only the last %d count", SAMPLE_RING_KEPT);
    cr_assert_eq(r.max, 1000.0, "the maximum of every sample");
    cr_assert_eq(r.count, 4 + 2 * (uint64_t)SAMPLE_RING_KEPT);
    double v[5] = {9.0, -1.0, 4.0, 4.0, 0.5};
    cr_assert_eq(median_sorting(v, 5), 4.0);
    cr_assert(v[0] == -1.0 && v[4] == 9.0, "sorted in place");
    cr_assert_eq(median_sorting(v, 0), 0.0);
}
