/* runner.c - the input thread (runner.h). */
#include "input/runner.h"

#include <assert.h>
#include <errno.h>
#include <poll.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <time.h>
#include <unistd.h>

#include "engine/clock.h"
#include "engine/thread_name.h"
#include "engine/log.h"
#include "seat/session.h"

#define SEAT_CHECK_MS 200 /* with a seat: how often the input thread looks whether it is still ours */

struct input_runner {
    struct session *sn;       /* the seat (NULL: none): its devices are revoked on a VT switch */
    input_source *sources[INPUT_MAX_SOURCES]; /* owned; polled through their interface alone */
    int source_count;
    input_controller *controller;
    input_sink *sink;
    input_pick_fn pick;
    input_step_ready_fn step_ready;
    void *pick_ctx;
    int wake_fd;
    atomic_bool stop;
    pthread_t thread;
    bool started;
};

static void hook_pick(void *ctx, vec3 origin, vec3 dir, input_hit *out)
{
    input_runner *r = ctx;
    r->pick(r->pick_ctx, origin, dir, out);
}

static bool hook_step_ready(void *ctx, uint32_t step)
{
    input_runner *r = ctx;
    return !r->step_ready || r->step_ready(r->pick_ctx, step);
}

static void hook_emit(void *ctx, const input_txn *t)
{
    input_runner *r = ctx;
    input_sink_emit(r->sink, t);
}

static camera_desc hook_current_camera(void *ctx)
{
    input_runner *r = ctx;
    return input_sink_current_camera(r->sink);
}

static void on_event(void *ctx, const input_event *e)
{
    input_runner *r = ctx;
    input_controller_event(r->controller, e);
}

static void *input_main(void *arg)
{
    input_runner *r = arg;
    thread_name_set("tess-input");
    input_controller_tick(r->controller, clock_monotonic_us());
    bool said_devices = false;
    while (!atomic_load(&r->stop)) {
        uint64_t now = clock_monotonic_us();
        uint64_t deadline = input_controller_deadline_us(r->controller, now);
        int timeout_ms = 1000; /* also how often missing path devices are tried again */
        bool seat = r->sn && session_has_seat(r->sn);
        if (seat)
            timeout_ms = SEAT_CHECK_MS;
        if (deadline != UINT64_MAX) {
            uint64_t wait_us = deadline > now ? deadline - now : 0;
            if (wait_us < 1000000u)
                timeout_ms = (int)((wait_us + 999u) / 1000u);
        }
        struct pollfd fds[INPUT_MAX_SOURCES + 1];
        for (int i = 0; i < r->source_count; i++)
            fds[i] = (struct pollfd){.fd = input_source_fd(r->sources[i]), .events = POLLIN};
        fds[r->source_count] = (struct pollfd){.fd = r->wake_fd, .events = POLLIN};
        int n = poll(fds, (nfds_t)r->source_count + 1, timeout_ms);
        if (n < 0 && errno != EINTR) {
            log_error("input: poll failed: %s; input stops", strerror(errno));
            break;
        }
        if (atomic_load(&r->stop))
            break;
        /* a VT switch: the seat revokes our devices; release them and take them back on return
         * (the display thread acknowledges the switch; this thread only follows it) */
        bool failed = false, all_resumed = true;
        int devices = 0;
        for (int i = 0; i < r->source_count && !failed; i++) {
            input_source *src = r->sources[i];
            if (seat && !session_active(r->sn))
                input_source_suspend(src);
            else if (seat && input_source_suspended(src))
                input_source_resume(src);
            if (!input_source_dispatch(src, on_event, r)) {
                log_error("input: %s failed; input stops (the wall goes on)", src->ops->name);
                failed = true;
            }
            all_resumed = all_resumed && !input_source_suspended(src);
            devices += input_source_device_count(src);
        }
        if (failed)
            break;
        if (!said_devices && all_resumed) { /* the first events are the devices */
            said_devices = true;
            if (devices == 0)
                log_warn("input: no input device found (a wrong --seat or --input-device?); they are picked up "
                         "when they appear");
        }
        now = clock_monotonic_us();
        if (now >= deadline) /* the deadline asked for before the wait has come */
            input_controller_tick(r->controller, now);
    }
    return NULL;
}

input_runner *input_runner_start(input_source *const *sources, int source_count,
                                 const input_controller_config *controller, input_pick_fn pick,
                                 input_step_ready_fn step_ready, void *pick_ctx, input_sink *sink, struct session *sn,
                                 tess_error *err)
{
    assert(source_count >= 1 && source_count <= INPUT_MAX_SOURCES);
    input_runner *r = calloc(1, sizeof *r);
    if (!r) {
        for (int i = 0; i < source_count; i++)
            input_source_destroy(sources[i]);
        tess_error_set(err, "input: out of memory");
        return NULL;
    }
    for (int i = 0; i < source_count; i++)
        r->sources[i] = sources[i];
    r->source_count = source_count;
    r->sink = sink;
    r->pick = pick;
    r->step_ready = step_ready;
    r->pick_ctx = pick_ctx;
    r->wake_fd = -1;
    atomic_init(&r->stop, false);
    input_controller_hooks hooks = {
        .ctx = r, .pick = hook_pick, .emit = hook_emit, .current_camera = hook_current_camera,
        .step_ready = hook_step_ready};
    r->controller = input_controller_create(controller, &hooks);
    r->wake_fd = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (!r->controller || r->wake_fd < 0) {
        tess_error_set(err, "input: out of memory or file descriptors");
        goto fail;
    }
    r->sn = sn;
    if (pthread_create(&r->thread, NULL, input_main, r) != 0) {
        tess_error_set(err, "input: cannot start the input thread");
        goto fail;
    }
    r->started = true;
    return r;
fail:
    input_runner_stop(r);
    return NULL;
}

void input_runner_stop(input_runner *r)
{
    if (!r)
        return;
    if (r->started) {
        atomic_store(&r->stop, true);
        uint64_t one = 1;
        if (write(r->wake_fd, &one, sizeof one) < 0)
            log_warn("input: waking the input thread failed: %s", strerror(errno));
        pthread_join(r->thread, NULL);
    }
    for (int i = 0; i < r->source_count; i++)
        input_source_destroy(r->sources[i]);
    input_controller_destroy(r->controller);
    if (r->wake_fd >= 0)
        close(r->wake_fd);
    free(r);
}
