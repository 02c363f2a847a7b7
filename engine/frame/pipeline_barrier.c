/* pipeline_barrier.c - the barrier whose last arriving thread runs a function
 * (the frame barrier's serial section) before it releases the others; the
 * frame, animation and upscale barriers are all this one. */
#include "pipeline_private.h"

#include <pthread.h>
#include <stdatomic.h>

void pipeline_barrier_init(barrier *b)
{
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->released, NULL);
    b->participants = 1;
    b->arrived = 0;
    atomic_init(&b->generation, 0);
}

void pipeline_barrier_destroy(barrier *b)
{
    pthread_cond_destroy(&b->released);
    pthread_mutex_destroy(&b->lock);
}

/* Wait until all participants have arrived. The last one runs `serial(p)`
 * (if not NULL) while the others wait; serial returns the participants of the
 * next use (-1 keeps them), set before anyone is released. */
void pipeline_barrier_wait(barrier *b, pipeline *p, int (*serial)(pipeline *p))
{
    pthread_mutex_lock(&b->lock);
    uint64_t generation = atomic_load_explicit(&b->generation, memory_order_relaxed);
    if (++b->arrived == b->participants) {
        pthread_mutex_unlock(&b->lock);
        /* every participant is waiting below: nobody else runs */
        int participants = serial ? serial(p) : -1;
        pthread_mutex_lock(&b->lock);
        if (participants > 0)
            b->participants = participants;
        b->arrived = 0;
        atomic_store_explicit(&b->generation, generation + 1, memory_order_release);
        pthread_cond_broadcast(&b->released);
        pthread_mutex_unlock(&b->lock);
        return;
    }
    while (atomic_load_explicit(&b->generation, memory_order_acquire) == generation)
        pthread_cond_wait(&b->released, &b->lock);
    pthread_mutex_unlock(&b->lock);
}

/* Participants of a barrier nobody is waiting at (between steps). */
void pipeline_barrier_set_participants(barrier *b, int participants)
{
    pthread_mutex_lock(&b->lock);
    b->participants = participants;
    pthread_mutex_unlock(&b->lock);
}
