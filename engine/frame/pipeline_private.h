/* pipeline_private.h - the insides of the frame pipeline: struct pipeline, the
 * structs it holds, and the functions one of its files calls in another.
 * PRIVATE to engine/frame/pipeline*.c: only those files include it. Every
 * other user, in engine/frame or outside it, goes through pipeline.h, whose
 * model (the frame loop, the three buffers, transactions and records, the
 * governor) these comments assume. The comments on the fields say which lock
 * or which stage guards each.
 *
 * The pipeline's files, one job each:
 *   pipeline.c          its life: create, run (the traversers and the governor's
 *                       or render scale's buffers made first), destroy
 *   pipeline_barrier.c  the barrier whose last arriving thread runs a function
 *   pipeline_config.c   what it is given: the config's defaults and checks,
 *                       channels, cluster hooks, callbacks
 *   pipeline_queue.c    queueing (transactions, one-shots, the stop) and the
 *                       records: checked, queued (pipeline_queue_*), applied
 *                       at once (pipeline_apply)
 *   pipeline_state.c    the frame state: the one place a record changes it,
 *                       the setters (pipeline_set_*), what may be read of it
 *   pipeline_serial.c   the serial section at the frame barrier: the previous
 *                       step folded in, transactions, one-shots and serial
 *                       animation run, thread-count changes, the governor's
 *                       plan, the frame frozen
 *   pipeline_stages.c   what runs between barriers: the display stage, the
 *                       render stage (and upscaling), each thread's loop */
#ifndef TESSERA_PIPELINE_PRIVATE_H
#define TESSERA_PIPELINE_PRIVATE_H

#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "pipeline.h"
#include "engine/base/clock.h"
#include "engine/render/overlay.h"
#include "engine/scene/frame_state.h"

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
    double left_barrier_s; /* when it last left the frame barrier (pipeline_now_s); written by this thread,
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
    double serial_end_s;      /* when the last serial section ended (pipeline_now_s), 0 before the first */
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

/* The pipeline's clock (seconds, monotonic): every duration and timestamp here. */
static inline double pipeline_now_s(void) { return clock_monotonic_s(); }

/* pipeline_barrier.c: a barrier starts with one participant */
void pipeline_barrier_init(barrier *b);
void pipeline_barrier_destroy(barrier *b);
/* All participants arrive; the last runs serial(p) (NULL: nothing) before any leaves. */
void pipeline_barrier_wait(barrier *b, pipeline *p, int (*serial)(pipeline *p));
/* Only while nobody waits at b. */
void pipeline_barrier_set_participants(barrier *b, int participants);

/* pipeline_config.c */
/* An initial plane of the config that is unused (a zeroed entry). */
bool pipeline_plane_unused(const clip_plane *c);
/* The record that sets plane `index` as the config gives it. */
txn_record pipeline_plane_record(int index, const clip_plane *c);
/* Frees what a channel holds (its display included); the struct itself is the pipeline's. */
void pipeline_channel_free(pipe_channel *c);

/* pipeline_state.c */
/* In the serial section or while no loop runs; else logs and refuses. */
bool pipeline_may_change_state(const pipeline *p, const char *what);
/* Applies a record and what follows from it (the drawn overlay, the accel's flags);
 * callers: the serial section, or no loop runs. false, logged, where txn_apply refuses it. */
bool pipeline_apply_record(pipeline *p, const txn_record *r);
/* overlay.status from the state's status and the governor's line. */
void pipeline_compose_status(pipeline *p);

/* pipeline_serial.c */
/* The frame barrier's function: returns the threads of the next step (-1: the same). */
int pipeline_serial_section(pipeline *p);
/* Joins the threads from keep_below up (at least 1) that left the loop. */
void pipeline_join_departed(pipeline *p, int keep_below);

/* pipeline_stages.c */
/* A thread's loop steps until it leaves the loop (thread 0: the thread that called pipeline_run). */
void pipeline_frame_loop(render_thread *t);
/* A thread the serial section starts (pthread_create's function; arg: its render_thread). */
void *pipeline_thread_main(void *arg);

#endif
