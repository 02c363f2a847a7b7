/* traverser.h - the image traverser component: how a frame's pixels become
 * work for the render threads. One implementation so far, "tiled": square
 * tiles of every channel handed out by one atomic counter (the dynamic load
 * balancer), in a configurable tile order.
 *
 * Threading: begin_frame runs in the pipeline's serial section (no render
 * thread is working); render runs on every render thread at once, and
 * returns when no work is left for the frame. Which thread renders which tile
 * is up to the scheduler; a pixel's value never depends on it. */
#ifndef TESSERA_TRAVERSER_H
#define TESSERA_TRAVERSER_H

#include <stdint.h>

#include "display.h"
#include "engine/base/err.h"
#include "overlay.h"
#include "render.h"
#include "sampler.h"
#include "tile_order.h"

/* One channel's frame as the traverser sees it. */
typedef struct traverser_target {
    const render_view *view; /* camera (with the image size), scene, options */
    float *rgb;              /* where the pixels go: width * height * 3 floats; NULL: the channel
                                is switched off this frame and its tiles are skipped */
    image_display *sink;     /* with a write_tile hook: gets each finished tile; else NULL */
    const frame_image *img;  /* what sink->write_tile is given (the frame being rendered) */
    const overlay_plan *overlay; /* composited into each tile between rendering and write_tile;
                                    NULL: nothing of the overlay falls on this channel */
    /* The governor's accumulation buffer (pipeline.h, GOVERNOR): NULL for none.
     * With one, each tile is rendered into rgb (one sample per pixel), then per
     * float: accum = (accum_reset ? 0.0f : accum) + rgb, rgb = accum / accum_samples,
     * both before the overlay; resolve_only skips the rendering and only sets
     * rgb = accum / accum_samples (the overlay changed, the picture did not). */
    float *accum;
    float accum_samples; /* samples in accum after this frame, >= 1 */
    bool accum_reset;
    bool resolve_only;
} traverser_target;

typedef struct image_traverser image_traverser;

typedef struct image_traverser_ops {
    const char *name;
    /* Serial section: the frame about to render goes to these targets, one per
     * channel, with the image sizes given at creation. */
    void (*begin_frame)(image_traverser *t, const traverser_target *targets);
    /* Every render thread: render with `r` and `s` until the frame's work is
     * gone; adds the rays traced to *counts (the caller's own). */
    void (*render)(image_traverser *t, const renderer *r, const pixel_sampler *s, render_counts *counts);
    void (*destroy)(image_traverser *t);
} image_traverser_ops;

struct image_traverser {
    const image_traverser_ops *ops;
};

#define TRAVERSER_NAMES "tiled"

/* The tiled traverser for `channels` images of the given sizes: tiles of
 * tile_px x tile_px pixels (the last row and column may be smaller), each
 * channel's tiles in `order` (seed: shuffle), all channels' tiles in one
 * sequence under one counter. NULL with err when out of memory. */
image_traverser *traverser_tiled_create(int tile_px, tile_order order, uint32_t seed, const int *widths_px,
                                        const int *heights_px, int channels, tess_error *err);

static inline void image_traverser_destroy(image_traverser *t)
{
    if (t)
        t->ops->destroy(t);
}

#endif
