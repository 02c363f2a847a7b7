/* service.c - readiness, status and the watchdog for systemd (service.h),
 * through libsystemd's sd_notify. */
#include "service.h"

#include <inttypes.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <systemd/sd-daemon.h>

#include "engine/base/clock.h"
#include "engine/base/log.h"
#include "engine/base/thread_name.h"
#include "engine/frame/pipeline.h"

#define SERVICE_MESSAGE_BYTES 256 /* one datagram: a few assignments and a status line */
#define SERVICE_STATUS_BYTES 160

/* What the frame loop asked to send and the sender thread has not sent yet
 * (newer replaces older: one status line, flags). */
typedef struct outbox {
    bool ping, ready, stopping;
    char status[SERVICE_STATUS_BYTES]; /* "" for none */
} outbox;

struct service_notifier {
    /* the frame loop's side: the serial section and the display thread, never at once */
    double watchdog_s;       /* WATCHDOG_USEC in seconds; 0: no watchdog */
    bool ready;              /* READY=1 posted */
    double last_ping_s;      /* when WATCHDOG=1 was last posted; -1: never */
    double last_status_s;    /* when STATUS= was last posted; -1: never */
    uint64_t status_frame;   /* the frame of the last running STATUS (frames/s since then) */
    int output_channels;     /* channels 0 .. output_channels-1 are the outputs (attach) */
    int outputs_up, outputs; /* channels switched on / all, as the last STATUS said */
    bool paused;             /* the last STATUS said paused */
    /* the sender thread: sd_notify is a socket, a sendmsg and a close (tens of us, more
     * when the machine is busy): no I/O at the frame barrier */
    pthread_t sender;
    pthread_mutex_t lock;    /* guards box and quit */
    pthread_cond_t wake;     /* something was posted, or quit */
    outbox box;
    bool quit;
    bool send_failed;        /* sender thread only: a failed sd_notify was logged (said once) */
};

bool service_watchdog_due(double now_s, double last_s, double interval_s)
{
    return last_s < 0.0 || now_s - last_s >= interval_s / SERVICE_PINGS_PER_INTERVAL;
}

/* One datagram; a failure is said once (the kiosk goes on: if systemd
 * cannot hear us it restarts us, which the log then explains). */
static void notify(service_notifier *sn, const outbox *b)
{
    char msg[SERVICE_MESSAGE_BYTES];
    snprintf(msg, sizeof msg, "%s%s%s%s%s", b->ping ? "WATCHDOG=1\n" : "", b->ready ? "READY=1\n" : "",
             b->stopping ? "STOPPING=1\n" : "", b->status[0] ? "STATUS=" : "", b->status);
    size_t n = strlen(msg);
    if (n > 0 && msg[n - 1] == '\n')
        msg[n - 1] = '\0';
    int r = sd_notify(0, msg);
    if (r > 0 || sn->send_failed)
        return;
    sn->send_failed = true;
    if (r == 0)
        log_warn("service: NOTIFY_SOCKET went away: not telling the service manager anything more");
    else
        log_warn("service: cannot notify the service manager: %s (said once)", strerror(-r));
}

static void *sender_main(void *arg)
{
    service_notifier *sn = arg;
    thread_name_set("tess-notify");
    pthread_mutex_lock(&sn->lock);
    for (;;) {
        bool pending = sn->box.ping || sn->box.ready || sn->box.stopping || sn->box.status[0];
        if (!pending && sn->quit)
            break;
        if (!pending) {
            pthread_cond_wait(&sn->wake, &sn->lock);
            continue;
        }
        outbox b = sn->box;
        memset(&sn->box, 0, sizeof sn->box);
        pthread_mutex_unlock(&sn->lock);
        notify(sn, &b);
        pthread_mutex_lock(&sn->lock);
    }
    pthread_mutex_unlock(&sn->lock);
    return NULL;
}

/* Hand assignments to the sender (status NULL: none). */
static void post(service_notifier *sn, bool ping, bool ready, bool stopping, const char *status)
{
    pthread_mutex_lock(&sn->lock);
    sn->box.ping = sn->box.ping || ping;
    sn->box.ready = sn->box.ready || ready;
    sn->box.stopping = sn->box.stopping || stopping;
    if (status)
        snprintf(sn->box.status, sizeof sn->box.status, "%s", status);
    pthread_cond_signal(&sn->wake);
    pthread_mutex_unlock(&sn->lock);
}

service_notifier *service_notifier_create(void)
{
    const char *socket_path = getenv("NOTIFY_SOCKET");
    if (!socket_path || !socket_path[0])
        return NULL;
    service_notifier *sn = calloc(1, sizeof *sn);
    if (!sn) {
        log_error("service: out of memory; not telling the service manager (%s) anything", socket_path);
        return NULL;
    }
    pthread_mutex_init(&sn->lock, NULL);
    pthread_cond_init(&sn->wake, NULL);
    int e = pthread_create(&sn->sender, NULL, sender_main, sn);
    if (e != 0) {
        log_error("service: cannot start the notifier thread: %s; not telling the service manager anything",
                  strerror(e));
        pthread_cond_destroy(&sn->wake);
        pthread_mutex_destroy(&sn->lock);
        free(sn);
        return NULL;
    }
    uint64_t usec = 0;
    int r = sd_watchdog_enabled(0, &usec);
    if (r < 0)
        log_warn("service: WATCHDOG_USEC or WATCHDOG_PID unreadable (%s): no watchdog", strerror(-r));
    sn->watchdog_s = r > 0 ? 1e-6 * (double)usec : 0.0;
    sn->last_ping_s = -1.0;
    sn->last_status_s = -1.0;
    sn->outputs_up = sn->outputs = -1;
    if (sn->watchdog_s > 0.0)
        log_info("service: watchdog every %.3g s: WATCHDOG=1 from the frame loop at most every %.3g s", sn->watchdog_s,
                 sn->watchdog_s / SERVICE_PINGS_PER_INTERVAL);
    else
        log_info("service: notifying %s (no watchdog asked for)", socket_path);
    return sn;
}

void service_notifier_destroy(service_notifier *sn)
{
    if (!sn)
        return;
    pthread_mutex_lock(&sn->lock);
    sn->quit = true; /* the sender sends what is posted (STOPPING=1), then leaves */
    pthread_cond_signal(&sn->wake);
    pthread_mutex_unlock(&sn->lock);
    pthread_join(sn->sender, NULL);
    pthread_cond_destroy(&sn->wake);
    pthread_mutex_destroy(&sn->lock);
    free(sn);
}

double service_notifier_watchdog_s(const service_notifier *sn) { return sn ? sn->watchdog_s : 0.0; }

/* WATCHDOG=1 when due, with `status` (may be NULL) and READY=1 if `ready`;
 * nothing when none is wanted. */
static void report(service_notifier *sn, double now, bool ready, const char *status)
{
    bool feed = sn->watchdog_s > 0.0 && service_watchdog_due(now, sn->last_ping_s, sn->watchdog_s);
    if (!feed && !ready && !status)
        return;
    post(sn, feed, ready, false, status);
    if (feed)
        sn->last_ping_s = now;
}

/* Serial section, every frame. */
static void on_frame(pipeline *p, void *ctx, const frame_info *fi)
{
    service_notifier *sn = ctx;
    double now = clock_monotonic_s();
    int outputs = sn->output_channels, up = 0;
    for (int i = 0; i < outputs; i++)
        up += pipeline_channel_active(p, i);
    char status[SERVICE_STATUS_BYTES];
    bool with_status = false;
    bool changed = up != sn->outputs_up || outputs != sn->outputs || sn->paused;
    bool ready_now = !sn->ready && pipeline_get_stats(p).frames_displayed > 0; /* frame 0 has been shown */
    if (ready_now || (sn->ready && (changed || now - sn->last_status_s >= SERVICE_STATUS_PERIOD_S))) {
        char rate[48] = "";
        double span_s = now - sn->last_status_s;
        if (sn->ready && !sn->paused && sn->last_status_s >= 0.0 && span_s > 0.0 && fi->frame > sn->status_frame)
            snprintf(rate, sizeof rate, "%.1f frames/s, ", (double)(fi->frame - sn->status_frame) / span_s);
        snprintf(status, sizeof status, "running: %s%d of %d output%s up", rate, up, outputs, outputs == 1 ? "" : "s");
        with_status = true;
        sn->ready = true;
        sn->last_status_s = now;
        sn->status_frame = fi->frame;
        sn->outputs_up = up;
        sn->outputs = outputs;
        sn->paused = false;
    }
    report(sn, now, ready_now, with_status ? status : NULL);
}

static void on_termination(pipeline *p, void *ctx)
{
    service_notifier *sn = ctx;
    char status[SERVICE_STATUS_BYTES];
    snprintf(status, sizeof status, "stopping after %" PRIu64 " frames", pipeline_get_stats(p).frames_rendered);
    post(sn, false, false, true, status);
}

bool service_notifier_attach(service_notifier *sn, pipeline *p, int outputs)
{
    if (!sn)
        return true;
    int channels = pipeline_channel_count(p);
    sn->output_channels = outputs < 0 || outputs > channels ? channels : outputs;
    return pipeline_add_serial_animation(p, "service notifier", on_frame, sn) &&
           pipeline_add_termination(p, "service notifier", on_termination, sn);
}

void service_notifier_paused(service_notifier *sn, const char *why)
{
    if (!sn)
        return;
    double now = clock_monotonic_s();
    char status[SERVICE_STATUS_BYTES];
    bool with_status = false;
    if (why && !sn->paused) {
        snprintf(status, sizeof status, "paused: %s", why);
        with_status = true;
        sn->paused = true; /* the next frame says "running" again */
        sn->last_status_s = now;
    }
    if (why || sn->paused)
        report(sn, now, false, with_status ? status : NULL);
}
