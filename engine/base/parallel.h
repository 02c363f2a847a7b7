/* parallel.h - fork-join data parallelism for the engine: a pool of worker
 * threads that runs one parallel loop at a time, the calling thread included.
 *
 * A loop hands out [begin, end) chunks of an index range from one atomic
 * counter, so uneven chunks balance themselves. Which thread runs which chunk
 * is up to the scheduler: callers that need results independent of the thread
 * count (the BVH builder does) must combine per-chunk or per-worker results
 * with order-independent operations (min, max, integer sums) or by chunk index.
 *
 * Idle workers spin briefly (a few tens of microseconds, so back-to-back loops
 * don't pay a wake-up) and then sleep on a condition variable: an idle pool
 * burns no core. */
#ifndef TESSERA_PARALLEL_H
#define TESSERA_PARALLEL_H

#include <stddef.h>

typedef struct parallel_pool parallel_pool;

/* Body of a parallel loop: handle indices [begin, end). `worker` is in
 * [0, parallel_pool_threads()) and names the thread (the caller is 0), so
 * per-worker scratch needs no lock: calls with the same worker never overlap. */
typedef void (*parallel_fn)(void *ctx, size_t begin, size_t end, int worker);

/* A pool of `threads` threads counting the caller (threads - 1 are started;
 * threads < 1 counts as 1). If some threads cannot be started the pool simply
 * has fewer; NULL only when memory runs out. */
parallel_pool *parallel_pool_create(int threads);
void parallel_pool_destroy(parallel_pool *p); /* NULL is fine; the pool must be idle */

/* Threads that run a loop, the caller included; 1 for a NULL pool. */
int parallel_pool_threads(const parallel_pool *p);

/* Call fn on chunks that tile [0, count): each chunk is `grain` indices (the
 * last may be shorter; grain 0 counts as 1). Returns when every call has
 * returned; their memory effects are then visible to the caller. A NULL pool
 * runs every chunk on the caller, in order. Not reentrant: fn must not start
 * another loop on the same pool, and one loop runs at a time per pool. */
void parallel_pool_for(parallel_pool *p, size_t count, size_t grain, parallel_fn fn, void *ctx);

/* One-shot form: starts threads - 1 threads for this loop alone (about
 * 30 us per thread) unless the loop fits in one chunk. Use a pool when a
 * computation runs many loops. */
void parallel_for(int threads, size_t count, size_t grain, parallel_fn fn, void *ctx);

#endif
