/* test_pipeline.c - the parallel pipeline: frames equal single-camera renders
 * (no torn frames), bit-identical images for any thread count and tile order,
 * transactions from several threads applied once each in per-thread order,
 * thread-count changes at run time, time modes, callbacks, limits.
 * These also run under ThreadSanitizer (make test-tsan). */
#include <criterion/criterion.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "engine/scene/accel.h"
#include "engine/frame/pipeline.h"
#include "engine/render/render.h"
#include "engine/scene/scene.h"

/* Small images: these tests are about the pipeline, not the renderer. */
#define TEST_W 72
#define TEST_H 40
#define CAPTURE_MAX 512

/* ---- a display that keeps a copy of every frame it is shown ---- */
typedef struct captured {
    frame_image meta; /* meta.rgb points at pixels below */
    float *pixels;
} captured;

typedef struct capture_display {
    image_display base;
    captured frames[CAPTURE_MAX]; /* display thread only while running */
    int count;
    int fail_at_frame;            /* -1: never fail */
    int slow_at_frame;            /* -1: never; else show sleeps SLOW_SHOW_MS at this frame */
    /* check mode (check_ref set): each frame is compared with check_ref
     * (check_w x check_h) as it is shown and not kept, so a run may show any
     * number of frames; count counts them, first_wrong is the first frame that
     * differed or came out of order (-1: none) */
    const float *check_ref;
    int check_w, check_h;
    int first_wrong;
} capture_display;

static bool same_pixels(const float *a, const float *b, int w, int h);

#define SLOW_SHOW_MS 20

static bool capture_show(image_display *d, const frame_image *img, tess_error *err)
{
    capture_display *c = (capture_display *)d;
    if (c->slow_at_frame >= 0 && img->frame == (uint64_t)c->slow_at_frame) {
        struct timespec ts = {0, SLOW_SHOW_MS * 1000000L};
        while (nanosleep(&ts, &ts) != 0)
            ;
    }
    if (c->fail_at_frame >= 0 && img->frame == (uint64_t)c->fail_at_frame)
        return tess_error_set(err, "capture display: refusing frame %d as told", c->fail_at_frame);
    if (c->check_ref) {
        bool right = img->frame == (uint64_t)c->count && img->width_px == c->check_w &&
                     img->height_px == c->check_h && same_pixels(img->rgb, c->check_ref, c->check_w, c->check_h);
        if (!right && c->first_wrong < 0)
            c->first_wrong = c->count;
        c->count++;
        return true;
    }
    cr_assert(c->count < CAPTURE_MAX, "capture display: too many frames");
    size_t floats = (size_t)img->width_px * img->height_px * 3;
    captured *f = &c->frames[c->count++];
    f->meta = *img;
    f->pixels = malloc(floats * sizeof(float));
    cr_assert(f->pixels);
    memcpy(f->pixels, img->rgb, floats * sizeof(float));
    f->meta.rgb = f->pixels;
    return true;
}

static void capture_destroy(image_display *d)
{
    capture_display *c = (capture_display *)d;
    for (int i = 0; i < c->count; i++)
        free(c->frames[i].pixels);
    free(c);
}

static const image_display_ops capture_ops = {.name = "capture", .show = capture_show, .destroy = capture_destroy};

static capture_display *capture_create(void)
{
    capture_display *c = calloc(1, sizeof *c);
    cr_assert(c);
    c->base.ops = &capture_ops;
    c->fail_at_frame = -1;
    c->slow_at_frame = -1;
    c->first_wrong = -1;
    return c;
}

/* ---- the scene every test renders ---- */
typedef struct fixture {
    scene *scene;
    accel *accel;
} fixture;

static fixture fixture_make(void)
{
    tess_error err = {{0}};
    fixture fx;
    fx.scene = scene_create_default(&err);
    cr_assert(fx.scene, "default scene: %s", err.msg);
    fx.accel = accel_build(fx.scene, 2, &err);
    cr_assert(fx.accel, "accel_build: %s", err.msg);
    return fx;
}

static void fixture_free(fixture *fx)
{
    accel_destroy(fx->accel);
    scene_destroy(fx->scene);
}

/* Camera k of a family: an orbit around the scene's camera target. */
static camera_desc test_camera(const fixture *fx, int k)
{
    camera_desc c = fx->scene->camera;
    if (!fx->scene->has_camera) {
        vec3 lo, hi;
        scene_bounds(fx->scene, &lo, &hi);
        c = camera_frame_bounds(lo, hi, CAMERA_DEFAULT_VIEW_DIR, CAMERA_DEFAULT_FOV_DEG, TEST_W, TEST_H);
    }
    float a = 0.7f * (float)k;
    vec3 r = v3_sub(c.eye, c.look_at);
    c.eye = v3_add(c.look_at, v3(cosf(a) * r.x + sinf(a) * r.z, r.y, -sinf(a) * r.x + cosf(a) * r.z));
    return c;
}

/* The reference: render_image of one camera (single sample), caller frees. */
static float *reference(const fixture *fx, const camera_desc *cam, int w, int h)
{
    float *rgb = calloc((size_t)w * h * 3, sizeof(float));
    cr_assert(rgb);
    render_view v = {fx->scene, fx->accel, camera_basis_make(cam, w, h), true, RENDER_SHADE_PHONG, NULL, NULL};
    render_image(&v, 1, rgb, NULL);
    return rgb;
}

static bool same_pixels(const float *a, const float *b, int w, int h)
{
    return memcmp(a, b, (size_t)w * h * 3 * sizeof(float)) == 0;
}

static pipeline *make_pipeline(const fixture *fx, pipeline_config cfg, capture_display **cap, const camera_desc *cam)
{
    tess_error err = {{0}};
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p, "pipeline_create: %s", err.msg);
    *cap = capture_create();
    cr_assert(pipeline_add_channel(p, cam, TEST_W, TEST_H, &(*cap)->base, &err) == 0, "add_channel: %s", err.msg);
    (void)fx;
    return p;
}

static void run_ok(pipeline *p)
{
    tess_error err = {{0}};
    cr_assert(pipeline_run(p, &err), "pipeline_run: %s", err.msg);
}

Test(pipeline, frames_equal_single_camera_renders_and_none_is_lost)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    cfg.max_frames = 5;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    run_ok(p);
    float *ref = reference(&fx, &cam, TEST_W, TEST_H);
    cr_assert_eq(cap->count, 5, "displayed %d frames, expected 5", cap->count);
    for (int i = 0; i < cap->count; i++) {
        cr_assert_eq(cap->frames[i].meta.frame, (uint64_t)i, "frame %d displayed as number %llu", i,
                     (unsigned long long)cap->frames[i].meta.frame);
        cr_assert(same_pixels(cap->frames[i].pixels, ref, TEST_W, TEST_H), "frame %d differs from render_image", i);
    }
    pipeline_stats st = pipeline_get_stats(p);
    cr_assert_eq(st.frames_rendered, 5);
    cr_assert_eq(st.frames_displayed, 5);
    cr_assert_eq(st.rays.primary_rays, 5ull * TEST_W * TEST_H);
    free(ref);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* Every combination of thread count and tile order gives the same bits. */
Test(pipeline, bit_identical_for_thread_counts_tile_orders_and_sizes, .timeout = 120)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 1);
    const int thread_counts[] = {1, 2, 3, 7};
    const int tile_sizes[] = {16, 5};
    const pixel_sampler samplers[] = {pixel_sampler_single(), pixel_sampler_jittered(2, 7)};
    for (size_t si = 0; si < sizeof samplers / sizeof samplers[0]; si++) {
        float *first = NULL;
        for (size_t ti = 0; ti < sizeof thread_counts / sizeof thread_counts[0]; ti++)
            for (int order = 0; order < TILE_ORDER_COUNT; order++)
                for (size_t zi = 0; zi < sizeof tile_sizes / sizeof tile_sizes[0]; zi++) {
                    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
                    cfg.threads = thread_counts[ti];
                    cfg.order = (tile_order)order;
                    cfg.order_seed = 99;
                    cfg.tile_px = tile_sizes[zi];
                    cfg.sampler = samplers[si];
                    cfg.max_frames = 1;
                    capture_display *cap;
                    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
                    run_ok(p);
                    cr_assert_eq(cap->count, 1);
                    if (!first) {
                        first = malloc((size_t)TEST_W * TEST_H * 3 * sizeof(float));
                        memcpy(first, cap->frames[0].pixels, (size_t)TEST_W * TEST_H * 3 * sizeof(float));
                    } else {
                        cr_assert(same_pixels(first, cap->frames[0].pixels, TEST_W, TEST_H),
                                  "sampler %zu: %d threads, order %s, tile %d px differs from 1 thread rows",
                                  si, thread_counts[ti], tile_order_name((tile_order)order), tile_sizes[zi]);
                    }
                    pipeline_destroy(p);
                }
        if (si == 0) { /* single sampling equals render_image too */
            float *ref = reference(&fx, &cam, TEST_W, TEST_H);
            cr_assert(same_pixels(first, ref, TEST_W, TEST_H));
            free(ref);
        }
        free(first);
    }
    fixture_free(&fx);
}

/* ---- no torn frames ---- */
#define TORN_CAMERAS 5

typedef struct camera_sender {
    pipeline *p;
    camera_desc cams[TORN_CAMERAS];
    atomic_bool done;
    atomic_ulong sent;
} camera_sender;

static void *send_cameras(void *arg)
{
    camera_sender *s = arg;
    for (unsigned long k = 0; !atomic_load(&s->done); k++) {
        tess_error err = {{0}};
        if (pipeline_queue_camera(s->p, 0, &s->cams[k % TORN_CAMERAS], &err))
            atomic_fetch_add(&s->sent, 1);
        else
            sched_yield(); /* queue full: let frames drain it */
    }
    return NULL;
}

Test(pipeline, no_torn_frames_while_cameras_change_as_fast_as_possible, .timeout = 120)
{
    fixture fx = fixture_make();
    camera_sender s;
    for (int k = 0; k < TORN_CAMERAS; k++)
        s.cams[k] = test_camera(&fx, k);
    atomic_init(&s.done, false);
    atomic_init(&s.sent, 0);
    float *refs[TORN_CAMERAS];
    for (int k = 0; k < TORN_CAMERAS; k++)
        refs[k] = reference(&fx, &s.cams[k], TEST_W, TEST_H);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.tile_px = 8;
    cfg.max_frames = 60;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &s.cams[0]);
    s.p = p;
    pthread_t sender;
    cr_assert_eq(pthread_create(&sender, NULL, send_cameras, &s), 0);
    run_ok(p);
    atomic_store(&s.done, true);
    pthread_join(sender, NULL);
    cr_assert_eq(cap->count, 60);
    int seen[TORN_CAMERAS] = {0};
    for (int i = 0; i < cap->count; i++) {
        int match = -1;
        for (int k = 0; k < TORN_CAMERAS && match < 0; k++)
            if (same_pixels(cap->frames[i].pixels, refs[k], TEST_W, TEST_H))
                match = k;
        cr_assert(match >= 0, "frame %d is not the image of any one camera (torn)", i);
        /* and the frame's record names that camera */
        cr_assert(!memcmp(&cap->frames[i].meta.camera, &s.cams[match], sizeof(camera_desc)),
                  "frame %d: pixels of camera %d but metadata of another", i, match);
        seen[match]++;
    }
    int distinct = 0;
    for (int k = 0; k < TORN_CAMERAS; k++)
        distinct += seen[k] > 0;
    cr_assert(distinct >= 2, "only %d distinct cameras seen: the test did not exercise changes", distinct);
    cr_assert(atomic_load(&s.sent) > 60, "sender managed only %lu transactions", atomic_load(&s.sent));
    for (int k = 0; k < TORN_CAMERAS; k++)
        free(refs[k]);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- transactions from several threads ---- */
#define PRODUCERS 4
#define PER_PRODUCER 3000

typedef struct txn_log {
    pipeline *p;
    int applied[PRODUCERS * PER_PRODUCER][2]; /* (producer, seq) in applied order; serial section only */
    int count;
} txn_log;

typedef struct txn_args {
    txn_log *log;
    int producer, seq;
} txn_args;

static void record_txn(pipeline *p, void *args)
{
    txn_args *a = args;
    cr_assert(pipeline_in_serial_section(p));
    a->log->applied[a->log->count][0] = a->producer;
    a->log->applied[a->log->count][1] = a->seq;
    if (++a->log->count == PRODUCERS * PER_PRODUCER)
        pipeline_stop(p);
}

typedef struct producer_arg {
    txn_log *log;
    int producer;
} producer_arg;

static void *produce(void *arg)
{
    producer_arg *pa = arg;
    for (int seq = 0; seq < PER_PRODUCER;) {
        txn_args a = {pa->log, pa->producer, seq};
        if (pipeline_transaction(pa->log->p, "test", record_txn, &a, sizeof a))
            seq++;
        else
            sched_yield();
    }
    return NULL;
}

Test(pipeline, transactions_from_several_threads_apply_once_in_per_thread_order, .timeout = 120)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    txn_log *log = calloc(1, sizeof *log);
    log->p = p;
    producer_arg args[PRODUCERS];
    pthread_t th[PRODUCERS];
    for (int i = 0; i < PRODUCERS; i++) {
        args[i] = (producer_arg){log, i};
        cr_assert_eq(pthread_create(&th[i], NULL, produce, &args[i]), 0);
    }
    run_ok(p);
    for (int i = 0; i < PRODUCERS; i++)
        pthread_join(th[i], NULL);
    cr_assert_eq(log->count, PRODUCERS * PER_PRODUCER);
    int next[PRODUCERS] = {0};
    for (int i = 0; i < log->count; i++) {
        int who = log->applied[i][0], seq = log->applied[i][1];
        cr_assert_eq(seq, next[who], "producer %d: transaction %d applied where %d was due", who, seq, next[who]);
        next[who]++;
    }
    for (int i = 0; i < PRODUCERS; i++)
        cr_assert_eq(next[i], PER_PRODUCER);
    pipeline_stats st = pipeline_get_stats(p);
    cr_assert_eq(st.transactions_applied, (uint64_t)PRODUCERS * PER_PRODUCER);
    free(log);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- thread-count changes while rendering ---- */
typedef struct thread_plan {
    int threads_seen[64]; /* frame_info.threads per frame, from a serial callback */
    int frames;
} thread_plan;

static void set_threads_now(pipeline *p, void *args)
{
    int n;
    memcpy(&n, args, sizeof n);
    cr_assert(pipeline_set_threads(p, n));
}

static void note_threads(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    thread_plan *tp = ctx;
    if (fi->frame < 64)
        tp->threads_seen[fi->frame] = fi->threads;
    tp->frames++;
}

typedef struct racer {
    pipeline *p;
    atomic_bool done;
} racer;

/* Thread-count changes from another thread while frames render, each sent
 * once the count of applied changes has moved since the one before was sent
 * (an event, whatever the machine's speed: a starved sender makes the run
 * longer, never the test wrong), a new count every time (each differs from
 * the one before, the first from the pipeline's 2, so none is a no-op);
 * once RACE_CHANGES are applied it stops the pipeline. (The pipeline's own
 * start, 1 -> 2 threads at frame 0, counts as a change too.) */
#define RACE_CHANGES 12
static void *race_thread_counts(void *arg)
{
    racer *r = arg;
    static const int counts[] = {3, 1, 5, 2, 6, 1, 4, 2};
    struct timespec poll = {0, 200000};
    bool pending = false;
    uint64_t applied_at_send = 0;
    for (int sent = 0; !atomic_load(&r->done);) {
        uint64_t applied = pipeline_get_stats(r->p).thread_changes;
        if (applied >= RACE_CHANGES) {
            pipeline_stop(r->p);
            break;
        }
        if (pending && applied > applied_at_send)
            pending = false;
        if (!pending && pipeline_queue_threads(r->p, counts[sent % 8])) {
            sent++;
            pending = true;
            applied_at_send = applied;
        }
        nanosleep(&poll, NULL);
    }
    return NULL;
}

Test(pipeline, thread_count_changes_lose_no_frame_and_never_deadlock, .timeout = 120)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 2);
    float *ref = reference(&fx, &cam, TEST_W, TEST_H);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    cfg.tile_px = 8;
    cfg.max_frames = 40;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    thread_plan tp = {{0}, 0};
    cr_assert(pipeline_add_serial_animation(p, "note threads", note_threads, &tp));
    /* a fixed plan for the first frames ... */
    const int plan_frame[] = {2, 4, 6, 8, 10, 12};
    const int plan_threads[] = {3, 1, 7, 2, 5, 1};
    for (int i = 0; i < 6; i++)
        cr_assert(pipeline_at_frame(p, (uint64_t)plan_frame[i], "set threads", set_threads_now, &plan_threads[i],
                                    sizeof(int)));
    run_ok(p);
    cr_assert_eq(cap->count, 40, "%d frames displayed of 40", cap->count);
    for (int i = 0; i < cap->count; i++) {
        cr_assert_eq(cap->frames[i].meta.frame, (uint64_t)i);
        cr_assert(same_pixels(cap->frames[i].pixels, ref, TEST_W, TEST_H), "frame %d wrong", i);
    }
    /* the serial section sees the count of the frame before the change is applied */
    for (int i = 0; i < 6; i++)
        cr_assert_eq(tp.threads_seen[plan_frame[i] + 1], plan_threads[i], "frame %d ran with %d threads, not %d",
                     plan_frame[i] + 1, tp.threads_seen[plan_frame[i] + 1], plan_threads[i]);
    pipeline_destroy(p);

    /* ... then changes from another thread while frames render, until it
     * has seen RACE_CHANGES applied and stops the run */
    cfg.max_frames = 0;
    p = make_pipeline(&fx, cfg, &cap, &cam);
    cap->check_ref = ref;
    cap->check_w = TEST_W;
    cap->check_h = TEST_H;
    racer r = {p, false};
    atomic_init(&r.done, false);
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, race_thread_counts, &r), 0);
    run_ok(p);
    atomic_store(&r.done, true);
    pthread_join(th, NULL);
    pipeline_stats st = pipeline_get_stats(p);
    cr_assert(st.thread_changes >= RACE_CHANGES, "%llu thread changes applied", (unsigned long long)st.thread_changes);
    cr_assert(cap->count >= RACE_CHANGES, "%d frames for %d changes", cap->count, RACE_CHANGES);
    cr_assert_eq(cap->first_wrong, -1, "frame %d wrong or out of order (of %d)", cap->first_wrong, cap->count);
    free(ref);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- time modes, one-shots, animation callbacks ---- */
typedef struct time_log {
    double time_s[64];
    int threads[64];
    int frames;
    int oneshot_frame[4];
} time_log;

static void note_time(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    time_log *tl = ctx;
    if (tl->frames < 64)
        tl->time_s[tl->frames] = fi->time_s;
    tl->frames++;
}

Test(pipeline, fixed_rate_time_is_frame_over_rate_and_real_time_advances)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    cfg.rate_hz = 24.0;
    cfg.max_frames = 10;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    time_log tl;
    memset(&tl, 0, sizeof tl);
    cr_assert(pipeline_add_serial_animation(p, "time", note_time, &tl));
    run_ok(p);
    for (int i = 0; i < 10; i++) {
        cr_assert_eq(tl.time_s[i], (double)i / 24.0, "frame %d time %.17g", i, tl.time_s[i]);
        cr_assert_eq(cap->frames[i].meta.time_s, (double)i / 24.0);
    }
    pipeline_destroy(p);

    cfg.time_mode = PIPELINE_TIME_REAL;
    p = make_pipeline(&fx, cfg, &cap, &cam);
    memset(&tl, 0, sizeof tl);
    cr_assert(pipeline_add_serial_animation(p, "time", note_time, &tl));
    run_ok(p);
    cr_assert_eq(tl.time_s[0], 0.0);
    for (int i = 1; i < 10; i++)
        cr_assert(tl.time_s[i] > tl.time_s[i - 1], "real time did not advance at frame %d", i);
    pipeline_destroy(p);
    fixture_free(&fx);
}

typedef struct oneshot_args {
    time_log *tl;
    int slot;
} oneshot_args;

static uint64_t current_frame; /* written by a serial callback, read by one-shots (both serial) */

static void track_frame(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    (void)ctx;
    current_frame = fi->frame;
}

static void oneshot_note(pipeline *p, void *args)
{
    (void)p;
    oneshot_args *a = args;
    /* one-shots run before serial animation: the tracker still shows the frame before */
    a->tl->oneshot_frame[a->slot] = (int)(current_frame + 1);
}

static void register_late(pipeline *p, void *args)
{
    oneshot_args a = *(oneshot_args *)args;
    /* frame 1 is long gone by now: runs at the next barrier */
    cr_assert(pipeline_at_frame(p, 1, "late", oneshot_note, &a, sizeof a));
}

Test(pipeline, one_shot_callbacks_run_once_at_their_frame)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    cfg.max_frames = 12;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    time_log tl;
    memset(&tl, 0, sizeof tl);
    for (int i = 0; i < 4; i++)
        tl.oneshot_frame[i] = -1;
    current_frame = (uint64_t)-1;
    cr_assert(pipeline_add_serial_animation(p, "track", track_frame, NULL));
    oneshot_args a0 = {&tl, 0}, a1 = {&tl, 1}, a2 = {&tl, 2};
    cr_assert(pipeline_at_frame(p, 7, "seven", oneshot_note, &a1, sizeof a1));
    cr_assert(pipeline_at_frame(p, 0, "zero", oneshot_note, &a0, sizeof a0));
    cr_assert(pipeline_at_frame(p, 5, "register late", register_late, &a2, sizeof a2));
    run_ok(p);
    cr_assert_eq(tl.oneshot_frame[0], 0);
    cr_assert_eq(tl.oneshot_frame[1], 7);
    cr_assert_eq(tl.oneshot_frame[2], 6, "late one-shot ran at %d", tl.oneshot_frame[2]);
    pipeline_destroy(p);
    fixture_free(&fx);
}

typedef struct parallel_log {
    atomic_int calls[32];           /* per frame */
    atomic_ullong thread_bits[32];  /* per frame: which thread ids called */
    int threads[32];
} parallel_log;

static void parallel_note(pipeline *p, void *ctx, const frame_info *fi, int thread, int threads)
{
    (void)p;
    parallel_log *pl = ctx;
    if (fi->frame >= 32)
        return;
    atomic_fetch_add(&pl->calls[fi->frame], 1);
    atomic_fetch_or(&pl->thread_bits[fi->frame], 1ull << thread);
    if (thread == 0)
        pl->threads[fi->frame] = threads;
}

Test(pipeline, parallel_animation_runs_once_per_thread_per_frame)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.max_frames = 8;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    parallel_log *pl = calloc(1, sizeof *pl);
    cr_assert(pipeline_add_parallel_animation(p, "note", parallel_note, pl));
    int four = 4;
    cr_assert(pipeline_at_frame(p, 4, "four threads", set_threads_now, &four, sizeof four));
    run_ok(p);
    for (int f = 0; f < 8; f++) {
        int want = f < 4 ? 3 : 4;
        cr_assert_eq(atomic_load(&pl->calls[f]), want, "frame %d: %d calls", f, atomic_load(&pl->calls[f]));
        cr_assert_eq(atomic_load(&pl->thread_bits[f]), (1ull << want) - 1);
        cr_assert_eq(pl->threads[f], want);
    }
    cr_assert_eq(cap->count, 8);
    free(pl);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- channels ---- */
Test(pipeline, channels_render_their_own_camera_and_size_to_their_own_display)
{
    fixture fx = fixture_make();
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.max_frames = 3;
    cfg.order = TILE_ORDER_HILBERT;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    const int sizes[3][2] = {{TEST_W, TEST_H}, {33, 57}, {100, 20}};
    capture_display *caps[3];
    camera_desc cams[3];
    for (int c = 0; c < 3; c++) {
        cams[c] = test_camera(&fx, 3 + c);
        caps[c] = capture_create();
        cr_assert_eq(pipeline_add_channel(p, &cams[c], sizes[c][0], sizes[c][1], &caps[c]->base, &err), c, "%s",
                     err.msg);
    }
    cr_assert_eq(pipeline_channel_count(p), 3);
    run_ok(p);
    for (int c = 0; c < 3; c++) {
        float *ref = reference(&fx, &cams[c], sizes[c][0], sizes[c][1]);
        cr_assert_eq(caps[c]->count, 3);
        for (int i = 0; i < 3; i++) {
            cr_assert_eq(caps[c]->frames[i].meta.channel, c);
            cr_assert_eq(caps[c]->frames[i].meta.width_px, sizes[c][0]);
            cr_assert(same_pixels(caps[c]->frames[i].pixels, ref, sizes[c][0], sizes[c][1]), "channel %d frame %d",
                      c, i);
        }
        free(ref);
    }
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- channels switched off and on (a wall output unplugged and back) ---- */
typedef struct stage_counting_display {
    capture_display cap; /* first: frames shown */
    int stages;          /* end_stage calls */
} stage_counting_display;

static bool count_stage(image_display *d, tess_error *err)
{
    (void)err;
    ((stage_counting_display *)d)->stages++;
    return true;
}

static const image_display_ops stage_counting_ops = {
    .name = "stage-counting", .show = capture_show, .destroy = capture_destroy, .end_stage = count_stage};

static void switch_channel_1(pipeline *p, void *args)
{
    bool on;
    memcpy(&on, args, sizeof on);
    cr_assert(pipeline_set_channel_active(p, 1, on));
}

Test(pipeline, a_switched_off_channel_is_neither_rendered_nor_shown_and_comes_back, .timeout = 60)
{
    fixture fx = fixture_make();
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.max_frames = 12;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    stage_counting_display *disp[2];
    camera_desc cams[2] = {test_camera(&fx, 1), test_camera(&fx, 2)};
    for (int c = 0; c < 2; c++) {
        disp[c] = calloc(1, sizeof *disp[c]);
        cr_assert(disp[c]);
        disp[c]->cap.base.ops = &stage_counting_ops;
        disp[c]->cap.fail_at_frame = -1;
        cr_assert_eq(pipeline_add_channel(p, &cams[c], TEST_W, TEST_H, &disp[c]->cap.base, &err), c, "%s", err.msg);
    }
    bool off = false, on = true;
    cr_assert(pipeline_at_frame(p, 3, "unplug", switch_channel_1, &off, sizeof off));
    cr_assert(pipeline_at_frame(p, 7, "plug", switch_channel_1, &on, sizeof on));
    cr_assert(pipeline_channel_active(p, 1));
    run_ok(p);
    cr_assert(pipeline_channel_active(p, 1));
    /* channel 0 never stopped; channel 1 missed frames 3..6 exactly */
    cr_assert_eq(disp[0]->cap.count, 12);
    const uint64_t expected[] = {0, 1, 2, 7, 8, 9, 10, 11};
    cr_assert_eq(disp[1]->cap.count, 8);
    float *ref = reference(&fx, &cams[1], TEST_W, TEST_H);
    for (int i = 0; i < 8; i++) {
        cr_expect_eq(disp[1]->cap.frames[i].meta.frame, expected[i], "shown frame %d is %llu", i,
                     (unsigned long long)disp[1]->cap.frames[i].meta.frame);
        cr_expect(same_pixels(disp[1]->cap.frames[i].pixels, ref, TEST_W, TEST_H), "frame %llu",
                  (unsigned long long)expected[i]);
    }
    free(ref);
    /* with an end_stage hook a display stage runs every loop step, frames or not:
     * steps 0..11 (frames 0..11 render; step 0 has nothing to show yet) and the
     * last one (frame 11 shown); every display's end_stage in each */
    cr_expect_eq(disp[0]->stages, 13);
    cr_expect_eq(disp[1]->stages, 13);
    pipeline_stats st = pipeline_get_stats(p);
    cr_expect_eq(st.frames_displayed, 12);
    pipeline_destroy(p);
    fixture_free(&fx);
}

static void switch_channel_0(pipeline *p, void *args)
{
    bool on;
    memcpy(&on, args, sizeof on);
    cr_assert(pipeline_set_channel_active(p, 0, on));
}

Test(pipeline, with_every_channel_off_end_stage_is_still_served_every_step, .timeout = 60)
{
    fixture fx = fixture_make();
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    cfg.max_frames = 10;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    stage_counting_display *disp = calloc(1, sizeof *disp);
    cr_assert(disp);
    disp->cap.base.ops = &stage_counting_ops;
    disp->cap.fail_at_frame = -1;
    camera_desc cam = test_camera(&fx, 5);
    cr_assert_eq(pipeline_add_channel(p, &cam, TEST_W, TEST_H, &disp->cap.base, &err), 0, "%s", err.msg);
    bool off = false, on = true;
    cr_assert(pipeline_at_frame(p, 2, "unplug", switch_channel_0, &off, sizeof off));
    cr_assert(pipeline_at_frame(p, 6, "plug", switch_channel_0, &on, sizeof on));
    run_ok(p);
    const uint64_t shown[] = {0, 1, 6, 7, 8, 9};
    cr_assert_eq(disp->cap.count, 6);
    for (int i = 0; i < 6; i++)
        cr_expect_eq(disp->cap.frames[i].meta.frame, shown[i]);
    cr_expect_eq(disp->stages, 11, "steps 0..9 and the last: %d", disp->stages);
    pipeline_stats st = pipeline_get_stats(p);
    cr_expect_eq(st.frames_displayed, 6, "stages without a frame are not frames displayed");
    cr_expect_eq(st.frames_rendered, 10);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- the write_tile hook: what a scan-out display gets from the render threads ---- */
#define TILE_RING 4 /* as the DRM display: frame f in slot f % 4 */
typedef struct tile_display {
    image_display base;
    float *slots[TILE_RING];           /* copies of the tiles, TEST_W x TEST_H each */
    atomic_int *written[TILE_RING];    /* per pixel: times a tile covered it */
    int frames_checked;                /* display thread */
    int bad_frames;                    /* display thread */
} tile_display;

static void tile_write(image_display *d, const frame_image *img, int x0, int y0, int x1, int y1)
{
    tile_display *t = (tile_display *)d;
    int slot = (int)(img->frame % TILE_RING);
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            size_t i = (size_t)y * img->width_px + x;
            memcpy(&t->slots[slot][3 * i], &img->rgb[3 * i], 3 * sizeof(float));
            atomic_fetch_add_explicit(&t->written[slot][i], 1, memory_order_relaxed);
        }
}

static bool tile_show(image_display *d, const frame_image *img, tess_error *err)
{
    (void)err;
    tile_display *t = (tile_display *)d;
    int slot = (int)(img->frame % TILE_RING);
    bool good = same_pixels(t->slots[slot], img->rgb, img->width_px, img->height_px);
    for (int i = 0; i < img->width_px * img->height_px; i++) {
        good = good && atomic_load(&t->written[slot][i]) == 1;
        atomic_store(&t->written[slot][i], 0);
    }
    t->frames_checked++;
    t->bad_frames += !good;
    return true;
}

static void tile_destroy(image_display *d)
{
    tile_display *t = (tile_display *)d;
    for (int k = 0; k < TILE_RING; k++) {
        free(t->slots[k]);
        free(t->written[k]);
    }
    free(t);
}

static const image_display_ops tile_ops = {
    .name = "tiles", .show = tile_show, .destroy = tile_destroy, .write_tile = tile_write};

Test(pipeline, write_tile_gets_every_pixel_of_every_frame_once_before_show, .timeout = 60)
{
    fixture fx = fixture_make();
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.max_frames = 10;
    cfg.tile_px = 8; /* TEST_W 72 x TEST_H 40: 9 x 5 tiles */
    cfg.order = TILE_ORDER_SHUFFLE;
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    tile_display *t = calloc(1, sizeof *t);
    cr_assert(t);
    t->base.ops = &tile_ops;
    for (int k = 0; k < TILE_RING; k++) {
        t->slots[k] = calloc((size_t)TEST_W * TEST_H * 3, sizeof(float));
        t->written[k] = calloc((size_t)TEST_W * TEST_H, sizeof(atomic_int));
        cr_assert(t->slots[k] && t->written[k]);
    }
    camera_desc cam = test_camera(&fx, 4);
    cr_assert_eq(pipeline_add_channel(p, &cam, TEST_W, TEST_H, &t->base, &err), 0, "%s", err.msg);
    run_ok(p);
    cr_expect_eq(t->frames_checked, 10);
    cr_expect_eq(t->bad_frames, 0, "%d of 10 frames had pixels written twice, never or differently", t->bad_frames);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- stopping, termination, failures, limits ---- */
static void count_termination(pipeline *p, void *ctx)
{
    (void)p;
    ++*(int *)ctx;
}

typedef struct stopper {
    pipeline *p;
    capture_display *cap;
} stopper;

static void *stop_soon(void *arg)
{
    stopper *s = arg;
    struct timespec ts = {0, 1000000};
    while (pipeline_get_stats(s->p).frames_rendered < 2) /* stop while frames are flowing */
        nanosleep(&ts, NULL);
    pipeline_stop(s->p);
    return NULL;
}

Test(pipeline, stop_from_another_thread_displays_the_last_frame_and_runs_termination, .timeout = 60)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    int terminations = 0;
    cr_assert(pipeline_add_termination(p, "count", count_termination, &terminations));
    stopper s = {p, cap};
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, stop_soon, &s), 0);
    run_ok(p);
    pthread_join(th, NULL);
    pipeline_stats st = pipeline_get_stats(p);
    cr_assert_eq(terminations, 1);
    cr_assert(st.frames_rendered >= 2);
    cr_assert_eq(st.frames_displayed, st.frames_rendered, "rendered %llu, displayed %llu",
                 (unsigned long long)st.frames_rendered, (unsigned long long)st.frames_displayed);
    cr_assert_eq((uint64_t)cap->count, st.frames_displayed);
    /* stopped: transactions are refused */
    cr_assert_not(pipeline_queue_threads(p, 2));
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- the stop: every transaction applied, refused or discarded, each counted ---- */
#define STOP_BACKLOG 7 /* queued in the last serial section, just before the stop */

typedef struct stop_books {
    pipeline *p;
    atomic_uint_fast64_t applied;           /* count_applied ran */
    atomic_uint_fast64_t accepted, refused; /* pipeline_transaction's answers, every thread */
    int backlog_accepted;                   /* of the backlog (serial section only) */
    bool refused_after_stop;                /* (serial section only) */
    atomic_bool run_returned;
} stop_books;

static void count_applied(pipeline *p, void *args)
{
    (void)p;
    stop_books *b = *(stop_books **)args;
    atomic_fetch_add(&b->applied, 1);
}

static bool book(stop_books *b)
{
    bool ok = pipeline_transaction(b->p, "counted", count_applied, &b, sizeof b);
    atomic_fetch_add(ok ? &b->accepted : &b->refused, 1);
    return ok;
}

/* Frame 5's serial section: a backlog, then the stop, then one more (refused). */
static void backlog_then_stop(pipeline *p, void *ctx, const frame_info *fi)
{
    stop_books *b = ctx;
    if (fi->frame != 5)
        return;
    for (int i = 0; i < STOP_BACKLOG; i++)
        b->backlog_accepted += book(b);
    pipeline_stop(p);
    b->refused_after_stop = !book(b);
}

static void *flood_until_closed(void *arg)
{
    stop_books *b = arg;
    while (!atomic_load(&b->run_returned)) {
        book(b);
        struct timespec ts = {0, 20000}; /* 20 us: busy, but far from filling the queue in a frame */
        nanosleep(&ts, NULL);
    }
    book(b); /* after run: refused */
    return NULL;
}

/* Before: transactions accepted after the last barrier that ran any were
 * dropped at the stop without a trace (the soak's reconciliation found it). */
Test(pipeline, at_the_stop_every_transaction_is_applied_refused_or_counted_as_discarded, .timeout = 60)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    stop_books *b = calloc(1, sizeof *b);
    cr_assert(b);
    b->p = p;
    cr_assert(pipeline_add_serial_animation(p, "backlog, stop", backlog_then_stop, b));
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, flood_until_closed, b), 0);
    run_ok(p);
    atomic_store(&b->run_returned, true);
    pthread_join(th, NULL);
    pipeline_stats st = pipeline_get_stats(p);
    uint64_t accepted = atomic_load(&b->accepted), refused = atomic_load(&b->refused);
    uint64_t applied = atomic_load(&b->applied);
    cr_assert_eq(accepted, applied + st.transactions_discarded,
                 "%llu accepted, %llu applied + %llu discarded", (unsigned long long)accepted,
                 (unsigned long long)applied, (unsigned long long)st.transactions_discarded);
    cr_assert_eq(st.transactions_applied, applied);
    cr_assert_eq(b->backlog_accepted, STOP_BACKLOG);
    cr_assert(b->refused_after_stop, "a transaction queued after the stop was accepted");
    cr_assert(st.transactions_discarded >= STOP_BACKLOG, "the backlog queued before the stop: %llu discarded",
              (unsigned long long)st.transactions_discarded);
    cr_assert_eq(refused, st.transactions_rejected);
    cr_assert_eq(st.transactions_rejected, st.rejected_queue_full + st.rejected_stopped);
    cr_assert(st.rejected_stopped >= 2, "refused after the stop and after run: %llu",
              (unsigned long long)st.rejected_stopped);
    free(b);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- no I/O at the barrier: what the serial section logs is written after it ---- */
typedef struct barrier_log_probe {
    int fd;                          /* stderr's file */
    off_t size_before, size_after;   /* around a refused setter, in the serial section */
    bool ran;
} barrier_log_probe;

static off_t file_size(int fd)
{
    struct stat st;
    cr_assert_eq(fstat(fd, &st), 0);
    return st.st_size;
}

static void log_at_the_barrier(pipeline *p, void *args)
{
    barrier_log_probe *b = *(barrier_log_probe **)args;
    camera_desc bad = {{1, 2, 3}, {1, 2, 3}, {0, 1, 0}, 40.f}; /* eye == look_at */
    b->size_before = file_size(b->fd);
    cr_assert_not(pipeline_set_camera(p, 0, &bad)); /* logs why */
    b->size_after = file_size(b->fd);
    b->ran = true;
}

/* The soak saw frames stall for up to 1.4 s while a transaction's error line
 * waited for a busy disk: the serial section's log lines are now kept and
 * written by thread 0 after the barrier. */
Test(pipeline, what_the_serial_section_logs_is_written_after_the_barrier, .timeout = 60)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    cfg.max_frames = 3;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    char path[] = "/tmp/tessera-barrier-log-XXXXXX";
    int fd = mkstemp(path);
    cr_assert(fd >= 0);
    fflush(stderr);
    int saved = dup(2);
    cr_assert(saved >= 0 && dup2(fd, 2) == 2);
    barrier_log_probe probe = {.fd = fd};
    barrier_log_probe *pp = &probe;
    cr_assert(pipeline_transaction(p, "log", log_at_the_barrier, &pp, sizeof pp));
    tess_error err = {{0}};
    bool ran = pipeline_run(p, &err);
    fflush(stderr);
    dup2(saved, 2);
    close(saved);
    cr_assert(ran, "%s", err.msg);
    cr_assert(probe.ran);
    cr_assert_eq(probe.size_after, probe.size_before, "%lld bytes written to stderr at the barrier",
                 (long long)(probe.size_after - probe.size_before));
    char text[4096] = "";
    ssize_t n = pread(fd, text, sizeof text - 1, 0);
    cr_assert(n > 0);
    text[n] = '\0';
    cr_assert(strstr(text, "eye and look_at are the same point"), "the line was never written: '%s'", text);
    close(fd);
    unlink(path);
    pipeline_destroy(p);
    fixture_free(&fx);
}

Test(pipeline, a_failing_display_stops_the_pipeline_with_its_error, .timeout = 60)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 3;
    cfg.max_frames = 20;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    cap->fail_at_frame = 3;
    tess_error err = {{0}};
    cr_assert_not(pipeline_run(p, &err));
    cr_assert(strstr(err.msg, "refusing frame 3"), "error: %s", err.msg);
    cr_assert_eq(cap->count, 3);
    pipeline_destroy(p);
    fixture_free(&fx);
}

/* ---- each step's time: its render stage and the rest ---- */
#define SPLIT_FRAMES 12
#define SLOW_SERIAL_FRAME 7
typedef struct step_split {
    double frame_s[SPLIT_FRAMES], render_s[SPLIT_FRAMES];
} step_split;

static void note_split(pipeline *p, void *ctx, const frame_info *fi)
{
    (void)p;
    step_split *sp = ctx;
    if (fi->frame < SPLIT_FRAMES) {
        sp->frame_s[fi->frame] = fi->last_frame_s;
        sp->render_s[fi->frame] = fi->last_render_s;
    }
    if (fi->frame == SLOW_SERIAL_FRAME) { /* a serial section held up: in the next step's time */
        struct timespec ts = {0, SLOW_SHOW_MS * 1000000L};
        while (nanosleep(&ts, &ts) != 0)
            ;
    }
}

/* One render thread, so a step is its display stage, its render stage and
 * the serial section in a row: what a slow display or a slow serial section
 * costs is outside rendering, whatever the machine's speed (soak.sh judges
 * frame gaps on this: a view that costs more to render is not a stall). */
Test(pipeline, a_step_s_time_splits_into_its_render_stage_and_the_rest, .timeout = 60)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 1;
    cfg.max_frames = SPLIT_FRAMES;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    cap->slow_at_frame = 3;
    step_split sp;
    memset(&sp, 0, sizeof sp);
    cr_assert(pipeline_add_serial_animation(p, "split", note_split, &sp));
    run_ok(p);
    cr_assert_eq(sp.frame_s[0], 0.0);
    cr_assert_eq(sp.render_s[0], 0.0);
    double limit_s = 1e-3 * SLOW_SHOW_MS;
    int held_up = 0;
    for (int f = 1; f < SPLIT_FRAMES; f++) {
        cr_assert(sp.render_s[f] > 0.0, "frame %d: no render stage time", f);
        cr_assert(sp.render_s[f] <= sp.frame_s[f], "frame %d: render stage %.6f s > step %.6f s", f, sp.render_s[f],
                  sp.frame_s[f]);
        if (sp.frame_s[f] - sp.render_s[f] >= limit_s)
            held_up++;
    }
    /* the step that showed frame 3, and the one after the slow serial section at frame 7 */
    cr_assert(sp.frame_s[SLOW_SERIAL_FRAME + 1] - sp.render_s[SLOW_SERIAL_FRAME + 1] >= limit_s,
              "the slow serial section is not outside rendering: step %.6f s, render %.6f s",
              sp.frame_s[SLOW_SERIAL_FRAME + 1], sp.render_s[SLOW_SERIAL_FRAME + 1]);
    cr_assert(held_up >= 2, "%d step(s) held up %d ms outside rendering, want the slow show's and the serial's",
              held_up, SLOW_SHOW_MS);
    pipeline_destroy(p);
    fixture_free(&fx);
}

typedef struct misuse_log {
    bool run_refused, setter_outside_refused, big_args_refused;
    pipeline *p;
} misuse_log;

static void try_run_inside(pipeline *p, void *args)
{
    misuse_log *m = *(misuse_log **)args;
    tess_error err = {{0}};
    m->run_refused = !pipeline_run(p, &err) && strstr(err.msg, "inside") != NULL;
}

static void slow_transaction(pipeline *p, void *args)
{
    (void)p;
    (void)args;
    struct timespec ts = {0, 5000000}; /* 5 ms: over the 2 ms budget */
    nanosleep(&ts, NULL);
}

static void *setter_from_outside(void *arg)
{
    misuse_log *m = arg;
    camera_desc c = {{0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 40.f};
    m->setter_outside_refused = !pipeline_set_camera(m->p, 0, &c);
    return NULL;
}

static void spawn_setter(pipeline *p, void *args)
{
    /* from a thread that is not in the serial section, while the pipeline runs */
    misuse_log *m = *(misuse_log **)args;
    (void)p;
    pthread_t th;
    cr_assert_eq(pthread_create(&th, NULL, setter_from_outside, m), 0);
    pthread_join(th, NULL);
}

Test(pipeline, limits_are_enforced)
{
    fixture fx = fixture_make();
    camera_desc cam = test_camera(&fx, 0);
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 2;
    cfg.max_frames = 4;
    capture_display *cap;
    pipeline *p = make_pipeline(&fx, cfg, &cap, &cam);
    misuse_log m = {false, false, false, p};
    misuse_log *mp = &m;
    char big[PIPELINE_ARGS_MAX + 1] = {0};
    cr_assert_not(pipeline_transaction(p, "too big", slow_transaction, big, sizeof big));
    cr_assert(pipeline_transaction(p, "run inside", try_run_inside, &mp, sizeof mp));
    cr_assert(pipeline_transaction(p, "slow", slow_transaction, NULL, 0));
    cr_assert(pipeline_transaction(p, "setter outside", spawn_setter, &mp, sizeof mp));
    run_ok(p);
    cr_assert(m.run_refused, "pipeline_run inside a transaction was not refused");
    cr_assert(m.setter_outside_refused, "a camera change outside the serial section was not refused");
    pipeline_stats st = pipeline_get_stats(p);
    /* the 5 ms one at least (on a loaded machine a preempted quick one may be counted too) */
    cr_assert(st.slow_callbacks >= 1, "the slow transaction was not counted");
    cr_assert_eq(st.transactions_rejected, 1);
    pipeline_destroy(p);

    /* a full queue refuses (nothing drains it before run) */
    int refused = 0;
    p = make_pipeline(&fx, cfg, &cap, &cam);
    for (int i = 0; i < PIPELINE_QUEUE_MAX + 10; i++)
        refused += !pipeline_queue_threads(p, 1);
    cr_assert_eq(refused, 10);
    pipeline_destroy(p);
    fixture_free(&fx);
}

Test(pipeline, bad_configs_are_refused_with_the_field_named)
{
    fixture fx = fixture_make();
    tess_error err = {{0}};
    pipeline_config cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.threads = 0;
    cr_assert_null(pipeline_create(&cfg, &err));
    cr_assert(strstr(err.msg, "threads"), "%s", err.msg);
    cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.tile_px = 2;
    err.msg[0] = 0;
    cr_assert_null(pipeline_create(&cfg, &err));
    cr_assert(strstr(err.msg, "tile_px"), "%s", err.msg);
    cfg = pipeline_config_default(fx.scene, fx.accel);
    cfg.time_mode = PIPELINE_TIME_FIXED_RATE;
    cfg.rate_hz = 0.0;
    err.msg[0] = 0;
    cr_assert_null(pipeline_create(&cfg, &err));
    cr_assert(strstr(err.msg, "rate_hz"), "%s", err.msg);
    cfg = pipeline_config_default(fx.scene, fx.accel);
    pipeline *p = pipeline_create(&cfg, &err);
    cr_assert(p);
    camera_desc bad = {{0, 0, 0}, {0, 0, 0}, {0, 1, 0}, 40.f};
    err.msg[0] = 0;
    cr_assert_eq(pipeline_add_channel(p, &bad, 10, 10, &capture_create()->base, &err), -1);
    cr_assert(strstr(err.msg, "channel 0"), "%s", err.msg);
    err.msg[0] = 0;
    cr_assert_not(pipeline_run(p, &err));
    cr_assert(strstr(err.msg, "no channels"), "%s", err.msg);
    pipeline_destroy(p);
    fixture_free(&fx);
}
