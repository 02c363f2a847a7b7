#define _DEFAULT_SOURCE /* madvise, MADV_HUGEPAGE */
#include "memory.h"

#include <stdlib.h>
#include <sys/mman.h>

/* Transparent huge pages are 2 MiB on x86-64. */
#define MEMORY_HUGE_PAGE_BYTES ((size_t)2 << 20)

void *memory_alloc_large(size_t bytes)
{
    if (bytes < MEMORY_HUGE_PAGE_BYTES) {
        size_t rounded = (bytes + 63) & ~(size_t)63;
        return aligned_alloc(64, rounded ? rounded : 64);
    }
    size_t rounded = (bytes + MEMORY_HUGE_PAGE_BYTES - 1) & ~(MEMORY_HUGE_PAGE_BYTES - 1);
    void *p = aligned_alloc(MEMORY_HUGE_PAGE_BYTES, rounded);
#ifdef MADV_HUGEPAGE
    /* advice only: on kernels without THP (or with it off) this fails harmlessly */
    if (p)
        (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
    return p;
}
