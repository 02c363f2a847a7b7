#include "parallel.h"
#include "thread_name.h"

#include <assert.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdlib.h>

/* Polls of a changing counter before a thread sleeps: some 30 us (a pause is
 * ~26 ns on the development machine, a yield ~0.5 us), longer than the serial
 * gap between two loops of the BVH builder, far shorter than any idle period. */
#define PARALLEL_SPIN_POLLS 1024
/* Every this many polls the spinner yields its core instead of pausing, so a pool
 * with more threads than cores lets the threads with work run. */
#define PARALLEL_YIELD_EVERY 64

/* Lifecycle of one loop (a "job"):
 *  1. The caller, with every worker idle (pending == 0), writes the job fields,
 *     sets next = 0 and pending = workers, then bumps `generation` under `lock`
 *     and broadcasts `wake`.
 *  2. A worker that sees a new generation (acquire) reads the job fields, claims
 *     chunks from `next` until none are left, then decrements `pending`; the
 *     one that brings it to 0 signals `done` under `lock`.
 *  3. The caller runs chunks too, then waits for pending == 0 (acquire), which
 *     orders every worker's writes before its return.
 * Stopping is a job with `stop` set. */
struct parallel_pool {
    int threads;            /* workers + the caller; fixed after create */
    pthread_t *workers;     /* threads - 1 ids; fixed after create */
    pthread_mutex_t lock;   /* held to change `generation` and to signal/wait on the condvars,
                             * so a thread that checked a counter under it cannot miss the signal */
    pthread_cond_t wake;    /* workers sleep here for a new generation */
    pthread_cond_t done;    /* the caller sleeps here for pending == 0 */
    atomic_uint generation; /* job number; written by the caller under `lock` (release), polled by workers */
    atomic_int pending;     /* workers that have not finished the current job */
    atomic_size_t next;     /* first unclaimed index of the current job */
    atomic_bool stop;       /* set by destroy before its final generation bump */
    atomic_bool busy;       /* a loop is running: catches reentrant or concurrent use */
    /* The current job: written by the caller only while pending == 0 (no worker
     * reads them then), published to workers by the generation bump. */
    parallel_fn fn;
    void *ctx;
    size_t count, grain;
};

typedef struct worker_arg {
    parallel_pool *pool;
    int worker; /* 1 .. threads - 1 */
} worker_arg;

/* One poll's wait while spinning. */
static inline void spin_pause(int poll)
{
    if (poll % PARALLEL_YIELD_EVERY == PARALLEL_YIELD_EVERY - 1) {
        sched_yield();
        return;
    }
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#elif defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

/* Claim and run chunks of the current job until none are left. */
static void run_chunks(parallel_pool *p, int worker)
{
    for (;;) {
        size_t begin = atomic_fetch_add_explicit(&p->next, p->grain, memory_order_relaxed);
        if (begin >= p->count)
            return;
        size_t end = p->count - begin > p->grain ? begin + p->grain : p->count;
        p->fn(p->ctx, begin, end, worker);
    }
}

/* Wait until generation differs from `seen`; returns the new value. */
static unsigned wait_generation(parallel_pool *p, unsigned seen)
{
    for (int i = 0; i < PARALLEL_SPIN_POLLS; i++) {
        unsigned g = atomic_load_explicit(&p->generation, memory_order_acquire);
        if (g != seen)
            return g;
        spin_pause(i);
    }
    pthread_mutex_lock(&p->lock);
    unsigned g;
    while ((g = atomic_load_explicit(&p->generation, memory_order_acquire)) == seen)
        pthread_cond_wait(&p->wake, &p->lock);
    pthread_mutex_unlock(&p->lock);
    return g;
}

static void *worker_main(void *arg)
{
    worker_arg a = *(worker_arg *)arg;
    free(arg);
    thread_name_set("tess-pool");
    parallel_pool *p = a.pool;
    unsigned seen = 0; /* the generation at create */
    for (;;) {
        seen = wait_generation(p, seen);
        if (atomic_load_explicit(&p->stop, memory_order_relaxed))
            return NULL;
        run_chunks(p, a.worker);
        /* release: our chunks' writes happen before the caller's return */
        if (atomic_fetch_sub_explicit(&p->pending, 1, memory_order_acq_rel) == 1) {
            pthread_mutex_lock(&p->lock);
            pthread_cond_signal(&p->done);
            pthread_mutex_unlock(&p->lock);
        }
    }
}

/* Publish the job already written into p to the workers. */
static void publish(parallel_pool *p)
{
    atomic_store_explicit(&p->next, 0, memory_order_relaxed);
    atomic_store_explicit(&p->pending, p->threads - 1, memory_order_relaxed);
    pthread_mutex_lock(&p->lock);
    atomic_fetch_add_explicit(&p->generation, 1, memory_order_release);
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
}

static void wait_workers(parallel_pool *p)
{
    for (int i = 0; i < PARALLEL_SPIN_POLLS; i++) {
        if (atomic_load_explicit(&p->pending, memory_order_acquire) == 0)
            return;
        spin_pause(i);
    }
    pthread_mutex_lock(&p->lock);
    while (atomic_load_explicit(&p->pending, memory_order_acquire) != 0)
        pthread_cond_wait(&p->done, &p->lock);
    pthread_mutex_unlock(&p->lock);
}

parallel_pool *parallel_pool_create(int threads)
{
    if (threads < 1)
        threads = 1;
    parallel_pool *p = calloc(1, sizeof *p);
    if (!p)
        return NULL;
    p->workers = calloc((size_t)threads, sizeof *p->workers);
    if (!p->workers) {
        free(p);
        return NULL;
    }
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->wake, NULL);
    pthread_cond_init(&p->done, NULL);
    atomic_init(&p->generation, 0);
    atomic_init(&p->pending, 0);
    atomic_init(&p->next, 0);
    atomic_init(&p->stop, false);
    atomic_init(&p->busy, false);
    p->threads = 1;
    /* Workers see threads only through jobs published after this loop, so
     * bumping it as each one starts is safe. */
    for (int i = 1; i < threads; i++) {
        worker_arg *a = malloc(sizeof *a);
        if (!a)
            break;
        *a = (worker_arg){p, i};
        if (pthread_create(&p->workers[i - 1], NULL, worker_main, a) != 0) {
            free(a);
            break;
        }
        p->threads++;
    }
    return p;
}

void parallel_pool_destroy(parallel_pool *p)
{
    if (!p)
        return;
    assert(!atomic_load(&p->busy));
    atomic_store_explicit(&p->stop, true, memory_order_relaxed);
    publish(p); /* the release bump orders `stop` before the workers see it */
    for (int i = 0; i < p->threads - 1; i++)
        pthread_join(p->workers[i], NULL);
    pthread_cond_destroy(&p->done);
    pthread_cond_destroy(&p->wake);
    pthread_mutex_destroy(&p->lock);
    free(p->workers);
    free(p);
}

int parallel_pool_threads(const parallel_pool *p) { return p ? p->threads : 1; }

void parallel_pool_for(parallel_pool *p, size_t count, size_t grain, parallel_fn fn, void *ctx)
{
    if (grain == 0)
        grain = 1;
    if (!p || p->threads == 1 || count <= grain) {
        for (size_t begin = 0; begin < count; begin += grain)
            fn(ctx, begin, count - begin > grain ? begin + grain : count, 0);
        return;
    }
    bool was_busy = atomic_exchange(&p->busy, true);
    assert(!was_busy && "parallel_pool_for: reentrant or concurrent use of one pool");
    (void)was_busy;
    p->fn = fn;
    p->ctx = ctx;
    p->count = count;
    p->grain = grain;
    publish(p);
    run_chunks(p, 0);
    wait_workers(p);
    atomic_store(&p->busy, false);
}

void parallel_for(int threads, size_t count, size_t grain, parallel_fn fn, void *ctx)
{
    parallel_pool *p = NULL;
    if (threads > 1 && count > (grain ? grain : 1))
        p = parallel_pool_create(threads); /* NULL (out of memory): runs on the caller */
    parallel_pool_for(p, count, grain, fn, ctx);
    parallel_pool_destroy(p);
}
