/* runner.c - the input thread (runner.h). */
#include "runner.h"

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

#include "engine/base/clock.h"
#include "engine/base/thread_name.h"
#include "engine/base/log.h"
#include "seat/session.h"

#define SEAT_CHECK_MS 200 /* with a seat: how often the input thread looks whether it is still ours */

/* A remote viewer's private view: its device's events go to a controller of its own. */
typedef struct private_view {
    bool used;
    int device;
    int channel;
    input_controller *controller;
    uint64_t due_us;       /* its deadline as asked before the wait (UINT64_MAX: none) */
} private_view;

struct input_runner {
    struct session *sn;       /* the seat (NULL: none): its devices are revoked on a VT switch */
    input_source *sources[INPUT_MAX_SOURCES]; /* owned; polled through their interface alone */
    int source_count;
    input_controller *controller;      /* the wall's: every device not in `privates` */
    input_controller_config controller_cfg; /* its config, the start of a private view's */
    input_controller_hooks hooks;      /* every controller's */
    private_view privates[INPUT_MAX_VIEWERS];
    uint64_t due_us;                   /* the wall's controller's deadline as asked before the wait */
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

static private_view *private_of(input_runner *r, int device)
{
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++)
        if (r->privates[i].used && r->privates[i].device == device)
            return &r->privates[i];
    return NULL;
}

static void private_end(input_runner *r, private_view *pv)
{
    input_txn off = txn_channel_active(pv->channel, false);
    input_sink_emit(r->sink, &off);
    input_controller_destroy(pv->controller);
    log_info("input: device %d's private view (channel %d) ends", pv->device, pv->channel);
    memset(pv, 0, sizeof *pv);
}

/* INPUT_PRIVATE_VIEW: the device steers channel e->code with a controller of
 * its own, starting from the wall's camera; the channel is switched on after
 * its camera is set, so its first frame already shows that camera. */
static void private_start(input_runner *r, const input_event *e)
{
    private_view *pv = private_of(r, e->device);
    if (pv)
        private_end(r, pv);
    for (int i = 0; i < INPUT_MAX_VIEWERS && !pv; i++)
        if (!r->privates[i].used)
            pv = &r->privates[i];
    if (!pv || e->code <= 0) {
        log_warn("input: device %d: a private view of channel %d refused (%s)", e->device, e->code,
                 pv ? "channel 0 is the wall's" : "too many private views");
        return;
    }
    input_controller_config cfg = r->controller_cfg;
    cfg.private_channel = e->code;
    input_controller *c = input_controller_create(&cfg, &r->hooks);
    if (!c) {
        log_error("input: device %d: no private view: out of memory", e->device);
        return;
    }
    *pv = (private_view){.used = true, .device = e->device, .channel = e->code, .controller = c, .due_us = UINT64_MAX};
    input_controller_tick(c, e->time_us);
    input_controller_jump(c, input_sink_current_camera(r->sink));
    input_txn on = txn_channel_active(pv->channel, true);
    input_sink_emit(r->sink, &on);
    log_info("input: device %d steers channel %d (a private view)", e->device, e->code);
}

/* Events of a device with a private view go to its controller (its removal
 * ends the view); the rest to the wall's. */
static void on_event(void *ctx, const input_event *e)
{
    input_runner *r = ctx;
    if (e->kind == INPUT_PRIVATE_VIEW) {
        private_start(r, e);
        return;
    }
    private_view *pv = private_of(r, e->device);
    if (!pv) {
        input_controller_event(r->controller, e);
        return;
    }
    input_controller_event(pv->controller, e);
    if (e->kind == INPUT_DEVICE_REMOVED)
        private_end(r, pv);
}

/* Ask every controller for its deadline before the wait (kept: a deadline asked
 * again once it has passed may lie ahead, e.g. the idle tour's, which says "a
 * second from now" when asked late); the earliest. */
static uint64_t deadline_us(input_runner *r, uint64_t now)
{
    uint64_t d = r->due_us = input_controller_deadline_us(r->controller, now);
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++)
        if (r->privates[i].used) {
            uint64_t p = r->privates[i].due_us = input_controller_deadline_us(r->privates[i].controller, now);
            d = p < d ? p : d;
        }
    return d;
}

/* Tick every controller whose deadline, as asked before the wait, has come. */
static void tick_due(input_runner *r, uint64_t now)
{
    if (r->due_us <= now)
        input_controller_tick(r->controller, now);
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++)
        if (r->privates[i].used && r->privates[i].due_us <= now)
            input_controller_tick(r->privates[i].controller, now);
}

static void *input_main(void *arg)
{
    input_runner *r = arg;
    thread_name_set("tess-input");
    input_controller_tick(r->controller, clock_monotonic_us());
    bool said_devices = false;
    while (!atomic_load(&r->stop)) {
        uint64_t now = clock_monotonic_us();
        uint64_t deadline = deadline_us(r, now);
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
            tick_due(r, now);
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
    r->hooks = (input_controller_hooks){
        .ctx = r, .pick = hook_pick, .emit = hook_emit, .current_camera = hook_current_camera,
        .step_ready = hook_step_ready};
    r->controller_cfg = *controller;
    r->controller_cfg.private_channel = 0;
    r->controller = input_controller_create(&r->controller_cfg, &r->hooks);
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
    for (int i = 0; i < INPUT_MAX_VIEWERS; i++)
        input_controller_destroy(r->privates[i].controller); /* the run is over: their channels stay */
    input_controller_destroy(r->controller);
    if (r->wake_fd >= 0)
        close(r->wake_fd);
    free(r);
}
