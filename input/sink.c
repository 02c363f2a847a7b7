/* sink.c - input transactions into a pipeline (sink.h). */
#include "sink.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/base/clock.h"
#include "engine/base/thread_name.h"
#include "engine/base/log.h"
#include "navigate.h"

struct input_sink {
    pipeline *p;
    input_sink_config cfg;
    double t0_s;                   /* recording time 0 (clock_monotonic_s) */

    pthread_mutex_t lock;          /* guards the mailbox and `shown` */
    bool mail_queued;              /* a mailbox transaction waits for the barrier */
    bool mail_has_camera, mail_has_cursor;
    camera_desc mail_camera;
    bool mail_cursor_on;
    float mail_sx, mail_sy;
    camera_desc shown;             /* the camera the wall shows (set in the serial section) */

    pthread_mutex_t record_lock;   /* guards `record` */
    FILE *record;

    /* the tour: serial section only */
    bool tour_on, tour_fresh;
    double tour_start_s;
    camera_desc tour_from;

    /* replay */
    input_record replay;
    size_t replay_next;            /* FRAMES: the next entry */
    pthread_t replay_thread;
    bool replay_thread_started;
    atomic_bool replay_stop;

    atomic_uint_fast64_t emitted, refused;
    atomic_uint_fast64_t replayed;        /* played back from a record (not emitted) */
    atomic_uint_fast64_t queued;          /* pipeline transactions queued (accepted) */
    atomic_uint_fast64_t camera_changes;  /* cameras put into the mailbox */
    atomic_uint_fast64_t camera_applied;  /* mailbox transactions that applied a camera */
    atomic_uint_fast64_t tour_starts, tour_stops; /* the tour started / stopped at a barrier */
};

/* ---- serial section: applying ------------------------------------------------------ */

static void show_camera(input_sink *s, pipeline *p, const camera_desc *c)
{
    txn_record r = txn_camera(TXN_ALL_CHANNELS, c); /* the wall's camera: every channel */
    pipeline_apply(p, &r);
    pthread_mutex_lock(&s->lock);
    s->shown = *c;
    pthread_mutex_unlock(&s->lock);
}

static void apply_mail(pipeline *p, void *args)
{
    input_sink *s = *(input_sink **)args;
    pthread_mutex_lock(&s->lock);
    bool has_camera = s->mail_has_camera, has_cursor = s->mail_has_cursor;
    camera_desc cam = s->mail_camera;
    bool on = s->mail_cursor_on;
    float sx = s->mail_sx, sy = s->mail_sy;
    s->mail_has_camera = s->mail_has_cursor = false;
    s->mail_queued = false;
    pthread_mutex_unlock(&s->lock);
    if (has_camera) {
        show_camera(s, p, &cam);
        atomic_fetch_add(&s->camera_applied, 1);
    }
    if (has_cursor) {
        txn_record r = txn_cursor(on, sx, sy);
        pipeline_apply(p, &r);
    }
}

typedef struct tour_args {
    input_sink *s;
    bool on;
} tour_args;

static void apply_tour(pipeline *p, void *args)
{
    (void)p;
    const tour_args *a = args;
    if (!a->s->cfg.tour)
        return;
    if (a->on && !a->s->tour_on)
        a->s->tour_fresh = true;
    if (a->on != a->s->tour_on)
        atomic_fetch_add(a->on ? &a->s->tour_starts : &a->s->tour_stops, 1);
    a->s->tour_on = a->on;
}

static void apply_quit(pipeline *p, void *args)
{
    (void)args;
    pipeline_stop(p); /* (logged when queued: no I/O at the barrier) */
}

/* The tour player: a serial animation. */
static void tour_step(pipeline *p, void *ctx, const frame_info *fi)
{
    input_sink *s = ctx;
    if (!s->tour_on)
        return;
    if (s->tour_fresh) {
        s->tour_fresh = false;
        s->tour_start_s = fi->time_s;
        s->tour_from = pipeline_camera(p, 0);
    }
    const camera_path *path = s->cfg.tour;
    double t = fi->time_s - s->tour_start_s;
    double duration = camera_path_duration(path);
    double path_t = path->count ? path->keys[0].time_s : 0.0;
    if (duration > 0.0)
        path_t += fmod(t, duration);
    camera_desc cam = camera_path_eval(path, path_t);
    if (t < s->cfg.tour_ease_s)
        cam = navigate_blend(&s->tour_from, &cam, navigate_ease(t / s->cfg.tour_ease_s));
    show_camera(s, p, &cam);
}

#define SINK_ORIGIN_BYTES 512 /* "--replay-input FILE:LINE" (a longer name is cut) */

/* ---- any thread: queueing ------------------------------------------------------------ */

static void count_refused(input_sink *s, bool queued)
{
    atomic_fetch_add(queued ? &s->queued : &s->refused, 1);
}

static void queue_mail(input_sink *s, const input_txn *t)
{
    pthread_mutex_lock(&s->lock);
    if (t->kind == TXN_CAMERA) {
        atomic_fetch_add(&s->camera_changes, 1);
        s->mail_has_camera = true;
        s->mail_camera = t->args.camera.camera;
    } else {
        s->mail_has_cursor = true;
        s->mail_cursor_on = t->args.cursor.on;
        s->mail_sx = t->args.cursor.sx;
        s->mail_sy = t->args.cursor.sy;
    }
    bool need_queue = !s->mail_queued;
    s->mail_queued = true;
    pthread_mutex_unlock(&s->lock);
    if (!need_queue)
        return;
    bool queued = pipeline_transaction(s->p, "input camera/cursor", apply_mail, &s, sizeof s);
    count_refused(s, queued);
    if (!queued) {
        pthread_mutex_lock(&s->lock);
        s->mail_queued = false;
        pthread_mutex_unlock(&s->lock);
    }
}

/* Submit a record to the pipeline; a replayed one's refusal names its file and line. */
static void submit(input_sink *s, const input_txn *t, const input_record_entry *from)
{
    char origin[SINK_ORIGIN_BYTES];
    if (from && from->line && s->replay.name)
        snprintf(origin, sizeof origin, "--replay-input %s:%zu", s->replay.name, from->line);
    count_refused(s, pipeline_submit_from(s->p, t, from && from->line && s->replay.name ? origin : NULL));
}

/* Queue one transaction (live, or replayed `from` a record entry; a status
 * text is also printed). The wall's camera and the cursor go through the
 * mailbox, tour and quit are carried out here (input-level kinds), every
 * other record is submitted to the pipeline as it is. */
static void queue(input_sink *s, const input_txn *t, const input_record_entry *from)
{
    if (s->cfg.print_status && t->kind == TXN_STATUS && t->args.status.text[0]) {
        printf("status: %s\n", t->args.status.text);
        fflush(stdout);
    }
    switch (t->kind) {
    case TXN_CAMERA:
        if (t->args.camera.channel != TXN_ALL_CHANNELS) { /* one channel's (a private view's, or replayed) */
            submit(s, t, from);
            break;
        }
        queue_mail(s, t);
        break;
    case TXN_CURSOR:
        queue_mail(s, t);
        break;
    case TXN_TOUR: {
        /* logged here, when queued (no I/O at the barrier): the tour then starts or stops at
         * the next frame; tests/vm_input.sh waits for these lines */
        if (s->cfg.tour)
            log_info(t->args.flag.on ? "input: the attract tour starts" : "input: the attract tour stops (input)");
        tour_args a = {s, t->args.flag.on};
        count_refused(s, pipeline_transaction(s->p, "input tour", apply_tour, &a, sizeof a));
        break;
    }
    case TXN_QUIT:
        log_info("input: quit");
        count_refused(s, pipeline_transaction(s->p, "input quit", apply_quit, NULL, 0));
        break;
    default:
        submit(s, t, from);
        break;
    }
}

/* A record that concerns only a private channel (a remote viewer's own view):
 * not what the wall showed, so not recorded. */
static bool names_private_channel(const input_sink *s, const input_txn *t)
{
    if (t->kind == TXN_CAMERA)
        return t->args.camera.channel != TXN_ALL_CHANNELS && pipeline_channel_private(s->p, t->args.camera.channel);
    return t->kind == TXN_CHANNEL_ACTIVE && pipeline_channel_private(s->p, t->args.channel.channel);
}

void input_sink_emit(input_sink *s, const input_txn *t)
{
    atomic_fetch_add(&s->emitted, 1);
    if (s->record && !names_private_channel(s, t)) {
        pthread_mutex_lock(&s->record_lock);
        if (s->record && !input_record_write(s->record, clock_monotonic_s() - s->t0_s, t)) {
            log_error("--record-input %s: write failed; recording stopped", s->cfg.record_file);
            fclose(s->record);
            s->record = NULL;
        }
        pthread_mutex_unlock(&s->record_lock);
    }
    queue(s, t, NULL);
}

camera_desc input_sink_current_camera(input_sink *s)
{
    pthread_mutex_lock(&s->lock);
    camera_desc c = s->shown;
    pthread_mutex_unlock(&s->lock);
    return c;
}

input_sink_stats input_sink_get_stats(input_sink *s)
{
    uint64_t changes = atomic_load(&s->camera_changes), applied = atomic_load(&s->camera_applied);
    return (input_sink_stats){atomic_load(&s->emitted),     atomic_load(&s->refused), changes, applied,
                              atomic_load(&s->replayed),    atomic_load(&s->queued),
                              atomic_load(&s->tour_starts), atomic_load(&s->tour_stops)};
}

/* ---- life ------------------------------------------------------------------------------ */

input_sink *input_sink_create(pipeline *p, const input_sink_config *cfg, tess_error *err)
{
    input_sink *s = calloc(1, sizeof *s);
    if (!s) {
        tess_error_set(err, "input: out of memory");
        return NULL;
    }
    s->p = p;
    s->cfg = *cfg;
    if (s->cfg.tour_ease_s <= 0.0)
        s->cfg.tour_ease_s = 2.0;
    if (s->cfg.tour && s->cfg.tour->count == 0)
        s->cfg.tour = NULL;
    pthread_mutex_init(&s->lock, NULL);
    pthread_mutex_init(&s->record_lock, NULL);
    s->t0_s = clock_monotonic_s();
    s->shown = pipeline_camera(p, 0);
    atomic_init(&s->replay_stop, false);
    if (cfg->record_file && cfg->record_file[0]) {
        s->record = fopen(cfg->record_file, "w");
        if (!s->record || fprintf(s->record, "%s\n", INPUT_RECORD_HEADER) < 0 || fflush(s->record) != 0) {
            tess_error_set(err, "--record-input %s: cannot write: %s", cfg->record_file, strerror(errno));
            input_sink_destroy(s);
            return NULL;
        }
    }
    if (s->cfg.tour && !pipeline_add_serial_animation(p, "attract tour", tour_step, s)) {
        tess_error_set(err, "input: cannot register the tour animation");
        input_sink_destroy(s);
        return NULL;
    }
    return s;
}

void input_sink_destroy(input_sink *s)
{
    if (!s)
        return;
    atomic_store(&s->replay_stop, true);
    if (s->replay_thread_started)
        pthread_join(s->replay_thread, NULL);
    if (s->record)
        fclose(s->record);
    input_record_free(&s->replay);
    pthread_mutex_destroy(&s->lock);
    pthread_mutex_destroy(&s->record_lock);
    free(s);
}

/* ---- replay ------------------------------------------------------------------------------ */

bool input_replay_speed_from_name(const char *name, input_replay_speed *out)
{
    static const char *const names[] = {"recorded", "frames", "all"};
    for (int i = 0; i < 3; i++)
        if (strcmp(name, names[i]) == 0) {
            *out = (input_replay_speed)i;
            return true;
        }
    return false;
}

static void replay_frame(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    (void)fi;
    input_sink *s = ctx;
    if (s->replay_next < s->replay.count) {
        atomic_fetch_add(&s->replayed, 1);
        const input_record_entry *e = &s->replay.entries[s->replay_next++];
        queue(s, &e->txn, e);
    }
}

static void *replay_main(void *arg)
{
    input_sink *s = arg;
    thread_name_set("tess-replay");
    double t0_s = clock_monotonic_s();
    for (size_t i = 0; i < s->replay.count; i++) {
        for (;;) {
            if (atomic_load(&s->replay_stop) || pipeline_stop_requested(s->p))
                return NULL;
            double wait_s = s->replay.entries[i].time_s - (clock_monotonic_s() - t0_s);
            if (wait_s <= 0.0)
                break;
            if (wait_s > 0.02)
                wait_s = 0.02; /* look at the stop flags every 20 ms */
            struct timespec ts = {0, (long)(wait_s * 1e9)};
            nanosleep(&ts, NULL);
        }
        atomic_fetch_add(&s->replayed, 1);
        queue(s, &s->replay.entries[i].txn, &s->replay.entries[i]);
    }
    return NULL;
}

bool input_sink_replay(input_sink *s, const input_record *rec, input_replay_speed speed, tess_error *err)
{
    if (s->replay.entries || s->replay_thread_started)
        return tess_error_set(err, "--replay-input: only one replay per run");
    s->replay.entries = malloc((rec->count ? rec->count : 1) * sizeof *rec->entries);
    if (!s->replay.entries)
        return tess_error_set(err, "--replay-input: out of memory");
    if (rec->count)
        memcpy(s->replay.entries, rec->entries, rec->count * sizeof *rec->entries);
    s->replay.count = s->replay.capacity = rec->count;
    if (rec->name && !(s->replay.name = strdup(rec->name)))
        return tess_error_set(err, "--replay-input: out of memory");
    switch (speed) {
    case INPUT_REPLAY_ALL:
        for (size_t i = 0; i < rec->count; i++) {
            atomic_fetch_add(&s->replayed, 1);
            queue(s, &s->replay.entries[i].txn, &s->replay.entries[i]);
        }
        return true;
    case INPUT_REPLAY_FRAMES:
        if (!pipeline_add_serial_animation(s->p, "input replay", replay_frame, s))
            return tess_error_set(err, "--replay-input: cannot register the replay animation");
        return true;
    case INPUT_REPLAY_RECORDED:
        if (pthread_create(&s->replay_thread, NULL, replay_main, s) != 0)
            return tess_error_set(err, "--replay-input: cannot start the replay thread");
        s->replay_thread_started = true;
        return true;
    }
    return tess_error_set(err, "--replay-input: unknown speed");
}
