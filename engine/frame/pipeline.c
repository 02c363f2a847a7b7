/* pipeline.c - the frame loop, the frame barrier and transactions; the
 * image traverser (traverser.h) hands out the work of a frame. See pipeline.h for the model; the comments here say which
 * lock or which stage guards each field. */
#include "pipeline.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "engine/scene/accel.h"
#include "engine/scene/frame_state.h"
#include "engine/base/log.h"
#include "engine/render/overlay.h"
#include "engine/scene/scene.h"
#include "engine/base/thread_name.h"
#include "engine/base/clock.h"

_Static_assert(PIPELINE_STATUS_BYTES == OVERLAY_TEXT_BYTES, "the status line is the overlay's text");
_Static_assert(PIPELINE_STATUS_BYTES == TXN_TEXT_BYTES, "the status line is a status record's text");
_Static_assert(PIPELINE_MAX_CHANNELS == TXN_MAX_CHANNELS, "records name the pipeline's channels");
_Static_assert(PIPELINE_MAX_THREADS == TXN_MAX_THREADS, "records give the pipeline's thread counts");
_Static_assert(sizeof(txn_record) <= PIPELINE_ARGS_MAX, "a record rides in a queue slot");

/* A queued callback with its own copy of the arguments, or a record
 * (fn NULL: args holds a txn_record, applied to the frame state). */
typedef struct queued_call {
    pipeline_fn fn;     /* NULL: a record */
    const char *name;
    uint64_t due_frame; /* one-shots: the frame it runs at; transactions: 0 */
    size_t args_bytes;
    union {
        max_align_t align;
        unsigned char bytes[PIPELINE_ARGS_MAX];
    } args;
} queued_call;

typedef struct serial_callback {
    const char *name;
    pipeline_serial_fn fn;
    void *ctx;
} serial_callback;

typedef struct parallel_callback {
    const char *name;
    pipeline_parallel_fn fn;
    void *ctx;
} parallel_callback;

typedef struct termination_callback {
    const char *name;
    pipeline_termination_fn fn;
    void *ctx;
} termination_callback;

enum { BUFFER_COUNT = 3 };

typedef struct frame_buffer {
    float *rgb;       /* width * height * 3, 64-byte aligned inside rgb_block */
    void *rgb_block;  /* what calloc gave (freed): zeroed pages the kernel maps only when first
                         written, so a channel that never renders (a remote view's private
                         channel nobody uses) costs address space, not memory */
    frame_image meta; /* what is (being) rendered into rgb */
    bool rendered;    /* the frame in meta was rendered (its channel was on); serial section */
} frame_buffer;

typedef struct pipe_channel {
    /* its camera and active flag live in the frame state (pipeline.state) */
    /* fixed after pipeline_add_channel */
    int width_px, height_px;
    float plane_aspect;    /* width / height of the image plane the window is part of */
    camera_window window;  /* the part of that plane this channel shows */
    image_display *display;
    frame_buffer buffers[BUFFER_COUNT];
    /* buffer states (indices into buffers): changed only by the serial section */
    int pending, queued, on_screen;
    bool queued_valid; /* buffers[queued] holds a finished frame not yet displayed */
    /* frozen for the frame being rendered: written by the serial section, read by render threads */
    render_view view;
    overlay_plan overlay; /* the overlay in this channel's pixels (given to the traverser only when
                             something of it falls on them) */
    bool overlay_on;      /* overlay has something to draw this frame */
    /* governor only (NULL / unused without one), made by pipeline_run: */
    float *accum;         /* accumulation buffer, width * height * 3 (render threads, per tile) */
    float *lowres;        /* a reduced frame, the size of rung 1's (render threads) */
    render_view lowres_view;              /* frozen like `view`, for reduced frames */
    upscale_plan *plans[GOVERNOR_RUNGS];  /* [0] unused; read-only once made */
    uint32_t first_band;  /* reduced frames: this channel's first upscale work item */
} pipe_channel;

/* What every thread does in the current loop step; written only by the
 * serial section, read by all threads after the barrier releases them. */
typedef struct loop_step {
    frame_info info;
    bool render;           /* render frame info.frame */
    bool display;          /* thread 0 runs the display stage first: shows the queued buffers, end_stage hooks */
    bool frames_queued;    /* ... and some channel has a queued frame to show */
    bool animate_parallel; /* parallel animation callbacks, then the animation barrier */
    bool exit;             /* leave the loop */
} loop_step;

/* One per thread slot, each on its own cache lines (the counts are written
 * once per frame by their thread and read by the serial section). */
typedef struct render_thread {
    alignas(64) pipeline *p;
    int id;              /* 0 is the thread that called pipeline_run */
    pthread_t handle;    /* valid while `joinable` */
    bool joinable;       /* serial section / run only */
    uint64_t start_generation; /* a new thread waits until the frame barrier passes this generation */
    render_counts counts; /* rays of the current frame; written by this thread in the render
                             stage, read and cleared by the serial section */
    double barrier_s;     /* this thread's time at frame barriers so far; its own until run ends */
    double left_barrier_s; /* when it last left the frame barrier (now_s); written by this thread,
                              read by the next serial section (the barrier orders them) */
    double render_stage_s; /* its render stage in the current step: written by this thread, read
                              and cleared by the serial section (the frame barrier orders them) */
    double upscale_stage_s; /* of which upscaling; the same rules */
    float *upscale_scratch; /* governor: upscale_plan_rows' scratch, made by the serial section
                               before the thread's first reduced frame; used only by this thread */
} render_thread;

/* A barrier whose last arriving thread runs a function before releasing the
 * others. Guarded by `lock`: arrived, participants, and every change of
 * `generation` (atomic so that it may be read without the lock).
 * Waiters sleep on the condition variable at once: spinning first (2000 pause
 * iterations) made no difference above the noise in `bench --scaling` on 2
 * cores (median fraction of linear 0.993 vs 0.988, spread +-2 %), so it is
 * not done. */
typedef struct barrier {
    pthread_mutex_t lock;
    pthread_cond_t released;
    int participants;
    int arrived;
    atomic_uint_fast64_t generation;
} barrier;


struct pipeline {
    pipeline_config cfg;

    /* channels: the array is fixed once run starts */
    pipe_channel channels[PIPELINE_MAX_CHANNELS];
    int channel_count;
    image_traverser *traverser; /* made by pipeline_run, when the channels are known */
    bool displays_every_stage;  /* some channel's display has an end_stage hook; set by pipeline_run */
    /* the cluster hooks (pipeline.h): fixed once the loop runs */
    pipeline_record_fn record_observer;
    void *record_observer_ctx;
    pipeline_sync_fn frame_sync;
    void *frame_sync_ctx;
    pipeline_display_sync_fn display_sync;
    void *display_sync_ctx;
    pipeline_plan_sync_fn plan_sync;
    void *plan_sync_ctx;
    governor_cost step_cost; /* serial section: the cost observed this step instead of the measured one */
    bool step_cost_set;      /* serial section: step_cost holds it (cleared once observed) */

    /* transaction queue (ring) and one-shots: guarded by queue_lock */
    pthread_mutex_t queue_lock;
    queued_call *queue;   /* PIPELINE_QUEUE_MAX slots */
    size_t queue_head, queue_count;
    queued_call *oneshots; /* PIPELINE_QUEUE_MAX slots, unordered; due frames ascend within a frame's run */
    size_t oneshot_count;
    pthread_cond_t queue_changed; /* signalled on every queued call and on stop (an idle step waits on it) */
    bool closed;   /* no more transactions: run has returned */
    bool refusing; /* the last call was refused (logging only the first of a run) */

    /* callbacks: changed only in the serial section or before run */
    serial_callback serial_anim[PIPELINE_MAX_CALLBACKS];
    int serial_anim_count;
    parallel_callback parallel_anim[PIPELINE_MAX_CALLBACKS];
    int parallel_anim_count;
    termination_callback terminations[PIPELINE_MAX_CALLBACKS];
    int termination_count;

    /* What transactions change (cameras, channel switches, threads, overlay inputs, render
     * options, per-geometry flags): written only in the serial section (or while no loop
     * runs), read by render threads during the frame through render_view.state: the state at
     * the barrier is the frame's snapshot (frame_state.h). */
    frame_state state;
    overlay_state overlay;     /* as drawn: derived from the state (status composed with the
                                  governor's line, cursor) in the serial section */
    const renderer *frame_renderer; /* the state's renderer frozen for the frame being rendered */

    /* the governor: serial section only, except `frame_plan`, `frame_sampler`,
     * `reduced` and the upscale fields, which render threads read in the
     * step the serial section prepared */
    bool governed;
    bool fixed_scale;                    /* cfg.render_scale < 1 without a governor: every frame at rung 1 */
    double rung_scale[GOVERNOR_RUNGS];   /* the scale of each rung in use: the governor's ladder, or
                                            {1, render_scale}; rung_count of them */
    int rung_count;
    governor gov;
    governor_frame frame_plan;           /* of the frame being rendered */
    pixel_sampler frame_sampler;         /* its sampler */
    bool reduced;                        /* the frame renders at a reduced scale */
    double rung_pixels[GOVERNOR_RUNGS];  /* low-res pixels of every channel at each rung */
    uint64_t planned_picture_serial, planned_overlay_serial;
    image_traverser *rung_traversers[GOVERNOR_RUNGS]; /* [0] unused: low-res tiles of each rung */
    size_t upscale_scratch_floats;       /* the most any plan needs */
    barrier upscale_barrier;             /* between the low-res tiles and upscaling */
    uint32_t upscale_items;              /* bands of all active channels this frame */
    alignas(64) atomic_uint upscale_next; /* next band to hand out; reset by the serial section */
    alignas(64) double last_upscale_s;   /* serial section: the previous step's longest upscale */
    double last_step_pixels;             /* serial section: low-res pixels the previous step rendered */

    /* the loop */
    barrier frame_barrier, anim_barrier;
    loop_step step;
    render_thread threads[PIPELINE_MAX_THREADS];
    int thread_count;      /* threads in the loop this step: serial section only */
    atomic_bool stop_requested;
    atomic_bool running;
    bool ran;              /* pipeline_run was called: its thread only */
    bool exit_after_step;  /* the current step is the last: serial section only */
    uint64_t next_frame;   /* serial section only */
    uint64_t next_step;    /* serial section only: loop steps that rendered or idled (frames without a governor) */
    double start_s, last_serial_s;
    double last_render_s;  /* serial section only: the previous step's longest render stage */
    queued_call *oneshot_scratch; /* serial section only: due one-shots being run */

    /* display stage: written by thread 0 in the display stage, read by the serial section */
    double display_stage_s; /* duration of the last display stage */
    bool closed_prepared; /* scene_prepare_closed ran (serial section, the first frame with a
                             cutting plane on and caps drawn); serial sections only */
    bool display_failed;
    tess_error display_error;

    /* statistics: guarded by stats_lock */
    pthread_mutex_t stats_lock;
    pipeline_stats stats;
    /* per-frame aggregates of the frame barrier, written only by serial sections (one at a
     * time, ordered by the barrier) and copied into stats when the run ends */
    double serial_s;          /* time inside serial sections */
    double release_s;         /* per barrier: from the serial section's end to the last thread leaving */
    double serial_end_s;      /* when the last serial section ended (now_s), 0 before the first */
    int released_threads;     /* threads the last serial section released */
    uint64_t serial_sections; /* frame barriers passed */

    /* What the serial section logs (a refused setter, a slow transaction): kept
     * here and written by thread 0 after the barrier, never at it (stderr may
     * block: a soak on a busy disk saw frames of 0.1-1.4 s, 86 % of its slow
     * transactions being ones that logged). Appended by the serial section,
     * written and emptied by thread 0 before it arrives at the next barrier:
     * the barrier orders the two. */
    char barrier_log[PIPELINE_BARRIER_LOG_BYTES];
    size_t barrier_log_bytes;
    uint64_t barrier_log_dropped; /* lines that did not fit */
};

/* log_divert_thread's target in the serial section: the line is kept for thread 0. */
_Static_assert(OVERLAY_POINTERS == TXN_POINTERS, "a pointer record's slot is an overlay pointer");

static void keep_barrier_log(void *ctx, const char *line)
{
    pipeline *p = ctx;
    size_t n = strlen(line);
    if (p->barrier_log_bytes + n + 1 > sizeof p->barrier_log) {
        p->barrier_log_dropped++;
        return;
    }
    memcpy(p->barrier_log + p->barrier_log_bytes, line, n);
    p->barrier_log[p->barrier_log_bytes + n] = '\n';
    p->barrier_log_bytes += n + 1;
}

/* Thread 0, after a barrier: write what the serial section logged (one write). */
static void flush_barrier_log(pipeline *p)
{
    if (p->barrier_log_bytes) {
        fwrite(p->barrier_log, 1, p->barrier_log_bytes, stderr);
        p->barrier_log_bytes = 0;
    }
    if (p->barrier_log_dropped) {
        log_warn("pipeline: %llu more log lines of one frame barrier dropped (over %d bytes)",
                 (unsigned long long)p->barrier_log_dropped, PIPELINE_BARRIER_LOG_BYTES);
        p->barrier_log_dropped = 0;
    }
}

/* The pipeline whose serial section this thread is running, if any. */
static _Thread_local const pipeline *tls_serial_owner;

static double now_s(void) { return clock_monotonic_s(); }

/* ---------------------------------------------------------------- barrier */

static void barrier_init(barrier *b)
{
    pthread_mutex_init(&b->lock, NULL);
    pthread_cond_init(&b->released, NULL);
    b->participants = 1;
    b->arrived = 0;
    atomic_init(&b->generation, 0);
}

static void barrier_destroy(barrier *b)
{
    pthread_cond_destroy(&b->released);
    pthread_mutex_destroy(&b->lock);
}

/* Wait until all participants have arrived. The last one runs `serial(p)`
 * (if not NULL) while the others wait; serial returns the participants of the
 * next use (-1 keeps them), set before anyone is released. */
static void barrier_wait(barrier *b, pipeline *p, int (*serial)(pipeline *p))
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
static void barrier_set_participants(barrier *b, int participants)
{
    pthread_mutex_lock(&b->lock);
    b->participants = participants;
    pthread_mutex_unlock(&b->lock);
}

/* ---------------------------------------------------------------- config */

pipeline_config pipeline_config_default(const struct scene *s, const struct accel *a)
{
    pipeline_config c;
    memset(&c, 0, sizeof c);
    c.scene = s;
    c.accel = a;
    c.threads = 1;
    c.time_mode = PIPELINE_TIME_REAL;
    c.rate_hz = 30.0;
    c.max_frames = 0;
    c.tile_px = RENDER_TILE_PX;
    c.order = TILE_ORDER_ROWS;
    c.order_seed = 1;
    c.sampler = pixel_sampler_single();
    c.renderer = renderer_by_name("raytracer");
    c.shadows = true;
    c.budget_ms = 0.0;
    c.still_s = GOVERNOR_DEFAULT_STILL_S;
    c.refine_k = GOVERNOR_DEFAULT_REFINE_K;
    c.upscale = UPSCALE_BILINEAR;
    c.render_scale = 1.0;
    c.settings = render_settings_default();
    c.opacity = 1.f; /* the planes: all unused (zeroed) */
    return c;
}

static bool settings_validate(const render_settings *s, tess_error *err)
{
    if (!(s->min_transmittance > 0.f && s->min_transmittance < 1.f))
        return tess_error_set(err, "pipeline: settings.min_transmittance: %g is not in (0, 1)",
                              (double)s->min_transmittance);
    if (s->max_layers < 1 || s->max_layers > PIPELINE_MAX_LAYERS_MAX)
        return tess_error_set(err, "pipeline: settings.max_layers: %d is not in 1..%d", s->max_layers,
                              PIPELINE_MAX_LAYERS_MAX);
    if (s->cap_style != RENDER_CAP_TINT && s->cap_style != RENDER_CAP_HATCH)
        return tess_error_set(err, "pipeline: settings.cap_style: unknown style %d", (int)s->cap_style);
    if (s->ao_rays < 1 || s->ao_rays > PIPELINE_AO_RAYS_MAX)
        return tess_error_set(err, "pipeline: settings.ao_rays: %d is not in 1..%d", s->ao_rays,
                              PIPELINE_AO_RAYS_MAX);
    if (!isfinite(s->ao_distance) || s->ao_distance < 0.f)
        return tess_error_set(err, "pipeline: settings.ao_distance: %g is not a distance >= 0 (0: from the scene)",
                              (double)s->ao_distance);
    if (s->ao_interleave < 1 || s->ao_interleave > PIPELINE_AO_INTERLEAVE_MAX)
        return tess_error_set(err, "pipeline: settings.ao_interleave: %d is not in 1..%d", s->ao_interleave,
                              PIPELINE_AO_INTERLEAVE_MAX);
    if (s->ao_filter_px < 1 || s->ao_filter_px > PIPELINE_AO_FILTER_PX_MAX || s->ao_filter_px % 2 == 0)
        return tess_error_set(err, "pipeline: settings.ao_filter_px: %d is not odd in 1..%d", s->ao_filter_px,
                              PIPELINE_AO_FILTER_PX_MAX);
    if (s->ao_frames < 1 || s->ao_frames > PIPELINE_AO_FRAMES_MAX)
        return tess_error_set(err, "pipeline: settings.ao_frames: %d is not in 1..%d", s->ao_frames,
                              PIPELINE_AO_FRAMES_MAX);
    if (!(s->ao_exponent >= 1.f && s->ao_exponent <= RENDER_AO_EXPONENT_MAX))
        return tess_error_set(err, "pipeline: settings.ao_exponent: %g is not in [1, %g]", (double)s->ao_exponent,
                              (double)RENDER_AO_EXPONENT_MAX);
    return true;
}

/* An initial plane the config leaves unused: off, zero normal (a zeroed entry). */
static bool plane_unused(const clip_plane *c)
{
    return !c->on && c->normal.x == 0.f && c->normal.y == 0.f && c->normal.z == 0.f;
}

static txn_record plane_record(int index, const clip_plane *c)
{
    const float point[3] = {c->point.x, c->point.y, c->point.z}, normal[3] = {c->normal.x, c->normal.y, c->normal.z};
    return txn_clip_plane(index, c->on, point, normal);
}

bool pipeline_config_validate(const pipeline_config *cfg, tess_error *err)
{
    if (!cfg->scene || !cfg->accel)
        return tess_error_set(err, "pipeline: no scene or acceleration structure");
    if (cfg->threads < 1 || cfg->threads > PIPELINE_MAX_THREADS)
        return tess_error_set(err, "pipeline: threads: %d is not in 1..%d", cfg->threads, PIPELINE_MAX_THREADS);
    if (cfg->time_mode != PIPELINE_TIME_REAL && cfg->time_mode != PIPELINE_TIME_FIXED_RATE)
        return tess_error_set(err, "pipeline: unknown time mode %d", (int)cfg->time_mode);
    if (cfg->time_mode == PIPELINE_TIME_FIXED_RATE && !(cfg->rate_hz > 0.0 && isfinite(cfg->rate_hz)))
        return tess_error_set(err, "pipeline: rate_hz: %g is not a positive frame rate", cfg->rate_hz);
    if (cfg->tile_px < PIPELINE_TILE_PX_MIN || cfg->tile_px > PIPELINE_TILE_PX_MAX)
        return tess_error_set(err, "pipeline: tile_px: %d is not in %d..%d", cfg->tile_px, PIPELINE_TILE_PX_MIN,
                              PIPELINE_TILE_PX_MAX);
    if (!cfg->renderer)
        return tess_error_set(err, "pipeline: no renderer");
    if ((unsigned)cfg->order >= TILE_ORDER_COUNT)
        return tess_error_set(err, "pipeline: unknown tile order %d", (int)cfg->order);
    if (!pixel_sampler_validate(&cfg->sampler, err)) {
        tess_error_prefix(err, "pipeline: sampler: ");
        return false;
    }
    if (cfg->sampler.kind == PIXEL_SAMPLER_STRATUM)
        return tess_error_set(err, "pipeline: sampler: a stratum sampler is the governor's, not a config's");
    if (!(cfg->budget_ms >= 0.0) || !isfinite(cfg->budget_ms))
        return tess_error_set(err, "pipeline: budget_ms: %g is not a time >= 0 (0: no governor)", cfg->budget_ms);
    if (!upscale_scale_validate(cfg->render_scale, err)) {
        tess_error_prefix(err, "pipeline: render_scale: ");
        return false;
    }
    if (cfg->render_scale < 1.0 && cfg->budget_ms > 0.0)
        return tess_error_set(err, "pipeline: render_scale %g with budget_ms %g: the governor picks the scale",
                              cfg->render_scale, cfg->budget_ms);
    if ((unsigned)cfg->upscale > UPSCALE_CLAMPED_CUBIC)
        return tess_error_set(err, "pipeline: unknown upscale filter %d", (int)cfg->upscale);
    if (cfg->budget_ms > 0.0) {
        governor_config g = {cfg->budget_ms * 1e-3, cfg->still_s, cfg->refine_k};
        if (!governor_config_validate(&g, err)) {
            tess_error_prefix(err, "pipeline: ");
            return false;
        }
    }
    if (!settings_validate(&cfg->settings, err))
        return false;
    if (!isfinite(cfg->opacity) || cfg->opacity < 0.f || cfg->opacity > 1.f)
        return tess_error_set(err, "pipeline: opacity: %g is not in [0, 1]", (double)cfg->opacity);
    for (int i = 0; i < CLIP_MAX_PLANES; i++) {
        if (plane_unused(&cfg->clip[i]))
            continue;
        txn_record r = plane_record(i, &cfg->clip[i]);
        if (!txn_validate(&r, err)) {
            tess_error_prefix(err, "pipeline: clip[%d]: ", i);
            return false;
        }
    }
    return true;
}

/* The part opacities the scene starts with (scene_instance.opacity); false
 * on no memory. */
static bool start_opacities(frame_state *st, const scene *s)
{
    for (uint32_t i = 0; s && i < s->instance_count; i++)
        if (s->instances[i].opacity != 1.f && !frame_state_set_opacity(st, i, 1, s->instances[i].opacity))
            return false;
    return true;
}

pipeline *pipeline_create(const pipeline_config *cfg, tess_error *err)
{
    if (!pipeline_config_validate(cfg, err))
        return NULL;
    pipeline *p = calloc(1, sizeof *p);
    queued_call *queue = malloc(PIPELINE_QUEUE_MAX * sizeof *queue);
    queued_call *oneshots = malloc(PIPELINE_QUEUE_MAX * sizeof *oneshots);
    queued_call *scratch = malloc(PIPELINE_QUEUE_MAX * sizeof *scratch);
    if (!p || !queue || !oneshots || !scratch) {
        free(p);
        free(queue);
        free(oneshots);
        free(scratch);
        tess_error_set(err, "pipeline: out of memory");
        return NULL;
    }
    p->cfg = *cfg;
    p->queue = queue;
    p->oneshots = oneshots;
    p->oneshot_scratch = scratch;
    frame_state_init(&p->state, cfg->renderer, cfg->shadows, cfg->threads, accel_geometry_count(cfg->accel));
    p->frame_renderer = cfg->renderer;
    /* an earlier user's hidden flags, and the part opacities the scene starts with */
    if (!frame_state_adopt_hidden(&p->state, cfg->accel) || !start_opacities(&p->state, cfg->scene)) {
        frame_state_finish(&p->state);
        free(p);
        free(queue);
        free(oneshots);
        free(scratch);
        tess_error_set(err, "pipeline: out of memory");
        return NULL;
    }
    /* where inspection starts: as records, so the planes are normalised as input's are (validated above) */
    if (cfg->opacity != 1.f)
        frame_state_set_global_opacity(&p->state, cfg->opacity);
    for (int i = 0; i < CLIP_MAX_PLANES; i++)
        if (!plane_unused(&cfg->clip[i])) {
            txn_record r = plane_record(i, &cfg->clip[i]);
            tess_error unused = {{0}};
            bool applied = txn_apply(&r, &p->state, &unused);
            assert(applied); /* pipeline_config_validate checked it; a plane allocates nothing */
            (void)applied;
        }
    pthread_mutex_init(&p->queue_lock, NULL);
    pthread_cond_init(&p->queue_changed, NULL);
    pthread_mutex_init(&p->stats_lock, NULL);
    barrier_init(&p->frame_barrier);
    barrier_init(&p->anim_barrier);
    barrier_init(&p->upscale_barrier);
    p->frame_plan = (governor_frame){GOVERNOR_FRAME_SCALED, 0, 0, 1};
    p->frame_sampler = cfg->sampler;
    atomic_init(&p->upscale_next, 0);
    atomic_init(&p->stop_requested, false);
    atomic_init(&p->running, false);
    p->thread_count = 1;
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++) {
        p->threads[i].p = p;
        p->threads[i].id = i;
    }
    return p;
}

static void channel_free(pipe_channel *c)
{
    for (int b = 0; b < BUFFER_COUNT; b++)
        free(c->buffers[b].rgb_block);
    free(c->accum);
    free(c->lowres);
    for (int r = 0; r < GOVERNOR_RUNGS; r++)
        upscale_plan_destroy(c->plans[r]);
    image_display_destroy(c->display);
}

int pipeline_add_channel(pipeline *p, const camera_desc *camera, int width_px, int height_px, image_display *display,
                         tess_error *err)
{
    float aspect = height_px > 0 ? (float)width_px / (float)height_px : 1.f;
    return pipeline_add_channel_window(p, camera, aspect, CAMERA_WINDOW_FULL, width_px, height_px, display, err);
}

int pipeline_add_channel_window(pipeline *p, const camera_desc *camera, float plane_aspect, camera_window window,
                                int width_px, int height_px, image_display *display, tess_error *err)
{
    bool ok = true;
    if (p->ran || atomic_load(&p->running))
        ok = tess_error_set(err, "pipeline: channels can only be added before the pipeline runs");
    else if (p->channel_count == PIPELINE_MAX_CHANNELS)
        ok = tess_error_set(err, "pipeline: more than %d channels", PIPELINE_MAX_CHANNELS);
    else if (width_px < 1 || height_px < 1 || width_px > 65536 || height_px > 65536)
        ok = tess_error_set(err, "pipeline: channel %d: image size %dx%d is not in 1x1..65536x65536",
                            p->channel_count, width_px, height_px);
    else if (!display)
        ok = tess_error_set(err, "pipeline: channel %d has no display", p->channel_count);
    else if (!(plane_aspect > 0.f && isfinite(plane_aspect)) || !(window.half_width > 0.f) ||
             !(window.half_height > 0.f) || !isfinite(window.center_x) || !isfinite(window.center_y) ||
             !isfinite(window.half_width) || !isfinite(window.half_height))
        ok = tess_error_set(err, "pipeline: channel %d: degenerate window or plane aspect", p->channel_count);
    else if (!camera_validate(camera, err)) {
        tess_error_prefix(err, "pipeline: channel %d: ", p->channel_count);
        ok = false;
    }
    if (!ok) {
        image_display_destroy(display);
        return -1;
    }
    pipe_channel *c = &p->channels[p->channel_count];
    memset(c, 0, sizeof *c);
    c->width_px = width_px;
    c->height_px = height_px;
    c->plane_aspect = plane_aspect;
    c->window = window;
    c->display = display;
    /* the status line's corner: the bottom-left of every window so far */
    float left = window.center_x - window.half_width, bottom = window.center_y - window.half_height;
    if (p->channel_count == 0 || left < p->overlay.anchor_sx)
        p->overlay.anchor_sx = left;
    if (p->channel_count == 0 || bottom < p->overlay.anchor_sy)
        p->overlay.anchor_sy = bottom;
    size_t floats = (size_t)width_px * (size_t)height_px * 3;
    /* cache-line aligned, so a tile row shares lines with a neighbour tile only where the
     * image width makes it (16-pixel float RGB rows are whole lines) */
    size_t bytes = floats * sizeof(float) + 64;
    for (int b = 0; b < BUFFER_COUNT; b++)
        if ((c->buffers[b].rgb_block = calloc(1, bytes)))
            c->buffers[b].rgb = (float *)(((uintptr_t)c->buffers[b].rgb_block + 63) & ~(uintptr_t)63);
    bool have_memory = true;
    for (int b = 0; b < BUFFER_COUNT; b++)
        have_memory = have_memory && c->buffers[b].rgb != NULL;
    if (!have_memory) {
        channel_free(c);
        memset(c, 0, sizeof *c);
        tess_error_set(err, "pipeline: channel %d: out of memory for its %dx%d frame buffers (%d of %.1f GiB each)",
                       p->channel_count, width_px, height_px, BUFFER_COUNT, (double)bytes / (1024.0 * 1024 * 1024));
        return -1;
    }
    c->pending = 0;
    c->queued = 1;
    c->on_screen = 2;
    frame_state_add_channel(&p->state, camera); /* its index is channel_count: both stop at the same maximum */
    return p->channel_count++;
}

/* A cluster hook may be set once, before the run. */
static bool may_set_hook(const pipeline *p, bool already_set)
{
    if (p->ran || atomic_load(&p->running)) {
        log_error("pipeline: a cluster hook can be set only before the pipeline runs");
        return false;
    }
    return !already_set;
}

bool pipeline_set_record_observer(pipeline *p, pipeline_record_fn fn, void *ctx)
{
    if (!may_set_hook(p, p->record_observer != NULL))
        return false;
    p->record_observer = fn;
    p->record_observer_ctx = ctx;
    return true;
}

bool pipeline_set_frame_sync(pipeline *p, pipeline_sync_fn fn, void *ctx)
{
    if (!may_set_hook(p, p->frame_sync != NULL))
        return false;
    p->frame_sync = fn;
    p->frame_sync_ctx = ctx;
    return true;
}

bool pipeline_governed(const pipeline *p) { return p->cfg.budget_ms > 0.0; }

bool pipeline_set_plan_sync(pipeline *p, pipeline_plan_sync_fn fn, void *ctx)
{
    if (!pipeline_governed(p) || !may_set_hook(p, p->plan_sync != NULL))
        return false;
    p->plan_sync = fn;
    p->plan_sync_ctx = ctx;
    return true;
}

governor_cost pipeline_step_cost(const pipeline *p)
{
    const loop_step *s = &p->step;
    return (governor_cost){s->info.last_frame_s, s->info.last_render_s, p->last_upscale_s, p->last_step_pixels};
}

void pipeline_set_step_cost(pipeline *p, const governor_cost *cost)
{
    p->step_cost = *cost;
    p->step_cost_set = true;
}

bool pipeline_set_display_sync(pipeline *p, pipeline_display_sync_fn fn, void *ctx)
{
    if (!may_set_hook(p, p->display_sync != NULL))
        return false;
    p->display_sync = fn;
    p->display_sync_ctx = ctx;
    return true;
}

bool pipeline_set_channel_private(pipeline *p, int channel, tess_error *err)
{
    if (p->ran || atomic_load(&p->running))
        return tess_error_set(err, "pipeline: a channel can be made private only before the pipeline runs");
    if (channel < 1 || channel >= p->channel_count)
        return tess_error_set(err, "pipeline: channel %d cannot be private (channels 1..%d may be; channel 0 is "
                                   "the wall's)",
                              channel, p->channel_count - 1);
    frame_state_set_private(&p->state, channel);
    return true;
}

bool pipeline_set_status_anchor(pipeline *p, float sx, float sy)
{
    if (p->ran || atomic_load(&p->running) || !isfinite(sx) || !isfinite(sy))
        return false;
    p->overlay.anchor_sx = sx;
    p->overlay.anchor_sy = sy;
    return true;
}

bool pipeline_channel_private(const pipeline *p, int channel)
{
    return channel >= 0 && channel < p->channel_count && p->state.private_view[channel];
}

/* ---------------------------------------------------------------- queueing */

static bool queue_call(pipeline *p, bool oneshot, uint64_t frame, const char *name, pipeline_fn fn,
                       const void *args, size_t args_bytes)
{
    if (args_bytes > PIPELINE_ARGS_MAX) {
        log_error("pipeline: transaction '%s': %zu bytes of arguments (at most %d are copied)", name, args_bytes,
                  PIPELINE_ARGS_MAX);
        pthread_mutex_lock(&p->stats_lock);
        p->stats.transactions_rejected++;
        pthread_mutex_unlock(&p->stats_lock);
        return false;
    }
    pthread_mutex_lock(&p->queue_lock);
    const char *refusal = NULL;
    queued_call *slot = NULL;
    /* once the stop is asked for no barrier runs transactions any more (serial_section) */
    bool stopping = p->closed || atomic_load(&p->stop_requested);
    if (stopping)
        refusal = p->closed ? "the pipeline has stopped" : "the pipeline is stopping";
    else if (!oneshot && p->queue_count == PIPELINE_QUEUE_MAX)
        refusal = "the transaction queue is full";
    else if (oneshot && p->oneshot_count == PIPELINE_QUEUE_MAX)
        refusal = "too many one-shot callbacks are waiting";
    else if (oneshot)
        slot = &p->oneshots[p->oneshot_count++];
    else
        slot = &p->queue[(p->queue_head + p->queue_count++) % PIPELINE_QUEUE_MAX];
    if (slot) {
        pthread_cond_broadcast(&p->queue_changed); /* an idle step may be waiting for work */
        slot->fn = fn;
        slot->name = name ? name : "(unnamed)";
        slot->due_frame = frame;
        slot->args_bytes = args_bytes;
        if (args_bytes)
            memcpy(slot->args.bytes, args, args_bytes);
    }
    /* log the first refusal of a run of them, not every retry of a flooding producer */
    bool first_refusal = refusal && !p->refusing;
    p->refusing = refusal != NULL;
    pthread_mutex_unlock(&p->queue_lock);
    if (refusal) {
        if (first_refusal)
            log_warn("pipeline: transaction '%s' refused: %s (further refusals are only counted until one is "
                     "accepted)",
                     name ? name : "(unnamed)", refusal);
        pthread_mutex_lock(&p->stats_lock);
        p->stats.transactions_rejected++;
        if (stopping)
            p->stats.rejected_stopped++;
        else
            p->stats.rejected_queue_full++;
        pthread_mutex_unlock(&p->stats_lock);
        return false;
    }
    return true;
}

static bool has_fn(pipeline_fn fn, const char *name)
{
    if (!fn)
        log_error("pipeline: transaction '%s' has no function", name ? name : "?");
    return fn != NULL;
}

bool pipeline_transaction(pipeline *p, const char *name, pipeline_fn fn, const void *args, size_t args_bytes)
{
    return has_fn(fn, name) && queue_call(p, false, 0, name, fn, args, args_bytes);
}

bool pipeline_at_frame(pipeline *p, uint64_t frame, const char *name, pipeline_fn fn, const void *args,
                       size_t args_bytes)
{
    return has_fn(fn, name) && queue_call(p, true, frame, name, fn, args, args_bytes);
}

void pipeline_stop(pipeline *p)
{
    atomic_store(&p->stop_requested, true);
    pthread_mutex_lock(&p->queue_lock); /* wake an idle step (it checks the flag under this lock) */
    pthread_cond_broadcast(&p->queue_changed);
    pthread_mutex_unlock(&p->queue_lock);
}

bool pipeline_stop_requested(const pipeline *p) { return atomic_load(&p->stop_requested); }

/* ---------------------------------------------------------------- records */

bool pipeline_in_serial_section(const pipeline *p) { return tls_serial_owner == p; }

/* State may change here: in the serial section, or while no loop runs. */
static bool may_change_state(const pipeline *p, const char *what)
{
    if (tls_serial_owner == p || !atomic_load(&p->running))
        return true;
    log_error("pipeline: %s outside a transaction or serial callback: refused (state changes only at the "
              "frame barrier)",
              what);
    return false;
}

/* What a record may name must exist in this pipeline: its geometries, its channels. */
static bool record_in_range(const pipeline *p, const txn_record *r, tess_error *err)
{
    const txn_geoms *g = r->kind == TXN_HIGHLIGHT ? &r->args.highlight.geoms
                         : r->kind == TXN_COLOUR  ? &r->args.colour.geoms
                         : r->kind == TXN_MOVE    ? &r->args.move.geoms
                         : r->kind == TXN_OPACITY && !r->args.opacity.all ? &r->args.opacity.geoms
                         : r->kind == TXN_HIDE || r->kind == TXN_SHOW || r->kind == TXN_ISOLATE ? &r->args.geoms
                                                                                                 : NULL;
    uint32_t count = p->state.geometry_count;
    if (g && (uint64_t)g->first + g->count > count)
        return txn_range_error(txn_kind_name(r->kind), g, count, err);
    int channel = r->kind == TXN_CAMERA ? r->args.camera.channel
                  : r->kind == TXN_CHANNEL_ACTIVE ? r->args.channel.channel
                                                  : TXN_ALL_CHANNELS;
    if (channel >= p->channel_count)
        return tess_error_set(err, "%s: no channel %d (there are %d)", txn_kind_name(r->kind), channel,
                              p->channel_count);
    return true;
}

/* Validate a record for queueing: its own checks, this pipeline's ranges, an engine kind. */
static bool record_ok(const pipeline *p, const txn_record *r, tess_error *err)
{
    if (!txn_validate(r, err) || !record_in_range(p, r, err))
        return false;
    if (txn_kind_input_level(r->kind))
        return tess_error_set(err, "%s: an input-level transaction (input/sink.h carries it out)",
                              txn_kind_name(r->kind));
    return true;
}

static bool submit(pipeline *p, const txn_record *r, tess_error *err)
{
    if (!record_ok(p, r, err))
        return false;
    if (!queue_call(p, false, 0, txn_kind_name(r->kind), NULL, r, sizeof *r))
        return tess_error_set(err, "pipeline: %s transaction refused (queue full or pipeline stopped)",
                              txn_kind_name(r->kind));
    return true;
}

bool pipeline_check(const pipeline *p, const txn_record *r, tess_error *err) { return record_ok(p, r, err); }

bool pipeline_submit_from(pipeline *p, const txn_record *r, const char *origin)
{
    tess_error err = {{0}};
    if (!record_ok(p, r, &err)) {
        log_error("pipeline: transaction refused: %s%s%s", origin ? origin : "", origin ? ": " : "", err.msg);
        pthread_mutex_lock(&p->stats_lock);
        p->stats.transactions_invalid++;
        pthread_mutex_unlock(&p->stats_lock);
        return false;
    }
    return submit(p, r, &err); /* a refusal by the queue is logged there */
}

bool pipeline_submit(pipeline *p, const txn_record *r) { return pipeline_submit_from(p, r, NULL); }

static void compose_status(pipeline *p);

/* Apply a record to the state (serial section, or no loop running) and carry
 * out what follows from it: the drawn overlay, the accel's hidden flags. */
static bool apply_record(pipeline *p, const txn_record *r)
{
    tess_error err = {{0}};
    if (!txn_apply(r, &p->state, &err)) {
        log_error("pipeline: transaction refused: %s", err.msg);
        return false;
    }
    if (p->record_observer)
        p->record_observer(p->record_observer_ctx, r);
    switch (r->kind) {
    case TXN_STATUS:
    case TXN_GOVERNOR_STATUS:
        compose_status(p);
        break;
    case TXN_CURSOR:
        p->overlay.cursor_visible = p->state.cursor_visible;
        p->overlay.cursor_sx = p->state.cursor_sx;
        p->overlay.cursor_sy = p->state.cursor_sy;
        break;
    case TXN_POINTER:
        for (int i = 0; i < OVERLAY_POINTERS; i++) {
            p->overlay.pointer_visible[i] = p->state.pointer_visible[i];
            p->overlay.pointer_sx[i] = p->state.pointer_sx[i];
            p->overlay.pointer_sy[i] = p->state.pointer_sy[i];
        }
        break;
    case TXN_HIDE:
    case TXN_SHOW:
    case TXN_ISOLATE:
    case TXN_SHOW_ALL:
        /* the accel's flags follow at the end of the serial section (once for all of its
         * records: only the flags that differ); outside a loop at once */
        if (tls_serial_owner != p)
            frame_state_sync_accel(&p->state, p->cfg.accel);
        break;
    default:
        break;
    }
    return true;
}

bool pipeline_apply(pipeline *p, const txn_record *r)
{
    if (!may_change_state(p, txn_kind_name(r->kind)))
        return false;
    tess_error err = {{0}};
    if (!record_ok(p, r, &err)) {
        log_error("pipeline: transaction refused: %s", err.msg);
        return false;
    }
    return apply_record(p, r);
}

/* ---- the setting-by-setting API: records built here ---- */

bool pipeline_queue_camera(pipeline *p, int channel, const camera_desc *camera, tess_error *err)
{
    if (channel < 0 || channel >= p->channel_count)
        return tess_error_set(err, "pipeline: no channel %d (there are %d)", channel, p->channel_count);
    if (!camera_validate(camera, err))
        return false;
    txn_record r = txn_camera(channel, camera);
    return submit(p, &r, err);
}

bool pipeline_queue_channel_active(pipeline *p, int channel, bool active)
{
    if (channel < 0 || channel >= p->channel_count) {
        log_error("pipeline: switching channel %d: there are %d channels", channel, p->channel_count);
        return false;
    }
    txn_record r = txn_channel_active(channel, active);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_threads(pipeline *p, int threads)
{
    txn_record r = txn_threads(threads);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_status(pipeline *p, const char *text)
{
    if (!text) {
        log_error("pipeline: status line: no text (\"\" hides the line)");
        return false;
    }
    txn_record r = txn_status(text);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_governor_status(pipeline *p, bool shown)
{
    txn_record r = txn_flag(TXN_GOVERNOR_STATUS, shown);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_cursor(pipeline *p, bool visible, float sx, float sy)
{
    txn_record r = txn_cursor(visible, sx, sy);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_hide(pipeline *p, uint32_t geom_id, bool hidden)
{
    txn_record r = txn_geoms_record(hidden ? TXN_HIDE : TXN_SHOW, geom_id, 1);
    return pipeline_submit(p, &r);
}

bool pipeline_queue_unhide_all(pipeline *p)
{
    txn_record r = txn_simple(TXN_SHOW_ALL);
    return pipeline_submit(p, &r);
}

/* ---------------------------------------------------------------- state */

/* overlay.status from the status text asked for and, when shown, the
 * governor's line for the frame being planned; bumps the state's
 * overlay_serial when the drawn text changes. */
static void compose_status(pipeline *p)
{
    const frame_state *st = &p->state;
    char text[PIPELINE_STATUS_BYTES];
    if (!st->governor_status_shown)
        snprintf(text, sizeof text, "%s", st->status);
    else {
        char line[PIPELINE_STATUS_BYTES];
        if (p->governed)
            governor_describe(&p->gov, &p->frame_plan, line, sizeof line);
        else
            snprintf(line, sizeof line, "governor: off (no frame budget)");
        /* the asked-for text first, the governor's line after it, cut at the end */
        size_t used = strlen(st->status);
        memcpy(text, st->status, used + 1);
        if (used && used + 3 < sizeof text) {
            memcpy(text + used, " | ", 4);
            used += 3;
        }
        size_t room = sizeof text - 1 - used, n = strnlen(line, room);
        memcpy(text + used, line, n);
        text[used + n] = '\0';
    }
    char before[PIPELINE_STATUS_BYTES];
    memcpy(before, p->overlay.status, sizeof before);
    overlay_set_status(&p->overlay, text);
    if (strcmp(before, p->overlay.status) != 0)
        frame_state_bump_overlay(&p->state);
}

/* The setters: records applied at once (serial section, or no loop running). */

bool pipeline_set_camera(pipeline *p, int channel, const camera_desc *camera)
{
    if (!may_change_state(p, "camera change"))
        return false;
    if (channel < 0 || channel >= p->channel_count) {
        log_error("pipeline: camera change for channel %d: there are %d channels", channel, p->channel_count);
        return false;
    }
    txn_record r = txn_camera(channel, camera);
    return apply_record(p, &r);
}

bool pipeline_set_channel_active(pipeline *p, int channel, bool active)
{
    if (!may_change_state(p, "channel switch"))
        return false;
    if (channel < 0 || channel >= p->channel_count) {
        log_error("pipeline: switching channel %d: there are %d channels", channel, p->channel_count);
        return false;
    }
    txn_record r = txn_channel_active(channel, active);
    return apply_record(p, &r);
}

bool pipeline_channel_active(const pipeline *p, int channel)
{
    return channel >= 0 && channel < p->channel_count && p->state.active[channel];
}

bool pipeline_set_threads(pipeline *p, int threads)
{
    if (!may_change_state(p, "thread-count change"))
        return false;
    txn_record r = txn_threads(threads);
    return apply_record(p, &r);
}

bool pipeline_set_status(pipeline *p, const char *text)
{
    if (!may_change_state(p, "status line change"))
        return false;
    if (!text) {
        log_error("pipeline: status line: no text (\"\" hides the line)");
        return false;
    }
    txn_record r = txn_status(text);
    return apply_record(p, &r);
}

bool pipeline_set_governor_status(pipeline *p, bool shown)
{
    if (!may_change_state(p, "governor status change"))
        return false;
    txn_record r = txn_flag(TXN_GOVERNOR_STATUS, shown);
    return apply_record(p, &r);
}

governor_frame pipeline_governor_frame(const pipeline *p) { return p->frame_plan; }

const char *pipeline_status(const pipeline *p) { return p->overlay.status; }

bool pipeline_set_cursor(pipeline *p, bool visible, float sx, float sy)
{
    if (!may_change_state(p, "cursor change"))
        return false;
    txn_record r = txn_cursor(visible, sx, sy);
    return apply_record(p, &r);
}

bool pipeline_cursor(const pipeline *p, float *sx, float *sy)
{
    if (sx)
        *sx = p->state.cursor_sx;
    if (sy)
        *sy = p->state.cursor_sy;
    return p->state.cursor_visible;
}

bool pipeline_set_hidden(pipeline *p, uint32_t geom_id, bool hidden)
{
    if (!may_change_state(p, hidden ? "hiding a geometry" : "showing a geometry"))
        return false;
    txn_record r = txn_geoms_record(hidden ? TXN_HIDE : TXN_SHOW, geom_id, 1);
    return apply_record(p, &r);
}

bool pipeline_unhide_all(pipeline *p)
{
    if (!may_change_state(p, "showing every geometry"))
        return false;
    txn_record r = txn_simple(TXN_SHOW_ALL);
    return apply_record(p, &r);
}

bool pipeline_hidden(const pipeline *p, uint32_t geom_id)
{
    /* the state is what was asked for; the accel (what traversal sees) follows it at the end
     * of each serial section, and is what other threads may read while the loop runs */
    if (tls_serial_owner == p || !atomic_load(&p->running))
        return frame_state_hidden(&p->state, geom_id);
    return accel_hidden(p->cfg.accel, geom_id);
}

uint32_t pipeline_geometry_count(const pipeline *p) { return accel_geometry_count(p->cfg.accel); }

const frame_state *pipeline_frame_state(const pipeline *p) { return &p->state; }

camera_desc pipeline_camera(const pipeline *p, int channel)
{
    if (channel < 0 || channel >= p->channel_count)
        return p->state.cameras[0];
    return p->state.cameras[channel];
}

uint64_t pipeline_camera_serial(const pipeline *p, int channel)
{
    if (channel < 0 || channel >= p->channel_count)
        return 0;
    return p->state.camera_serials[channel];
}

int pipeline_channel_count(const pipeline *p) { return p->channel_count; }

camera_basis pipeline_channel_basis(const pipeline *p, int channel)
{
    int i = channel < 0 || channel >= p->channel_count ? 0 : channel;
    const pipe_channel *c = &p->channels[i];
    return camera_basis_window(&p->state.cameras[i], c->plane_aspect, c->window, c->width_px, c->height_px);
}
uint64_t pipeline_frame(const pipeline *p) { return p->step.info.frame; }

pipeline_stats pipeline_get_stats(pipeline *p)
{
    pthread_mutex_lock(&p->stats_lock);
    pipeline_stats s = p->stats;
    pthread_mutex_unlock(&p->stats_lock);
    return s;
}

/* ---------------------------------------------------------------- callbacks */

static bool may_register(const pipeline *p, const char *what, int count)
{
    if (!may_change_state(p, what))
        return false;
    if (count >= PIPELINE_MAX_CALLBACKS) {
        log_error("pipeline: %s: more than %d registered", what, PIPELINE_MAX_CALLBACKS);
        return false;
    }
    return true;
}

bool pipeline_add_serial_animation(pipeline *p, const char *name, pipeline_serial_fn fn, void *ctx)
{
    if (!fn || !may_register(p, "serial animation callback", p->serial_anim_count))
        return false;
    p->serial_anim[p->serial_anim_count++] = (serial_callback){name ? name : "(unnamed)", fn, ctx};
    return true;
}

bool pipeline_add_parallel_animation(pipeline *p, const char *name, pipeline_parallel_fn fn, void *ctx)
{
    if (!fn || !may_register(p, "parallel animation callback", p->parallel_anim_count))
        return false;
    p->parallel_anim[p->parallel_anim_count++] = (parallel_callback){name ? name : "(unnamed)", fn, ctx};
    return true;
}

bool pipeline_add_termination(pipeline *p, const char *name, pipeline_termination_fn fn, void *ctx)
{
    if (!fn || !may_register(p, "termination callback", p->termination_count))
        return false;
    p->terminations[p->termination_count++] = (termination_callback){name ? name : "(unnamed)", fn, ctx};
    return true;
}

/* ---------------------------------------------------------------- serial section */

/* Time one serial callback against the budget. */
static void note_duration(pipeline *p, const char *kind, const char *name, double t0)
{
    double took = now_s() - t0;
    if (took <= PIPELINE_CALLBACK_BUDGET_S)
        return;
    log_warn("pipeline: %s '%s' took %.1f ms at the frame barrier (budget %.1f ms): every render thread waited",
             kind, name, 1e3 * took, 1e3 * PIPELINE_CALLBACK_BUDGET_S);
    pthread_mutex_lock(&p->stats_lock);
    p->stats.slow_callbacks++;
    pthread_mutex_unlock(&p->stats_lock);
}

/* Run the transactions queued before this point, in FIFO order. They run
 * outside queue_lock (they may queue more); the slots stay counted in the
 * queue until they are done, so producers cannot reuse them. */
static void run_transactions(pipeline *p)
{
    pthread_mutex_lock(&p->queue_lock);
    size_t head = p->queue_head, count = p->queue_count;
    pthread_mutex_unlock(&p->queue_lock);
    for (size_t i = 0; i < count; i++) {
        queued_call *c = &p->queue[(head + i) % PIPELINE_QUEUE_MAX];
        double t0 = now_s();
        if (c->fn)
            c->fn(p, c->args.bytes);
        else
            apply_record(p, (const txn_record *)(const void *)c->args.bytes);
        note_duration(p, "transaction", c->name, t0);
    }
    pthread_mutex_lock(&p->queue_lock);
    p->queue_head = (head + count) % PIPELINE_QUEUE_MAX;
    p->queue_count -= count;
    pthread_mutex_unlock(&p->queue_lock);
    pthread_mutex_lock(&p->stats_lock);
    p->stats.transactions_applied += count;
    pthread_mutex_unlock(&p->stats_lock);
}

/* Run the one-shots due at `frame` (or earlier), in the order they were queued. */
static void run_oneshots(pipeline *p, uint64_t frame)
{
    size_t due = 0;
    pthread_mutex_lock(&p->queue_lock);
    size_t kept = 0;
    for (size_t i = 0; i < p->oneshot_count; i++) {
        if (p->oneshots[i].due_frame <= frame)
            p->oneshot_scratch[due++] = p->oneshots[i];
        else
            p->oneshots[kept++] = p->oneshots[i];
    }
    p->oneshot_count = kept;
    pthread_mutex_unlock(&p->queue_lock);
    for (size_t i = 0; i < due; i++) {
        queued_call *c = &p->oneshot_scratch[i];
        double t0 = now_s();
        c->fn(p, c->args.bytes);
        note_duration(p, "one-shot callback", c->name, t0);
    }
}

static void run_serial_animation(pipeline *p)
{
    /* a callback may register another (it runs from the next frame): iterate over a copy */
    serial_callback cbs[PIPELINE_MAX_CALLBACKS];
    int n = p->serial_anim_count;
    memcpy(cbs, p->serial_anim, (size_t)n * sizeof cbs[0]);
    for (int i = 0; i < n; i++) {
        double t0 = now_s();
        cbs[i].fn(p, cbs[i].ctx, &p->step.info);
        note_duration(p, "serial animation", cbs[i].name, t0);
    }
}

static void *thread_main(void *arg);

/* Join threads that left the loop at an earlier barrier. */
static void join_departed(pipeline *p, int keep_below)
{
    for (int i = (keep_below > 1 ? keep_below : 1); i < PIPELINE_MAX_THREADS; i++)
        if (p->threads[i].joinable) {
            pthread_join(p->threads[i].handle, NULL);
            p->threads[i].joinable = false;
        }
}

/* Apply threads_wanted: start threads that join this step, or let the
 * highest-numbered ones leave after the barrier. Returns the new count. */
static int change_thread_count(pipeline *p)
{
    int want = p->state.threads, have = p->thread_count;
    if (want == have)
        return have;
    if (want > have) {
        for (int id = have; id < want; id++) {
            render_thread *t = &p->threads[id];
            if (t->joinable) { /* left at an earlier barrier: finish that first */
                pthread_join(t->handle, NULL);
                t->joinable = false;
            }
            memset(&t->counts, 0, sizeof t->counts);
            /* it must not arrive at the frame barrier before the barrier that started it releases */
            t->start_generation = atomic_load(&p->frame_barrier.generation);
            int rc = pthread_create(&t->handle, NULL, thread_main, t);
            if (rc != 0) {
                log_warn("pipeline: could start only %d of %d render threads: %s", id, want, strerror(rc));
                want = id;
                p->state.threads = id; /* serial section: what the state can have */
                break;
            }
            t->joinable = true;
        }
    }
    if (want != have) {
        pthread_mutex_lock(&p->stats_lock);
        p->stats.thread_changes++;
        pthread_mutex_unlock(&p->stats_lock);
        log_debug("pipeline: %d -> %d render threads from frame %llu", have, want,
                  (unsigned long long)p->step.info.frame);
    }
    p->thread_count = want;
    return want;
}

/* Fold in what the previous step did: rays, frames, buffer rotation. */
static void finish_previous_step(pipeline *p)
{
    const loop_step *prev = &p->step;
    render_counts sum = {0};
    double longest_render_s = 0.0, longest_upscale_s = 0.0;
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++) {
        if (p->threads[i].upscale_stage_s > longest_upscale_s)
            longest_upscale_s = p->threads[i].upscale_stage_s;
        p->threads[i].upscale_stage_s = 0.0;
        render_counts *c = &p->threads[i].counts;
        sum.primary_rays += c->primary_rays;
        sum.primary_hits += c->primary_hits;
        sum.shadow_rays += c->shadow_rays;
        sum.secondary_rays += c->secondary_rays;
        sum.ao_rays += c->ao_rays;
        memset(c, 0, sizeof *c);
        if (p->threads[i].render_stage_s > longest_render_s)
            longest_render_s = p->threads[i].render_stage_s;
        p->threads[i].render_stage_s = 0.0;
    }
    p->last_render_s = longest_render_s;
    p->last_upscale_s = longest_upscale_s;
    pthread_mutex_lock(&p->stats_lock);
    p->stats.rays.primary_rays += sum.primary_rays;
    p->stats.rays.primary_hits += sum.primary_hits;
    p->stats.rays.shadow_rays += sum.shadow_rays;
    p->stats.rays.secondary_rays += sum.secondary_rays;
    p->stats.rays.ao_rays += sum.ao_rays;
    if (prev->render)
        p->stats.frames_rendered++;
    if (prev->render && p->reduced) {
        p->stats.upscale_s += longest_upscale_s;
        p->stats.frames_reduced++;
    }
    if (prev->render && p->governed) {
        const governor_frame *f = &p->frame_plan;
        p->stats.frames_scaled += f->kind == GOVERNOR_FRAME_SCALED;
        p->stats.frames_accumulated += f->kind == GOVERNOR_FRAME_ACCUMULATE;
        p->stats.frames_resolved += f->kind == GOVERNOR_FRAME_RESOLVE;
    }
    if (prev->info.idle)
        p->stats.idle_steps++;
    if (prev->display && prev->frames_queued && !p->display_failed)
        p->stats.frames_displayed++;
    if (prev->display)
        p->stats.display_s += p->display_stage_s;
    pthread_mutex_unlock(&p->stats_lock);
    for (int i = 0; i < p->channel_count; i++) {
        pipe_channel *c = &p->channels[i];
        if (prev->display)
            c->queued_valid = false;
        if (prev->render) { /* on screen <- queued, queued <- pending, pending <- old on screen */
            int old_on_screen = c->on_screen;
            c->on_screen = c->queued;
            c->queued = c->pending;
            c->pending = old_on_screen;
            c->queued_valid = c->buffers[c->queued].rendered;
        }
    }
}

/* Freeze each channel's camera and options for the frame about to render,
 * and give the traverser (a reduced frame: its rung's) the frame's targets. */
static void freeze_frame(pipeline *p)
{
    traverser_target targets[PIPELINE_MAX_CHANNELS];
    const governor_frame *plan = &p->frame_plan;
    const bool accumulate = plan->kind == GOVERNOR_FRAME_ACCUMULATE || plan->kind == GOVERNOR_FRAME_RESOLVE;
    const double scale = p->rung_scale[plan->rung];
    const frame_state *st = &p->state; /* the frame's snapshot: unchanged until the next barrier */
    p->frame_renderer = st->renderer;
    /* private channels: the status line alone (the cursor and pointers are the wall's plane
     * points); made only when some channel is private and on */
    overlay_state private_overlay;
    bool any_private = false;
    for (int i = 0; i < p->channel_count && !any_private; i++)
        any_private = st->private_view[i] && st->active[i];
    if (any_private) {
        private_overlay = p->overlay;
        private_overlay.cursor_visible = false;
        memset(private_overlay.pointer_visible, 0, sizeof private_overlay.pointer_visible);
    }
    uint32_t bands = 0;
    for (int i = 0; i < p->channel_count; i++) {
        pipe_channel *c = &p->channels[i];
        const camera_desc *camera = &st->cameras[i];
        const bool active = st->active[i];
        c->view = (render_view){.scene = p->cfg.scene,
                                .accel = p->cfg.accel,
                                .camera = camera_basis_window(camera, c->plane_aspect, c->window, c->width_px,
                                                              c->height_px),
                                .shadows = st->shadows,
                                .shading = st->renderer->shading,
                                .state = st,
                                .settings = &p->cfg.settings}; /* fixed: the pipeline's copy */
        frame_buffer *b = &c->buffers[c->pending];
        b->meta = (frame_image){b->rgb, c->width_px, c->height_px, p->step.info.frame, p->step.info.time_s, i,
                                *camera, st->camera_serials[i], p->reduced ? scale : 1.0,
                                p->governed ? plan->samples : p->cfg.sampler.kind == PIXEL_SAMPLER_SINGLE
                                                                  ? 1
                                                                  : p->cfg.sampler.k * p->cfg.sampler.k};
        b->rendered = active;
        image_display *sink = c->display->ops->write_tile ? c->display : NULL;
        c->overlay_on = overlay_plan_make(&c->overlay, any_private && st->private_view[i] ? &private_overlay : &p->overlay,
                                          c->window, c->width_px, c->height_px);
        if (p->reduced) {
            int w = upscale_low_res_px(c->width_px, scale), h = upscale_low_res_px(c->height_px, scale);
            c->lowres_view = c->view;
            c->lowres_view.camera = camera_basis_window(camera, c->plane_aspect, c->window, w, h);
            targets[i] = (traverser_target){.view = &c->lowres_view, .rgb = active ? c->lowres : NULL,
                                            .img = &b->meta};
            c->first_band = bands;
            if (active)
                bands += (uint32_t)((c->height_px + p->cfg.tile_px - 1) / p->cfg.tile_px);
            continue;
        }
        targets[i] = (traverser_target){.view = &c->view, .rgb = active ? b->rgb : NULL, .sink = sink,
                                        .img = &b->meta, .overlay = c->overlay_on ? &c->overlay : NULL};
        if (accumulate) {
            targets[i].accum = c->accum;
            targets[i].accum_samples = (float)plan->samples;
            targets[i].accum_reset = plan->kind == GOVERNOR_FRAME_ACCUMULATE && plan->stratum == 0;
            targets[i].resolve_only = plan->kind == GOVERNOR_FRAME_RESOLVE;
        }
    }
    if (p->reduced) {
        p->upscale_items = bands;
        atomic_store_explicit(&p->upscale_next, 0, memory_order_relaxed);
        p->rung_traversers[plan->rung]->ops->begin_frame(p->rung_traversers[plan->rung], targets);
    } else
        p->traverser->ops->begin_frame(p->traverser, targets);
}

/* Whether a one-shot is due at `frame` (queue_lock held). One due at a later
 * frame is not work for an idle step: frames do not advance while idle, so
 * waking for it would spin. */
static bool oneshot_due(const pipeline *p, uint64_t frame)
{
    for (size_t i = 0; i < p->oneshot_count; i++)
        if (p->oneshots[i].due_frame <= frame)
            return true;
    return false;
}

/* Governor, real time: the previous step was idle; wait (in the serial
 * section, every render thread asleep at the barrier) until a transaction, a
 * one-shot or a stop arrives, or PIPELINE_IDLE_POLL_S passes (serial
 * animation, e.g. an idle clock, runs then). */
static void wait_while_idle(pipeline *p)
{
    struct timespec until;
    clock_gettime(CLOCK_REALTIME, &until); /* pthread_cond_timedwait's default clock */
    long ns = until.tv_nsec + (long)(PIPELINE_IDLE_POLL_S * 1e9);
    until.tv_sec += ns / 1000000000L;
    until.tv_nsec = ns % 1000000000L;
    pthread_mutex_lock(&p->queue_lock);
    while (p->queue_count == 0 && !oneshot_due(p, p->next_frame) && !atomic_load(&p->stop_requested))
        if (pthread_cond_timedwait(&p->queue_changed, &p->queue_lock, &until) == ETIMEDOUT)
            break;
    pthread_mutex_unlock(&p->queue_lock);
}

/* A reduced frame needs every thread's upscale scratch (made once per thread,
 * here in the serial section); false, logged, when there is no memory for it
 * (the frame is then rendered at full size). */
static bool have_upscale_scratch(pipeline *p, int threads)
{
    for (int i = 0; i < threads; i++)
        if (!p->threads[i].upscale_scratch) {
            p->threads[i].upscale_scratch = malloc(p->upscale_scratch_floats * sizeof(float));
            if (!p->threads[i].upscale_scratch) {
                log_error("pipeline: no memory for upscaling on thread %d: this frame renders at full size", i);
                return false;
            }
        }
    return true;
}

/* A fixed render scale (no governor): every frame at rung 1, with the config's sampler. */
static void plan_fixed_scale_frame(pipeline *p, int threads)
{
    bool scratch = have_upscale_scratch(p, threads);
    p->frame_plan = (governor_frame){GOVERNOR_FRAME_SCALED, scratch ? 1 : 0, 0, 1};
    p->reduced = scratch;
    p->frame_sampler = p->cfg.sampler;
}

/* Governor: feed it what the previous frame cost, plan this one, and make
 * sure the threads have upscale scratch for a reduced frame. Sets
 * frame_plan, frame_sampler and reduced. */
static void plan_governed_frame(pipeline *p, int threads)
{
    const loop_step *s = &p->step;
    if (p->last_step_pixels > 0.0) { /* the previous step rendered: what did it cost? */
        governor_cost cost = p->step_cost_set ? p->step_cost : pipeline_step_cost(p);
        uint64_t over = p->gov.frames_over_budget;
        governor_observe(&p->gov, &p->frame_plan, &cost);
        if (p->gov.frames_over_budget != over) {
            pthread_mutex_lock(&p->stats_lock);
            p->stats.frames_over_budget++;
            pthread_mutex_unlock(&p->stats_lock);
        }
    }
    bool picture_changed = p->state.picture_serial != p->planned_picture_serial || p->parallel_anim_count > 0;
    bool overlay_changed = p->state.overlay_serial != p->planned_overlay_serial;
    governor_mode before = p->gov.mode;
    int rung_before = p->frame_plan.rung;
    p->step_cost_set = false;
    governor_frame f = governor_plan(&p->gov, s->info.time_s, picture_changed, overlay_changed, p->rung_pixels);
    if (p->plan_sync) /* several processes: the leader's plan for all (cluster/) */
        p->plan_sync(p->plan_sync_ctx, s->info.frame, &f);
    if (f.kind == GOVERNOR_FRAME_SCALED && f.rung > 0 && !have_upscale_scratch(p, threads))
        f.rung = 0;
    p->frame_plan = f;
    p->planned_picture_serial = p->state.picture_serial;
    if (p->state.governor_status_shown)
        compose_status(p); /* the line describes this frame's plan */
    /* the drawn text changed while idle: show it */
    if (p->state.overlay_serial != p->planned_overlay_serial && p->frame_plan.kind == GOVERNOR_FRAME_IDLE)
        p->frame_plan.kind = GOVERNOR_FRAME_RESOLVE;
    p->planned_overlay_serial = p->state.overlay_serial;
    f = p->frame_plan;
    p->reduced = f.kind == GOVERNOR_FRAME_SCALED && f.rung > 0;
    p->frame_sampler = f.kind == GOVERNOR_FRAME_ACCUMULATE
                           ? pixel_sampler_stratum(p->cfg.refine_k, p->cfg.sampler.seed, f.stratum)
                           : pixel_sampler_single();
    if (p->gov.mode != before) {
        char line[PIPELINE_STATUS_BYTES];
        governor_describe(&p->gov, &f, line, sizeof line);
        log_info("pipeline: frame %llu: %s", (unsigned long long)s->info.frame, line);
    } else if (f.kind == GOVERNOR_FRAME_SCALED && f.rung != rung_before)
        log_debug("pipeline: frame %llu: governor: scale %.3g -> %.3g (predicted %.1f ms, budget %.1f ms)",
                  (unsigned long long)s->info.frame, p->rung_scale[rung_before], p->rung_scale[f.rung],
                  1e3 * governor_predict_s(&p->gov, f.rung, p->rung_pixels), p->cfg.budget_ms);
    p->last_step_pixels = 0.0;
    if (f.kind == GOVERNOR_FRAME_SCALED || f.kind == GOVERNOR_FRAME_ACCUMULATE) {
        for (int i = 0; i < p->channel_count; i++)
            if (p->state.active[i]) {
                double w = p->channels[i].width_px, h = p->channels[i].height_px;
                if (p->reduced) {
                    w = upscale_low_res_px(p->channels[i].width_px, p->rung_scale[f.rung]);
                    h = upscale_low_res_px(p->channels[i].height_px, p->rung_scale[f.rung]);
                }
                p->last_step_pixels += w * h;
            }
    }
}

/* The serial section of the frame barrier; returns the threads of the next step. */
static int serial_section_steps(pipeline *p)
{
    tls_serial_owner = p;
    join_departed(p, p->thread_count);
    finish_previous_step(p);
    loop_step *s = &p->step;
    if (p->exit_after_step) {
        s->render = s->display = s->animate_parallel = false;
        s->exit = true;
        tls_serial_owner = NULL;
        return -1;
    }
    if (s->info.idle && p->cfg.time_mode == PIPELINE_TIME_REAL) {
        double w0 = now_s();
        wait_while_idle(p);
        p->serial_s -= now_s() - w0; /* waiting for work is not serial work */
    }
    double now = now_s();
    uint64_t frame = p->next_frame, step = p->next_step;
    s->info.frame = frame;
    s->info.idle = false;
    s->info.last_frame_s = frame == 0 ? 0.0 : now - p->last_serial_s;
    s->info.last_render_s = frame == 0 ? 0.0 : p->last_render_s;
    p->last_serial_s = now;
    if (frame == 0)
        p->start_s = now;
    s->info.time_s = p->cfg.time_mode == PIPELINE_TIME_FIXED_RATE ? (double)step / p->cfg.rate_hz : now - p->start_s;
    s->info.threads = p->thread_count;
    /* a frame that will not render gets no callbacks (a stop asked for by one
     * of this barrier's transactions is seen after them) */
    bool stop = atomic_load(&p->stop_requested) || p->display_failed ||
                (p->cfg.max_frames > 0 && step >= p->cfg.max_frames);
    if (!stop) {
        run_transactions(p);
        run_oneshots(p, frame);
        run_serial_animation(p);
        stop = atomic_load(&p->stop_requested);
    }
    if (p->frame_sync) /* where processes meet: the leader's time, records and stop (cluster/) */
        p->frame_sync(p->frame_sync_ctx, p, &s->info, &stop);
    /* visibility changed by this barrier's records reaches the accel: one pass over the ids
     * they touched, accel_set_hidden only where a flag differs */
    frame_state_sync_accel(&p->state, p->cfg.accel);
    if (!p->closed_prepared && p->cfg.settings.caps && clip_planes_on(frame_state_clip_planes(&p->state))) {
        /* caps ask which parts are closed: answered here for all of them, not by a render thread mid-frame */
        scene_prepare_closed(p->cfg.scene, p->state.threads);
        p->closed_prepared = true;
    }
    bool any_queued = false;
    for (int i = 0; i < p->channel_count; i++)
        any_queued = any_queued || p->channels[i].queued_valid;
    /* displays with an end_stage hook are served every step, frames or not (a wall
     * whose monitors are all unplugged still has to notice one coming back) */
    s->frames_queued = any_queued;
    /* with a display sync (a wall of several machines) the display stage runs every step also
     * after a display failed: its barrier is one the other processes wait at */
    s->display = (any_queued || (!stop && p->displays_every_stage) || p->display_sync) &&
                 (!p->display_failed || p->display_sync);
    if (stop) {
        s->render = s->animate_parallel = false;
        p->exit_after_step = true;
        s->exit = !s->display; /* nothing left to show: leave now */
        tls_serial_owner = NULL;
        return -1;
    }
    int threads = change_thread_count(p);
    s->info.threads = threads;
    s->exit = false;
    p->next_step = step + 1;
    if (p->governed) {
        plan_governed_frame(p, threads);
        if (p->frame_plan.kind == GOVERNOR_FRAME_IDLE) {
            s->info.idle = true;
            s->render = s->animate_parallel = false;
            tls_serial_owner = NULL;
            return threads;
        }
    } else if (p->fixed_scale)
        plan_fixed_scale_frame(p, threads);
    if (p->reduced)
        barrier_set_participants(&p->upscale_barrier, threads);
    s->render = true;
    s->animate_parallel = p->parallel_anim_count > 0;
    if (s->animate_parallel)
        barrier_set_participants(&p->anim_barrier, threads);
    freeze_frame(p);
    p->next_frame = frame + 1;
    tls_serial_owner = NULL;
    return threads;
}

/* The serial section, its log lines kept for thread 0 (flush_barrier_log). */
static int serial_section(pipeline *p)
{
    double t0 = now_s();
    /* the previous barrier's release: when its last thread left (threads that left the
     * loop there, or started then, have an older or no timestamp and do not count) */
    if (p->serial_end_s > 0.0) {
        double last = p->serial_end_s;
        for (int i = 0; i < p->released_threads; i++)
            if (p->threads[i].left_barrier_s > last)
                last = p->threads[i].left_barrier_s;
        p->release_s += last - p->serial_end_s;
    }
    log_divert_thread(keep_barrier_log, p);
    int threads = serial_section_steps(p);
    log_divert_thread(NULL, NULL);
    p->serial_end_s = now_s();
    p->serial_s += p->serial_end_s - t0;
    p->serial_sections++;
    p->released_threads = threads > 0 ? threads : p->thread_count;
    return threads;
}

/* ---------------------------------------------------------------- the stages */

/* A display's show or end_stage failed: the run stops with its error. */
static void display_failed(pipeline *p, const image_display *d, tess_error *err)
{
    if (!tess_error_is_set(err))
        tess_error_set(err, "display '%s' failed without a reason", d->ops->name);
    p->display_error = *err;
    p->display_failed = true;
}

static void display_stage(pipeline *p)
{
    double t0 = now_s();
    for (int i = 0; i < p->channel_count && !p->display_failed; i++) {
        pipe_channel *c = &p->channels[i];
        if (!c->queued_valid)
            continue;
        tess_error err = {{0}};
        if (!c->display->ops->show(c->display, &c->buffers[c->queued].meta, &err))
            display_failed(p, c->display, &err);
    }
    for (int i = 0; i < p->channel_count && !p->display_failed; i++) {
        image_display *d = p->channels[i].display;
        tess_error err = {{0}};
        if (d->ops->settle_stage && !d->ops->settle_stage(d, &err))
            display_failed(p, d, &err);
    }
    /* the frame lock: every process here before a flip, also one whose display failed (it
     * shows nothing more, but the others wait at this barrier; its stop reaches them through
     * the next frame sync, so that all stop at the same step) */
    if (p->display_sync) {
        uint64_t shown = UINT64_MAX;
        for (int i = 0; i < p->channel_count && shown == UINT64_MAX && !p->display_failed; i++)
            if (p->channels[i].queued_valid)
                shown = p->channels[i].buffers[p->channels[i].queued].meta.frame;
        tess_error err = {{0}};
        if (!p->display_sync(p->display_sync_ctx, shown, &err) && !p->display_failed) { /* the first error stays */
            if (!tess_error_is_set(&err))
                tess_error_set(&err, "the display sync failed without a reason");
            p->display_error = err;
            p->display_failed = true;
        }
    }
    for (int i = 0; i < p->channel_count && !p->display_failed; i++) {
        image_display *d = p->channels[i].display;
        tess_error err = {{0}};
        if (d->ops->end_stage && !d->ops->end_stage(d, &err))
            display_failed(p, d, &err);
    }
    p->display_stage_s = now_s() - t0;
}

/* The dynamically balanced stage: the traverser hands out the frame's work. */
/* A reduced frame's second half: bands of tile_px output rows, upscaled from
 * the channel's low-res frame, then the overlay and write_tile per tile. */
static void upscale_stage(pipeline *p, render_thread *t)
{
    const int tile_px = p->cfg.tile_px, rung = p->frame_plan.rung;
    for (;;) {
        uint32_t item = atomic_fetch_add_explicit(&p->upscale_next, 1, memory_order_relaxed);
        if (item >= p->upscale_items)
            return;
        int ci = 0; /* first_band ascends; a channel switched off has no bands (its first equals the next's) */
        while (ci + 1 < p->channel_count && item >= p->channels[ci + 1].first_band)
            ci++;
        pipe_channel *c = &p->channels[ci];
        frame_buffer *b = &c->buffers[c->pending];
        int y0 = (int)(item - c->first_band) * tile_px;
        int y1 = y0 + tile_px < c->height_px ? y0 + tile_px : c->height_px;
        upscale_plan_rows(c->plans[rung], c->lowres, b->rgb, y0, y1, t->upscale_scratch);
        image_display *sink = c->display->ops->write_tile ? c->display : NULL;
        for (int x0 = 0; x0 < c->width_px; x0 += tile_px) {
            int x1 = x0 + tile_px < c->width_px ? x0 + tile_px : c->width_px;
            if (c->overlay_on)
                overlay_draw(&c->overlay, c->width_px, x0, y0, x1, y1, b->rgb);
            if (sink)
                sink->ops->write_tile(sink, &b->meta, x0, y0, x1, y1);
        }
    }
}

/* The dynamically balanced stage: the traverser hands out the frame's work
 * (a reduced frame: its rung's traverser, the upscale barrier, upscaling). */
static void render_stage(pipeline *p, render_thread *t)
{
    render_counts counts = {0}; /* on this thread's stack: no shared cache line per packet */
    double t0 = now_s();
    if (p->reduced) {
        image_traverser *lowres = p->rung_traversers[p->frame_plan.rung];
        lowres->ops->render(lowres, p->frame_renderer, &p->frame_sampler, &counts);
        barrier_wait(&p->upscale_barrier, p, NULL);
        double t1 = now_s();
        upscale_stage(p, t);
        t->upscale_stage_s = now_s() - t1;
    } else
        p->traverser->ops->render(p->traverser, p->frame_renderer, &p->frame_sampler, &counts);
    t->render_stage_s = now_s() - t0;
    t->counts = counts;
}

/* Steps 2-4 of the current loop step, then the next frame barrier. Returns
 * when this thread leaves the loop. */
static void frame_loop(render_thread *t)
{
    pipeline *p = t->p;
    for (;;) {
        const loop_step *s = &p->step;
        if (t->id == 0) /* the last barrier's log lines: written here, while nobody waits */
            flush_barrier_log(p);
        if (s->exit || t->id >= s->info.threads)
            return;
        if (s->animate_parallel) {
            for (int i = 0; i < p->parallel_anim_count; i++)
                p->parallel_anim[i].fn(p, p->parallel_anim[i].ctx, &s->info, t->id, s->info.threads);
            barrier_wait(&p->anim_barrier, p, NULL);
        }
        if (t->id == 0 && s->display)
            display_stage(p);
        if (s->render)
            render_stage(p, t);
        double arrived = now_s();
        barrier_wait(&p->frame_barrier, p, serial_section);
        t->left_barrier_s = now_s();
        t->barrier_s += t->left_barrier_s - arrived;
    }
}

/* A thread started in a serial section: it joins the step that section prepares. */
static void *thread_main(void *arg)
{
    render_thread *t = arg;
    thread_name_set("tess-render-%d", t->id);
    barrier *b = &t->p->frame_barrier;
    pthread_mutex_lock(&b->lock);
    while (atomic_load(&b->generation) == t->start_generation)
        pthread_cond_wait(&b->released, &b->lock);
    pthread_mutex_unlock(&b->lock);
    frame_loop(t);
    return NULL;
}

/* Reduced frames (a governor, or a fixed render scale): per rung above 0 a
 * tiled traverser of the low-res sizes and each channel's upscale plan, the
 * low-res buffers (rung 1 is the largest) and, with a governor, the
 * accumulation buffers. pipeline_run, before the loop; per-thread scratch
 * comes later (have_upscale_scratch). */
static bool reduced_setup(pipeline *p, const int *widths, const int *heights, tess_error *err)
{
    const char *who = p->governed ? "governor" : "render scale";
    for (int r = 1; r < p->rung_count; r++) {
        int low_w[PIPELINE_MAX_CHANNELS], low_h[PIPELINE_MAX_CHANNELS];
        for (int i = 0; i < p->channel_count; i++) {
            low_w[i] = upscale_low_res_px(widths[i], p->rung_scale[r]);
            low_h[i] = upscale_low_res_px(heights[i], p->rung_scale[r]);
        }
        p->rung_traversers[r] = traverser_tiled_create(p->cfg.tile_px, p->cfg.order, p->cfg.order_seed, low_w, low_h,
                                                       p->channel_count, err);
        if (!p->rung_traversers[r])
            return false;
        for (int i = 0; i < p->channel_count; i++) {
            pipe_channel *c = &p->channels[i];
            c->plans[r] = upscale_plan_create(low_w[i], low_h[i], widths[i], heights[i], p->cfg.upscale, err);
            if (!c->plans[r]) {
                tess_error_prefix(err, "pipeline: %s: channel %d: ", who, i);
                return false;
            }
            size_t need = upscale_plan_scratch_floats(c->plans[r]);
            if (need > p->upscale_scratch_floats)
                p->upscale_scratch_floats = need;
        }
    }
    for (int i = 0; i < p->channel_count; i++) {
        pipe_channel *c = &p->channels[i];
        size_t full = (size_t)widths[i] * (size_t)heights[i] * 3;
        size_t low = (size_t)upscale_low_res_px(widths[i], p->rung_scale[1]) *
                     (size_t)upscale_low_res_px(heights[i], p->rung_scale[1]) * 3;
        c->lowres = calloc(low, sizeof(float));
        if (p->governed)
            c->accum = calloc(full, sizeof(float));
        if (!c->lowres || (p->governed && !c->accum))
            return tess_error_set(err, "pipeline: %s: channel %d: out of memory for its %dx%d buffers", who, i,
                                  widths[i], heights[i]);
    }
    return true;
}

/* The governor (budget_ms > 0) or a fixed render scale (render_scale < 1):
 * the rungs in use, the governor's state, the buffers. */
static bool scale_setup(pipeline *p, const int *widths, const int *heights, tess_error *err)
{
    if (p->cfg.budget_ms > 0.0) {
        governor_config g = {p->cfg.budget_ms * 1e-3, p->cfg.still_s, p->cfg.refine_k};
        double output_pixels = 0.0;
        for (int i = 0; i < p->channel_count; i++)
            output_pixels += (double)widths[i] * (double)heights[i];
        governor_init(&p->gov, &g, output_pixels);
        for (int r = 0; r < GOVERNOR_RUNGS; r++) {
            p->rung_pixels[r] = governor_rung_pixels(r, widths, heights, p->channel_count);
            p->rung_scale[r] = GOVERNOR_SCALES[r];
        }
        p->rung_count = GOVERNOR_RUNGS;
        p->governed = true;
        p->frame_sampler = pixel_sampler_single();
    } else if (p->cfg.render_scale < 1.0) {
        p->rung_scale[0] = 1.0;
        p->rung_scale[1] = p->cfg.render_scale;
        p->rung_count = 2;
        p->fixed_scale = true;
    } else
        return true;
    if (!reduced_setup(p, widths, heights, err))
        return false;
    p->frame_plan = (governor_frame){GOVERNOR_FRAME_SCALED, 0, 0, 1};
    if (p->governed)
        log_info("pipeline: governor: budget %.1f ms, scales 1..%.3g (%s upscaling), refining to jittered:%d after "
                 "%.2f s still",
                 p->cfg.budget_ms, GOVERNOR_SCALES[GOVERNOR_RUNGS - 1], upscale_filter_name(p->cfg.upscale),
                 p->cfg.refine_k, p->cfg.still_s);
    return true;
}

bool pipeline_run(pipeline *p, tess_error *err)
{
    if (tls_serial_owner == p) {
        log_error("pipeline_run: called from inside the pipeline (a transaction or serial callback): refused");
        return tess_error_set(err, "pipeline_run: called from inside the pipeline");
    }
    if (p->ran)
        return tess_error_set(err, "pipeline_run: the pipeline has already run");
    if (p->channel_count == 0)
        return tess_error_set(err, "pipeline: no channels to render");
    int widths[PIPELINE_MAX_CHANNELS], heights[PIPELINE_MAX_CHANNELS];
    for (int i = 0; i < p->channel_count; i++) {
        widths[i] = p->channels[i].width_px;
        heights[i] = p->channels[i].height_px;
        p->displays_every_stage = p->displays_every_stage || p->channels[i].display->ops->end_stage != NULL;
    }
    p->traverser = traverser_tiled_create(p->cfg.tile_px, p->cfg.order, p->cfg.order_seed, widths, heights,
                                          p->channel_count, err);
    if (!p->traverser)
        return false;
    if (!scale_setup(p, widths, heights, err))
        return false;
    p->ran = true;
    atomic_store(&p->running, true);
    double t0 = now_s();
    /* the first barrier has this thread alone: its serial section starts the others */
    p->thread_count = 1;
    barrier_set_participants(&p->frame_barrier, 1);
    barrier_wait(&p->frame_barrier, p, serial_section);
    frame_loop(&p->threads[0]);
    join_departed(p, 1);
    double barrier_s = 0.0; /* every thread has been joined: their totals are final */
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++)
        barrier_s += p->threads[i].barrier_s;
    double run_s = now_s() - t0;
    /* what is still queued will never run: count it (every accepted transaction is
     * applied or discarded), and empty the queue so the counts stay exact */
    pthread_mutex_lock(&p->queue_lock);
    p->closed = true;
    size_t discarded = p->queue_count;
    p->queue_head = (p->queue_head + p->queue_count) % PIPELINE_QUEUE_MAX;
    p->queue_count = 0;
    pthread_mutex_unlock(&p->queue_lock);
    if (discarded)
        log_info("pipeline: %zu transaction%s queued before the stop not applied (the loop had ended)", discarded,
                 discarded == 1 ? "" : "s");
    for (int i = 0; i < p->termination_count; i++)
        p->terminations[i].fn(p, p->terminations[i].ctx);
    atomic_store(&p->running, false);
    pthread_mutex_lock(&p->stats_lock);
    p->stats.run_s = run_s;
    p->stats.barrier_s = barrier_s;
    p->stats.serial_s = p->serial_s;
    p->stats.release_s = p->release_s;
    p->stats.serial_sections = p->serial_sections;
    p->stats.transactions_discarded += discarded;
    pthread_mutex_unlock(&p->stats_lock);
    if (p->display_failed)
        return tess_error_set(err, "%s", p->display_error.msg);
    return true;
}

void pipeline_destroy(pipeline *p)
{
    if (!p)
        return;
    if (tls_serial_owner == p || atomic_load(&p->running)) {
        log_error("pipeline_destroy: the pipeline is running; refused (stop it and let pipeline_run return)");
        return;
    }
    for (int i = 0; i < p->channel_count; i++)
        channel_free(&p->channels[i]);
    image_traverser_destroy(p->traverser);
    barrier_destroy(&p->frame_barrier);
    barrier_destroy(&p->anim_barrier);
    barrier_destroy(&p->upscale_barrier);
    for (int r = 0; r < GOVERNOR_RUNGS; r++)
        image_traverser_destroy(p->rung_traversers[r]);
    for (int i = 0; i < PIPELINE_MAX_THREADS; i++)
        free(p->threads[i].upscale_scratch);
    pthread_cond_destroy(&p->queue_changed);
    pthread_mutex_destroy(&p->queue_lock);
    pthread_mutex_destroy(&p->stats_lock);
    free(p->queue);
    free(p->oneshots);
    free(p->oneshot_scratch);
    frame_state_finish(&p->state);
    free(p);
}
