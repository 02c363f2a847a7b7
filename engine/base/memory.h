/* memory.h - allocations for large, hot, read-mostly arrays (BVH nodes and
 * leaf blocks): 64-byte aligned always; from 2 MiB up, aligned to 2 MiB and
 * marked for transparent huge pages, so traversal of hundreds of megabytes
 * does not miss the TLB on every node. Free with free(). */
#ifndef TESSERA_MEMORY_H
#define TESSERA_MEMORY_H

#include <stddef.h>

void *memory_alloc_large(size_t bytes);

#endif
