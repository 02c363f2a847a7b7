/* source.c (remote) - remote viewers' input as an input source (source.h). */
#include "source.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "engine/base/log.h"

struct remote_source {
    input_source base;
    int fd;                                /* eventfd: written when events are queued */
    pthread_mutex_t lock;
    input_event queue[REMOTE_SOURCE_QUEUE]; /* lock: a ring, head .. head + count */
    int head, count;                       /* lock */
    uint64_t dropped;                      /* lock */
    input_event taken[REMOTE_SOURCE_QUEUE]; /* input thread: what dispatch hands out */
};

static int source_fd(const input_source *is) { return ((const remote_source *)is)->fd; }

static bool source_dispatch(input_source *is, input_event_fn fn, void *ctx)
{
    remote_source *s = (remote_source *)is;
    uint64_t ignored;
    if (read(s->fd, &ignored, sizeof ignored) < 0 && errno != EAGAIN)
        log_warn("remote view: reading the event counter: %s", strerror(errno));
    pthread_mutex_lock(&s->lock);
    int n = s->count;
    for (int i = 0; i < n; i++)
        s->taken[i] = s->queue[(s->head + i) % REMOTE_SOURCE_QUEUE];
    s->head = (s->head + n) % REMOTE_SOURCE_QUEUE;
    s->count = 0;
    pthread_mutex_unlock(&s->lock);
    for (int i = 0; i < n; i++)
        fn(ctx, &s->taken[i]);
    return true;
}

/* Remote viewers are not the seat's devices: a VT switch leaves them be. */
static void source_suspend(input_source *is) { (void)is; }
static void source_resume(input_source *is) { (void)is; }
static bool source_suspended(const input_source *is)
{
    (void)is;
    return false;
}
static int source_device_count(const input_source *is)
{
    (void)is;
    return 1;
}

static void source_destroy(input_source *is)
{
    remote_source *s = (remote_source *)is;
    if (s->fd >= 0)
        close(s->fd);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

static const input_source_ops remote_source_ops = {
    .name = "remote view",
    .fd = source_fd,
    .dispatch = source_dispatch,
    .suspend = source_suspend,
    .resume = source_resume,
    .suspended = source_suspended,
    .device_count = source_device_count,
    .destroy = source_destroy,
};

remote_source *remote_source_create(tess_error *err)
{
    remote_source *s = calloc(1, sizeof *s);
    if (!s) {
        tess_error_set(err, "remote view: out of memory");
        return NULL;
    }
    s->base.ops = &remote_source_ops;
    pthread_mutex_init(&s->lock, NULL);
    s->fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (s->fd < 0) {
        tess_error_set(err, "remote view: eventfd: %s", strerror(errno));
        source_destroy(&s->base);
        return NULL;
    }
    return s;
}

input_source *remote_source_input(remote_source *s) { return &s->base; }

bool remote_source_push(remote_source *s, const input_event *events, int count)
{
    pthread_mutex_lock(&s->lock);
    bool fits = s->count + count <= REMOTE_SOURCE_QUEUE;
    if (fits) {
        for (int i = 0; i < count; i++)
            s->queue[(s->head + s->count + i) % REMOTE_SOURCE_QUEUE] = events[i];
        s->count += count;
    } else {
        s->dropped++;
    }
    pthread_mutex_unlock(&s->lock);
    uint64_t one = 1;
    if (fits && write(s->fd, &one, sizeof one) < 0 && errno != EAGAIN)
        log_warn("remote view: waking the input thread: %s", strerror(errno));
    return fits;
}

uint64_t remote_source_dropped(remote_source *s)
{
    pthread_mutex_lock(&s->lock);
    uint64_t d = s->dropped;
    pthread_mutex_unlock(&s->lock);
    return d;
}
