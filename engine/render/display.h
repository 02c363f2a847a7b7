/* display.h - the image display component: where the pipeline hands a
 * finished frame. Implementations live outside the engine (wall/: null, dump;
 * DRM/KMS comes with the wall issue; tests have their own); the engine knows
 * only this interface.
 *
 * Threading: show() is called by the pipeline's display thread only, one call
 * at a time per display, during the display stage of the frame after the one
 * that rendered the image. The image is read-only and stays unchanged until
 * show() returns; a display that needs the pixels later copies them.
 *
 * Two optional hooks (NULL when not wanted; a display without them costs the
 * pipeline nothing):
 *   write_tile: called by render threads, concurrently, right after each tile
 *     of a frame was rendered into img->rgb, with the tile's pixel rectangle
 *     [x0, x1) x [y0, y1); tiles of one frame never overlap. A scan-out display
 *     converts the tile straight into the buffer that frame will be shown
 *     from, while the pixels are still in the render thread's cache (each
 *     pixel written once, never read back: scan-out memory may be
 *     write-combined). img->frame tells which frame (and so which buffer); the
 *     display must keep at least four buffers' worth of frames apart: frame f
 *     is written while f-1 waits for display and f-2 (or, until its flip
 *     completes, f-3) is on screen.
 *   end_stage: called on the display thread once per display stage, after all
 *     show() calls of that stage (also for displays that got no frame in it,
 *     e.g. a channel switched off): where a display that drives several
 *     channels' outputs (one card) commits them together. A pipeline with such
 *     a display runs a display stage every loop step, frames or not (from the
 *     first step, before any frame exists, to the one after the last frame),
 *     so it is served even while all its channels are switched off; the hook
 *     then paces the loop (it should wait for its events rather than return
 *     at once).
 *   settle_stage: optional, called on the display thread once per display
 *     stage after the show() calls and before the display sync (pipeline.h;
 *     a wall of several machines: the barrier before the flip), then
 *     end_stage after it: a display that commits in end_stage waits here for
 *     what its last commit started (a card's flips), so that after the
 *     barrier only the commit is left. A display must also work when a
 *     wrapper calls end_stage alone. */
#ifndef TESSERA_DISPLAY_H
#define TESSERA_DISPLAY_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/base/camera.h"
#include "engine/base/err.h"

/* One finished frame of one channel. */
typedef struct frame_image {
    const float *rgb;        /* linear RGB, 3 floats per pixel, row-major, top row first */
    int width_px, height_px;
    uint64_t frame;          /* pipeline frame number, from 0 */
    double time_s;           /* the frame's time (pipeline time mode) */
    int channel;             /* index of the channel that rendered it */
    camera_desc camera;      /* the camera it was rendered with */
    uint64_t camera_serial;  /* changes of this channel's camera before this frame (0: the initial one) */
    double render_scale;     /* the governor's render scale for the frame (1: full size) */
    int samples;             /* rays per pixel the picture holds (the governor's accumulation; else the sampler's) */
} frame_image;

typedef struct image_display image_display;

typedef struct image_display_ops {
    const char *name; /* component name, as in configs: "null", "dump", ... */
    /* Present one frame. False with err set stops the pipeline with that error. */
    bool (*show)(image_display *d, const frame_image *img, tess_error *err);
    void (*destroy)(image_display *d); /* frees d */
    void (*write_tile)(image_display *d, const frame_image *img, int x0, int y0, int x1, int y1); /* optional */
    bool (*end_stage)(image_display *d, tess_error *err); /* optional; false with err stops the pipeline */
    bool (*settle_stage)(image_display *d, tess_error *err); /* optional; false with err stops the pipeline */
} image_display_ops;

/* Implementations embed this as their first member. */
struct image_display {
    const image_display_ops *ops;
};

static inline void image_display_destroy(image_display *d)
{
    if (d)
        d->ops->destroy(d);
}

#endif
