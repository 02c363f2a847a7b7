/* governor.h - the frame-budget governor's decisions (issue 13): which render
 * scale a moving frame gets, when a still picture refines, and when it is
 * done. A pure state machine: the pipeline (pipeline.h, GOVERNOR) feeds it
 * what each frame cost and what changed, and carries out what it plans. No
 * clock, no threads, no allocation: tests drive it with synthetic costs.
 *
 * MODES
 *   MOVING      the picture changed within the last still_s seconds (frame
 *               time): frames render one ray per pixel at the scale the cost
 *               model picks, upscaled to the output size.
 *   REFINING    still for still_s: frame n (0 .. k^2 - 1) renders stratum n of
 *               jittered:k at full resolution into the accumulation buffer and
 *               shows its mean; frame k^2 - 1 is jittered:k's image, bit for bit.
 *   CONVERGED   nothing left to add: no frame renders (an idle wall costs no
 *               CPU) until the picture changes (MOVING) or only the overlay
 *               does (one RESOLVE frame: the converged mean, overlay redrawn).
 *
 * THE SCALE LADDER. Scales go down in steps of 1/8 from 1 to 1/4
 * (GOVERNOR_SCALES), rung 0 being full resolution. The cost model predicts a
 * frame at rung r as
 *   overhead_s + pixel_s * pixels(r) + (r > 0 ? upscale_s : 0)
 * where pixels(r) is the low-res pixel count of every channel together,
 * pixel_s the render time per low-res pixel, upscale_s the time to upscale to
 * the output and overhead_s the rest of a loop step (display stage, barriers,
 * serial section): each an exponential average (weight GOVERNOR_EMA_WEIGHT)
 * of what frames measured. The decision, once per moving frame:
 *   - over budget: when the prediction for the current rung exceeds
 *     GOVERNOR_HIGH_FRACTION x budget, jump straight to the largest scale
 *     predicted within GOVERNOR_TARGET_FRACTION x budget (or the smallest);
 *   - room to spare: when the next larger scale is predicted within
 *     GOVERNOR_TARGET_FRACTION x budget, go up one rung (never more: a wrong
 *     model costs one step, and going up one rung at a time is what keeps the
 *     scale from oscillating by more than one step).
 * With a cost linear in pixels the prediction after an up-step is at most
 * TARGET <= HIGH, so the next frame does not step back down: the scale settles
 * within a few frames and then moves by at most one rung. The refining and
 * resolve frames are at rung 0 and feed the model too. */
#ifndef TESSERA_GOVERNOR_H
#define TESSERA_GOVERNOR_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/err.h"

#define GOVERNOR_RUNGS 7
#define GOVERNOR_EMA_WEIGHT 0.5       /* weight of the newest measurement */
#define GOVERNOR_TARGET_FRACTION 0.85 /* aim frames at this part of the budget */
#define GOVERNOR_HIGH_FRACTION 1.0    /* step down when predicted over this part */
#define GOVERNOR_DEFAULT_STILL_S 0.25 /* still this long (frame time): refine */
#define GOVERNOR_DEFAULT_REFINE_K 4   /* converge to jittered:4 (16 frames) */

/* Rung r's render scale: 1, 7/8, ..., 1/4. */
extern const double GOVERNOR_SCALES[GOVERNOR_RUNGS];

typedef struct governor_config {
    double budget_s;  /* frame-time budget, > 0 */
    double still_s;   /* still this long before refining, >= 0 */
    int refine_k;     /* converge to jittered:refine_k, 1 .. PIXEL_SAMPLER_MAX_K */
} governor_config;

/* False with err naming the field and the problem. */
bool governor_config_validate(const governor_config *cfg, tess_error *err);

typedef enum governor_mode { GOVERNOR_MOVING, GOVERNOR_REFINING, GOVERNOR_CONVERGED } governor_mode;

/* What one frame does. */
typedef enum governor_frame_kind {
    GOVERNOR_FRAME_SCALED,     /* one ray per pixel at `rung`'s scale (rung 0: full size, no upscale) */
    GOVERNOR_FRAME_ACCUMULATE, /* stratum `stratum` of jittered:k into the accumulation buffer */
    GOVERNOR_FRAME_RESOLVE,    /* no rays: the converged mean shown again with a new overlay */
    GOVERNOR_FRAME_IDLE,       /* nothing rendered, nothing new shown */
} governor_frame_kind;

typedef struct governor_frame {
    governor_frame_kind kind;
    int rung;          /* SCALED: the ladder rung; else 0 */
    int stratum;       /* ACCUMULATE: 0 .. k^2 - 1 (0 resets the buffer) */
    int samples;       /* samples per pixel in the picture this frame shows (1 for SCALED) */
} governor_frame;

/* What a rendered frame cost, measured by the pipeline. */
typedef struct governor_cost {
    double step_s;     /* the whole loop step */
    double render_s;   /* its render stage (the longest thread), upscaling included */
    double upscale_s;  /* of which upscaling (the longest thread); 0 at full size */
    double pixels;     /* low-res pixels rendered, all channels */
} governor_cost;

typedef struct governor {
    governor_config cfg;
    double output_pixels;  /* full-size pixels of all channels */
    governor_mode mode;
    int rung;              /* moving frames' current rung */
    int stratum_next;      /* REFINING: the next stratum */
    bool resolve_pending;  /* CONVERGED: the overlay changed */
    double changed_at_s;   /* frame time of the last picture change */
    /* the cost model (all 0 until measured) */
    double pixel_s, upscale_s, overhead_s;
    bool have_pixel_s, have_upscale_s, have_overhead_s;
    uint64_t frames_over_budget; /* moving frames whose step went over the budget */
} governor;

/* A governor for channels of output_pixels full-size pixels in all. Starts
 * MOVING at full size (rung 0) as of time 0. */
void governor_init(governor *g, const governor_config *cfg, double output_pixels);

/* Low-res pixels of rung r for the given channel sizes (upscale_low_res_px
 * per axis, summed over channels). */
double governor_rung_pixels(int rung, const int *widths_px, const int *heights_px, int channels);

/* Plan the frame at frame time time_s. picture_changed: a transaction changed
 * what the picture shows (camera, hidden geometry, a channel switched on)
 * since the last plan; overlay_changed: only the overlay did. rung_pixels[r]:
 * governor_rung_pixels of each rung for the current channels. */
governor_frame governor_plan(governor *g, double time_s, bool picture_changed, bool overlay_changed,
                             const double *rung_pixels);

/* Feed what the frame planned last cost (after it rendered; not for IDLE). */
void governor_observe(governor *g, const governor_frame *f, const governor_cost *cost);

/* The prediction of rung r's step time (0 while nothing is measured). */
double governor_predict_s(const governor *g, int rung, const double *rung_pixels);

/* One line for the status line and the log, e.g. "governor: moving, scale 0.62
 * (budget 33 ms)" or "governor: refining 5/16 samples". */
void governor_describe(const governor *g, const governor_frame *f, char *buf, unsigned size);

#endif
