/* pipeline.h - the parallel rendering pipeline (Manta's architecture): N
 * render threads run a frame loop, meet only at the frame barrier, and every
 * change of renderer state is a transaction run at that barrier.
 *
 * FRAME LOOP. Step f of the loop, on every render thread:
 *   1. frame barrier. The last thread to arrive runs the serial section while
 *      the others wait: buffers rotate (below), frame f's time is set, queued
 *      transactions run in FIFO order, then one-shot callbacks due at frame f,
 *      then serial animation callbacks; hidden-geometry changes reach the
 *      accel; the thread count may change; the frame state (below) is frozen
 *      as frame f's snapshot; the tile counter is reset.
 *   2. parallel animation callbacks (inherently balanced work), each called on
 *      every thread with (thread, threads). Only when some are registered, a
 *      second barrier follows, because rendering reads what they write; a
 *      pipeline without them pays nothing.
 *   3. thread 0 hands frame f-1 of every channel to its display (imbalanced
 *      work), then calls each display's end_stage hook (display.h), and joins
 *      step 4.
 *   4. rendering of frame f (dynamically balanced): threads take tiles from
 *      one atomic counter over the tiles of every channel until none is left.
 * So the display of frame f-1 overlaps the rendering of frame f.
 *
 * BUFFERS. Each channel has three frame buffers, each in one state:
 *   PENDING   being rendered (frame f); written by render threads in step 4;
 *   QUEUED    finished (frame f-1), waiting for / being handed to the display;
 *             read by the display thread in step 3;
 *   ON SCREEN handed to the display before (frame f-2); nobody writes it, so
 *             a display may keep showing it (scan-out) until it is replaced.
 * The serial section rotates them: on screen <- queued, queued <- pending,
 * pending <- old on screen. Only the serial section changes states, so a
 * buffer's owner never changes while anybody touches it.
 *
 * FRAME STATE. Everything transactions change between frames lives in one
 * versioned object owned by the pipeline (frame_state.h): per-channel
 * cameras (with change serials) and active flags, the thread count, the
 * overlay's inputs (status text, cursor, governor line shown), render
 * options (renderer, shadows), the global opacity and cutting planes, and
 * per-geometry visibility, highlight, colour and opacity (arrays allocated
 * only when a scene first uses them). It starts from the config (renderer,
 * shadows, threads, opacity, cutting planes). It is
 * written only in the serial section (or while no loop runs), so the state
 * at a barrier is that frame's SNAPSHOT: render threads read it through a
 * const pointer (render_view.state, pipeline_frame_state) without locks, and
 * a change queued while frame f renders shows from frame f+1, never in the
 * middle of a frame. The renderer and shadows of a frame come from it.
 *
 * TRANSACTIONS. Any thread may queue a transaction, in one FIFO of two forms:
 *   - a RECORD (txn.h: a kind and its arguments by value, pipeline_submit):
 *     validated when queued (its own checks, then this pipeline's geometry
 *     and channel ranges), applied to the frame state at the barrier
 *     (txn_apply), so it can be recorded, replayed and sent to another
 *     process. Every built-in setting is a record: the pipeline_queue_*
 *     calls build one and submit it, the pipeline_set_* setters build one and
 *     apply it at once (pipeline_apply), so one path changes the state;
 *   - a CALLBACK plus a copy of up to PIPELINE_ARGS_MAX bytes of arguments
 *     (pipeline_transaction), for what needs arbitrary code (tests, the input
 *     sink's camera mailbox and tour).
 * The serial section runs them in the order they were queued (the order
 * between two queueing threads is the order their calls took the queue
 * lock). While it runs, no render thread touches renderer state, so a
 * callback may change anything: the frame state (through pipeline_apply or
 * the setters), thread count, callbacks. What it logs (log.h) is kept and
 * written by render thread 0 after the barrier.
 * A transaction (and any serial callback) MUST NOT
 *   - block: no waiting on locks other threads hold across frames, on I/O that
 *     may stall, on frames (it runs inside the frame the others wait for);
 *   - take long: every render thread waits for it. Each callback is timed;
 *     one over PIPELINE_CALLBACK_BUDGET_S is logged with its name and counted
 *     (pipeline_stats.slow_callbacks);
 *   - keep pointers to its argument copy after returning (the slot is reused);
 *   - call pipeline_run or pipeline_destroy (refused: they return an error).
 * Enforced: argument size and queue length (pipeline_transaction and
 * pipeline_submit return false), the state setters and pipeline_apply run
 * only inside the serial section or while no loop runs (called anywhere
 * else they log an error and return false), the time budget (logged
 * and counted), no re-entry of pipeline_run. Transactions queued while the
 * serial section runs (by a transaction) run at the next frame's barrier, so
 * one barrier always ends.
 *
 * TIME. PIPELINE_TIME_REAL: frame f's time is the monotonic clock at its
 * serial section minus the time at the first one. PIPELINE_TIME_FIXED_RATE:
 * frame f's time is f / rate_hz exactly, whatever the speed, so output is
 * reproducible. Either way frames render as fast as the threads allow.
 *
 * OVERLAY AND HIDING. Each channel's tiles get the overlay (overlay.h: a
 * status line at the plane's bottom-left corner, a cursor, both in plane
 * coordinates, drawn by every channel they fall on) composited right after
 * they are rendered, before a display's write_tile sees them. Geometries may
 * be hidden (accel.h: not seen, no shadows, not hit by any accel query): the
 * frame state says which, and at the end of each serial section the accel's
 * flags are brought in line (accel_set_hidden only where a flag differs,
 * accel_unhide_all after a show-all). Both change only through transactions
 * or in the serial section, like the rest of the state; a pipeline with
 * neither pays one branch per tile.
 *
 * DETERMINISM. A pixel's value depends on the scene (with its hidden
 * geometries), the channel's camera, the sampler, the renderer and the
 * overlay only (with the governor also on its plan for the frame, below):
 * never on the thread count, the tile size or the tile order.
 *
 * GOVERNOR (config budget_ms > 0; engine/frame/governor.h decides, this carries
 * out). Every frame has one plan for all channels, made in the serial section
 * after the transactions and serial animation:
 *   - a moving picture renders one ray per pixel at the ladder scale the cost
 *     model picks: each channel's low-res image (upscale.h, RENDER SCALE; the
 *     same scale on every output of a wall, so no seams between monitors) is
 *     rendered by the render threads from a tiled traverser of its own, then,
 *     after the upscale barrier (only frames at a reduced scale have it), the
 *     threads upscale bands of tile_px output rows (upscale_plan_rows) handed
 *     out by an atomic counter, composite the overlay and give each tile to
 *     write_tile. At scale 1 the frame is the ungoverned one, bit for bit;
 *   - a picture still for still_s seconds of frame time refines: frame n
 *     renders stratum n of jittered:refine_k (sampler.h, STRATUM) and adds it
 *     to the channel's accumulation buffer; it shows the mean so far. After
 *     refine_k^2 frames the picture is jittered:refine_k's, bit for bit;
 *   - a converged picture renders nothing: such a loop step is IDLE (no frame
 *     number is used, no display gets a frame, parallel animation is skipped;
 *     serial animation and transactions still run). In real time an idle step
 *     first waits up to PIPELINE_IDLE_POLL_S for a transaction, a one-shot due or
 *     a stop, so an idle wall costs no CPU; an overlay change alone makes one
 *     RESOLVE frame (the converged mean, new overlay, no rays).
 * What counts as a change of the picture: a record that bumps the frame
 * state's picture_serial (a different camera, a channel switched, visibility,
 * highlight, colour, shadows or renderer changed; frame_state.h), and any
 * registered parallel animation (it may change anything rendering reads, every frame).
 * The attract tour and camera paths change the camera every frame, so they
 * count as movement. max_frames counts loop steps, idle ones included, and
 * in PIPELINE_TIME_FIXED_RATE time is steps / rate_hz (without the governor
 * both are frames, as before). A governor costs nothing when off: no
 * buffers, no upscale barrier, the same frames.
 *
 * RENDER SCALE (config render_scale < 1, no governor): every frame is a
 * reduced frame as above at that one scale, with the config's sampler. */
#ifndef TESSERA_PIPELINE_H
#define TESSERA_PIPELINE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/accel/clip.h"
#include "engine/render/display.h"
#include "engine/base/err.h"
#include "governor.h"
#include "engine/render/render.h"
#include "engine/render/sampler.h"
#include "engine/render/tile_order.h"
#include "engine/render/traverser.h"
#include "txn.h"
#include "engine/render/upscale.h"

struct scene;
struct accel;
struct frame_state;

#define PIPELINE_MAX_THREADS 256
#define PIPELINE_MAX_CHANNELS 16
#define PIPELINE_ARGS_MAX 256            /* bytes of transaction arguments copied */
#define PIPELINE_QUEUE_MAX 4096          /* transactions waiting at once */
#define PIPELINE_CALLBACK_BUDGET_S 0.002 /* a transaction or serial callback taking longer is logged */
#define PIPELINE_MAX_CALLBACKS 64        /* animation + termination callbacks of each kind */
#define PIPELINE_TILE_PX_MIN 4
#define PIPELINE_TILE_PX_MAX 256
#define PIPELINE_STATUS_BYTES 128        /* status line text, with its terminating NUL */
#define PIPELINE_BARRIER_LOG_BYTES 16384 /* log text one serial section may leave for thread 0 to write */
#define PIPELINE_IDLE_POLL_S 0.05        /* governor, real time: an idle step waits this long for work */

typedef struct pipeline pipeline;

typedef enum pipeline_time_mode {
    PIPELINE_TIME_REAL,
    PIPELINE_TIME_FIXED_RATE,
} pipeline_time_mode;

/* What stays fixed for a pipeline's life (components chosen by name are
 * resolved into this by the caller; see app). */
typedef struct pipeline_config {
    const struct scene *scene; /* read-only while the pipeline exists */
    const struct accel *accel; /* built from scene */
    int threads;               /* initial render threads, the caller's included; 1..PIPELINE_MAX_THREADS */
    pipeline_time_mode time_mode;
    double rate_hz;            /* FIXED_RATE: frames per second of pipeline time, > 0 */
    uint64_t max_frames;       /* frames to render and display, then stop; 0: until pipeline_stop */
    /* image traverser "tiled" (traverser.h): square tiles handed out by one atomic counter */
    int tile_px;               /* PIPELINE_TILE_PX_MIN..MAX */
    tile_order order;
    uint32_t order_seed;       /* for TILE_ORDER_SHUFFLE */
    pixel_sampler sampler;
    const renderer *renderer;  /* renderer_by_name: "raytracer" or "eyelight" */
    bool shadows;
    /* the governor (GOVERNOR above): off when budget_ms is 0; then `sampler`
     * is every frame's, else frames moving use one ray per pixel and still
     * ones converge to jittered:refine_k with the sampler's seed */
    double budget_ms;          /* frame-time budget, >= 0 */
    double still_s;            /* still this long (frame time) before refining */
    int refine_k;              /* 1..PIXEL_SAMPLER_MAX_K */
    upscale_filter upscale;    /* how reduced frames are enlarged */
    /* without a governor: every frame rendered at this scale of its channel's
     * size (upscale.h, RENDER SCALE) with `sampler`, upscaled as the governor's
     * reduced frames are; (0, 1], 1 = full size; < 1 only with budget_ms 0 */
    double render_scale;
    /* inspection: how far transparency, caps and ambient occlusion go, fixed for the
     * pipeline's life (the pipeline keeps its copy; every render view it builds points at it:
     * render_view.settings), and where the frame state's opacity and planes start */
    render_settings settings;  /* ranges: pipeline_config_validate (PIPELINE_*_MAX below) */
    float opacity;             /* initial global opacity, [0, 1] */
    clip_plane clip[CLIP_MAX_PLANES]; /* initial cutting planes: an entry that is off with a zero
                                  normal is unused; any other must pass as a clip-plane record
                                  (txn.h: finite point, nonzero normal) and is applied as one
                                  (the normal normalised) */
} pipeline_config;

/* Bounds of render_settings (render.h) a config may ask for; each a cost bound:
 * the work per ray grows with them. */
#define PIPELINE_MAX_LAYERS_MAX 64   /* transparent layers blended along one ray */
#define PIPELINE_AO_RAYS_MAX 64      /* ambient occlusion rays per hit */
#define PIPELINE_AO_INTERLEAVE_MAX 8 /* K of the K x K direction-set pattern */
#define PIPELINE_AO_FILTER_PX_MAX 9  /* edge of the AO filter (odd) */
#define PIPELINE_AO_FRAMES_MAX 64    /* AO frames averaged per pixel sample */

/* Defaults: 1 thread, real time (rate 30 for FIXED_RATE), no frame limit,
 * 16-pixel tiles in row order, single sample, Phong with shadows, no
 * governor (still_s GOVERNOR_DEFAULT_STILL_S, refine_k
 * GOVERNOR_DEFAULT_REFINE_K, bilinear upscaling when one is asked for),
 * render_settings_default(), opaque, no cutting plane. */
pipeline_config pipeline_config_default(const struct scene *s, const struct accel *a);

/* Check a config; false with err naming the field and the problem. */
bool pipeline_config_validate(const pipeline_config *cfg, tess_error *err);

pipeline *pipeline_create(const pipeline_config *cfg, tess_error *err);

/* Add a viewpoint: a camera, an image size and the display its frames go to
 * (owned by the pipeline from now on, destroyed with it, also on failure).
 * Only before pipeline_run. Returns the channel index, or -1 with err. */
int pipeline_add_channel(pipeline *p, const camera_desc *camera, int width_px, int height_px, image_display *display,
                         tess_error *err);

/* A channel that shows `window` of the image plane of `camera` seen at
 * plane_aspect (width / height): one output of a display wall, an off-axis
 * part of one picture (camera_basis_window). pipeline_add_channel is this with
 * the whole plane at the image's own aspect. */
int pipeline_add_channel_window(pipeline *p, const camera_desc *camera, float plane_aspect, camera_window window,
                                int width_px, int height_px, image_display *display, tess_error *err);

/* Run the frame loop on the calling thread (render thread 0) and the others
 * it starts, until max_frames frames have been displayed, pipeline_stop, or a
 * display fails (then false with its error). The last rendered frame is
 * always displayed before returning. Runs once per pipeline. */
bool pipeline_run(pipeline *p, tess_error *err);

/* Make channel `channel` private (frame_state.h, PRIVATE CHANNELS): a camera
 * record for all channels (the wall's camera) leaves it and it draws no
 * cursor or pointers; a remote viewer's own view (remote/). Only before
 * pipeline_run. False with err. */
bool pipeline_set_channel_private(pipeline *p, int channel, tess_error *err);
/* Put the status line's bottom-left corner at plane point (sx, sy) instead of
 * the bottom-left corner of the channels' windows (a process that drives part
 * of a wall: cluster/, where the line must sit where the whole wall has it).
 * Only before pipeline_run; false when running or not finite. */
bool pipeline_set_status_anchor(pipeline *p, float sx, float sy);

/* Whether channel `channel` is private (fixed once the pipeline runs: any thread). */
bool pipeline_channel_private(const pipeline *p, int channel);

/* Free the pipeline, its channels and their displays. Only when it is not
 * running (never run, or pipeline_run has returned: stop it with
 * pipeline_stop and wait for that); while running it logs and refuses. */
void pipeline_destroy(pipeline *p);

/* ---- transactions and callbacks: any thread, any time (before run too) ---- */

/* Arguments arrive as a pointer to the pipeline's copy, aligned for any type. */
typedef void (*pipeline_fn)(pipeline *p, void *args);

/* Queue fn(p, copy of args) for the next barrier. `name` (a string literal:
 * kept, not copied) names it in logs. False, with a logged reason, when
 * args_bytes > PIPELINE_ARGS_MAX, the queue is full, or pipeline_stop has
 * been called (the loop runs no more transactions then). A transaction
 * accepted just before the stop whose barrier never comes is counted as
 * discarded (pipeline_stats). */
bool pipeline_transaction(pipeline *p, const char *name, pipeline_fn fn, const void *args, size_t args_bytes);

/* Queue fn to run once in the serial section of frame `frame`, after that
 * barrier's transactions and before serial animation; if that frame has
 * already started, at the next barrier. Same limits as pipeline_transaction.
 * With a governor, frame numbers do not advance while it idles: a one-shot
 * due at a later frame waits until the picture changes again. */
bool pipeline_at_frame(pipeline *p, uint64_t frame, const char *name, pipeline_fn fn, const void *args,
                       size_t args_bytes);

/* Ask the loop to stop: the frame being rendered is finished and displayed,
 * then run returns. Any thread; an atomic flag, not a transaction. */
void pipeline_stop(pipeline *p);

/* Whether pipeline_stop was called (any thread: a display waiting for
 * something outside tessera looks here so it never outlasts a stop). */
bool pipeline_stop_requested(const pipeline *p);

/* Queue a transaction record (txn.h) for the next barrier, where it is
 * applied to the frame state in FIFO order with the other transactions.
 * Validated here (txn_validate, then this pipeline's geometry and channel
 * ranges; input-level kinds are refused): false, logged, when invalid or
 * refused as pipeline_transaction is. */
bool pipeline_submit(pipeline *p, const txn_record *r);
/* The same, the refusal logged as coming from `origin` (e.g. "rec.txt:12":
 * the file and line a replayed record came from; NULL: none). */
bool pipeline_submit_from(pipeline *p, const txn_record *r, const char *origin);
/* The checks pipeline_submit makes (txn_validate, this pipeline's instance
 * and channel ranges, an engine kind), without queueing, logging or counting:
 * false with err naming the field. Any thread. */
bool pipeline_check(const pipeline *p, const txn_record *r, tess_error *err);

/* The setting-by-setting calls below build a record and submit it. */

/* A camera change for a channel, as a transaction (what input and camera
 * paths send). The camera is validated here: false with err if invalid. */
bool pipeline_queue_camera(pipeline *p, int channel, const camera_desc *camera, tess_error *err);

/* A thread-count change as a transaction (threads join or leave at the barrier). */
bool pipeline_queue_threads(pipeline *p, int threads);

/* Switch a channel off or on again, as a transaction (a wall output whose
 * monitor was unplugged, or came back). An off channel is not rendered and
 * its display gets no frames (its end_stage hook still runs); it keeps its
 * camera. From the frame after the barrier that applies it. */
bool pipeline_queue_channel_active(pipeline *p, int channel, bool active);

/* The status line as a transaction: `text` is copied (at most
 * PIPELINE_STATUS_BYTES - 1 bytes of it, the rest cut off); bytes outside
 * printable ASCII are drawn as '?'; "" hides the line. False (logged) for a
 * NULL text or when the transaction is refused. */
bool pipeline_queue_status(pipeline *p, const char *text);

/* Show the cursor with its tip at plane point (sx, sy) (camera.h's screen
 * coordinates of the whole wall: [-1, 1]^2; points off the plane are simply
 * not drawn), or hide it, as a transaction. False (logged) for a position
 * that is not finite or when the transaction is refused. */
bool pipeline_queue_cursor(pipeline *p, bool visible, float sx, float sy);

/* Show the governor's state (mode, scale, samples) as the status line, after
 * any status text of pipeline_queue_status, or stop showing it, as a
 * transaction. Without a governor the line says so. */
bool pipeline_queue_governor_status(pipeline *p, bool shown);

/* Hide geometry geom_id (ids as in scene.h) or show it again, as a
 * transaction (a hide or show record of count 1): a hidden geometry is not
 * seen and casts no shadows. False, logged, for an id the scene does not
 * have or when refused. The frame state holds the flags and the pipeline's
 * accel follows it (accel_set_hidden), so every user of that accel sees
 * them, and they stay after the pipeline is destroyed (a later pipeline on
 * the same accel starts from them). */
bool pipeline_queue_hide(pipeline *p, uint32_t geom_id, bool hidden);
/* Show every geometry again, as a transaction. */
bool pipeline_queue_unhide_all(pipeline *p);

/* ---- per-frame information given to callbacks ---- */
typedef struct frame_info {
    uint64_t frame;        /* the frame about to be rendered (an idle step renders none: the
                              next step gets the same number) */
    bool idle;             /* governor: this step renders nothing */
    double time_s;         /* its time */
    double last_frame_s;   /* wall-clock duration of the previous loop step (0 for frame 0) */
    double last_render_s;  /* the longest render stage of one thread in that step (0 when it rendered
                              nothing): last_frame_s minus this is what the step spent outside
                              rendering (display stage, serial section, barriers, waiting for a CPU) */
    int threads;           /* render threads for this frame */
} frame_info;

/* ---- one picture over several processes (cluster/: a wall of many machines) ----
 * Three hooks, each set once before pipeline_run (false when the pipeline
 * runs or one is set already), none of which a pipeline without them pays
 * for:
 *   - the RECORD OBSERVER sees every record applied to the frame state
 *     (through a transaction, a setter or pipeline_apply, in the serial
 *     section), right after it applied: what a leading process sends;
 *   - the FRAME SYNC runs once every loop step in the serial section, after
 *     the step's transactions, one-shots and serial animations (or in their
 *     place when the step stops): it may change the step's time and whether
 *     the loop stops after it, and apply records (pipeline_apply). It is the
 *     one serial callback that may block: it is where processes meet, once a
 *     frame;
 *   - the DISPLAY SYNC runs on the display thread in every display stage,
 *     after the show() calls and the settle_stage hooks (where a DRM wall
 *     waits for its last flips) and before the end_stage hooks (where it
 *     commits the next): the frame lock. It also runs after a display failed
 *     (the stage then shows nothing; `frame` is UINT64_MAX), up to the stop. With it the loop runs a display stage every
 *     step, the stopping one included, so every process calls it equally
 *     often. `frame`: the frame the stage showed (UINT64_MAX: none). It may
 *     block; false with err stops the run;
 *   - the PLAN SYNC (a governed pipeline only) runs in the serial section
 *     once the governor has planned the step, after the frame sync and
 *     before the plan is carried out: every process must render a frame at
 *     the same scale and stratum, so the leading process passes its *plan on
 *     and the others replace theirs with it. It may block.
 * pipeline_step_cost is what the governor will observe of the previous step
 * (a following process sends it to the leader); pipeline_set_step_cost puts
 * another cost in its place for this step only (the leader: the slowest
 * process's), both in the frame sync. */
typedef void (*pipeline_record_fn)(void *ctx, const txn_record *r);
typedef void (*pipeline_sync_fn)(void *ctx, pipeline *p, frame_info *info, bool *stop);
typedef bool (*pipeline_display_sync_fn)(void *ctx, uint64_t frame, tess_error *err);
bool pipeline_set_record_observer(pipeline *p, pipeline_record_fn fn, void *ctx);
bool pipeline_set_frame_sync(pipeline *p, pipeline_sync_fn fn, void *ctx);
bool pipeline_set_display_sync(pipeline *p, pipeline_display_sync_fn fn, void *ctx);
typedef void (*pipeline_plan_sync_fn)(void *ctx, uint64_t frame, governor_frame *plan);
bool pipeline_set_plan_sync(pipeline *p, pipeline_plan_sync_fn fn, void *ctx);
bool pipeline_governed(const pipeline *p);
governor_cost pipeline_step_cost(const pipeline *p);
void pipeline_set_step_cost(pipeline *p, const governor_cost *cost);

/* Serial animation: once per frame in the serial section, after transactions. */
typedef void (*pipeline_serial_fn)(pipeline *p, void *ctx, const frame_info *fi);
/* Parallel animation: once per frame on every render thread, after the barrier. */
typedef void (*pipeline_parallel_fn)(pipeline *p, void *ctx, const frame_info *fi, int thread, int threads);
/* Termination: once, on the thread that called pipeline_run, after the loop ends. */
typedef void (*pipeline_termination_fn)(pipeline *p, void *ctx);

/* Register callbacks: before pipeline_run, or inside the serial section (a
 * transaction or a serial callback). They take effect from the next frame
 * they can.
 * False when PIPELINE_MAX_CALLBACKS are registered or called elsewhere. */
bool pipeline_add_serial_animation(pipeline *p, const char *name, pipeline_serial_fn fn, void *ctx);
bool pipeline_add_parallel_animation(pipeline *p, const char *name, pipeline_parallel_fn fn, void *ctx);
bool pipeline_add_termination(pipeline *p, const char *name, pipeline_termination_fn fn, void *ctx);

/* ---- state: read anywhere the state cannot change under you (serial
 * section, or before/after run); set only inside the serial section ---- */
/* Apply a record to the frame state now (the setters below are this with
 * a record built for them): serial section, or while no loop runs; false,
 * logged, elsewhere or when the record is invalid for this pipeline. */
bool pipeline_apply(pipeline *p, const txn_record *r);
/* The frame state (frame_state.h). It changes only in the serial section,
 * so besides there (and before/after run) render threads and parallel
 * animation callbacks may read it during a frame: it is that frame's
 * snapshot. */
const struct frame_state *pipeline_frame_state(const pipeline *p);
bool pipeline_set_camera(pipeline *p, int channel, const camera_desc *camera);
bool pipeline_set_threads(pipeline *p, int threads);
bool pipeline_set_channel_active(pipeline *p, int channel, bool active);
bool pipeline_channel_active(const pipeline *p, int channel);
camera_desc pipeline_camera(const pipeline *p, int channel);
uint64_t pipeline_camera_serial(const pipeline *p, int channel); /* changes so far */
int pipeline_channel_count(const pipeline *p);
/* Channel `channel`'s camera basis for its current camera (its image size, window). */
camera_basis pipeline_channel_basis(const pipeline *p, int channel);
/* Overlay and hidden geometries (see the transactions above; the setters
 * validate as those do). pipeline_status is the text as drawn ('?' for
 * non-printable bytes); pipeline_cursor returns whether the cursor shows and
 * stores its position (either pointer may be NULL). */
bool pipeline_set_status(pipeline *p, const char *text);
const char *pipeline_status(const pipeline *p);
bool pipeline_set_cursor(pipeline *p, bool visible, float sx, float sy);
bool pipeline_cursor(const pipeline *p, float *sx, float *sy);
bool pipeline_set_governor_status(pipeline *p, bool shown);
/* The governor's plan for the frame the serial section prepares (serial
 * section only; a frame of kind SCALED at rung 0 without a governor). */
governor_frame pipeline_governor_frame(const pipeline *p);
bool pipeline_set_hidden(pipeline *p, uint32_t geom_id, bool hidden);
bool pipeline_unhide_all(pipeline *p);
/* Whether geom_id is hidden: in the serial section or while no loop runs,
 * as the frame state says (at once after a setter); on other threads while
 * running, the accel's flag (as of the last serial section). */
bool pipeline_hidden(const pipeline *p, uint32_t geom_id);
uint32_t pipeline_geometry_count(const pipeline *p);       /* ids 0..count-1 */
/* The frame the current serial section prepares (serial section only). */
uint64_t pipeline_frame(const pipeline *p);
/* True on a thread inside p's serial section. */
bool pipeline_in_serial_section(const pipeline *p);

typedef struct pipeline_stats {
    uint64_t frames_rendered, frames_displayed;
    uint64_t transactions_applied, transactions_rejected;
    /* of the rejected: the queue was full; the pipeline was stopping or had stopped
     * (the rest: more than PIPELINE_ARGS_MAX bytes of arguments) */
    uint64_t rejected_queue_full, rejected_stopped;
    /* records pipeline_submit refused as invalid for this pipeline (an instance
     * or channel it does not have, ...): never queued, not among the rejected */
    uint64_t transactions_invalid;
    /* accepted, then never run: still queued when the loop ended (queued after the
     * last barrier that ran transactions, before the stop was asked for). So every
     * accepted transaction is counted once: applied + discarded. */
    uint64_t transactions_discarded;
    uint64_t slow_callbacks;        /* over PIPELINE_CALLBACK_BUDGET_S */
    uint64_t thread_changes;        /* applied thread-count changes */
    render_counts rays;             /* over all frames */
    double display_s;               /* thread 0's time in display stages */
    double run_s;                   /* pipeline_run's wall time */
    double barrier_s;               /* summed over threads: time from arriving at a frame barrier to
                                       leaving it (idle at the end of frames + serial sections) */
    /* the frame barrier's serial part (per-frame aggregates, two clock reads a frame):
     * time inside serial sections (the last thread to arrive works, the others wait;
     * waiting there for work while idle not counted), and per barrier the release: from
     * the serial section's end to the last released thread leaving the barrier (wake-up
     * and mutex hand-off; with more threads than cores, also the wait for a core), summed
     * over every barrier but the last (whose release nothing follows) */
    double serial_s, release_s;
    uint64_t serial_sections;       /* frame barriers passed (serial sections run) */
    /* the governor (all 0 without one): rendered frames by kind, idle steps,
     * moving frames whose loop step took longer than the budget */
    uint64_t frames_scaled, frames_accumulated, frames_resolved, idle_steps;
    uint64_t frames_over_budget;
    /* frames rendered at a reduced scale (governor or render_scale), and the
     * seconds their upscaling took (per frame the longest thread's share) */
    uint64_t frames_reduced;
    double upscale_s;
} pipeline_stats;

/* Counters so far (exact after run returns; may lag while running). */
pipeline_stats pipeline_get_stats(pipeline *p);

#endif
