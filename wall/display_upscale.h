/* display_upscale.h (wall) - a display in front of another: the pipeline
 * renders a channel at a reduced size (engine/upscale.h, RENDER SCALE) and
 * this display upscales each finished frame to the output size before the
 * display behind it sees it. What `tessera render --scale S` puts in front of
 * its display; the governor will instead upscale on the render threads with
 * upscale_plan_rows.
 *
 * Threading: as display.h says, show() runs on the pipeline's display thread,
 * one call at a time; the upscale runs there too (single-threaded), into a
 * buffer of this display's own that the inner display reads during its show().
 * An inner display with a write_tile hook gets the whole upscaled frame as
 * one tile from show(), just before its show(); displays with an end_stage
 * hook (a DRM wall) cannot be wrapped. The overlay (status line, cursor) is
 * drawn into the reduced frame and upscaled with it. */
#ifndef TESSERA_WALL_DISPLAY_UPSCALE_H
#define TESSERA_WALL_DISPLAY_UPSCALE_H

#include <stdbool.h>
#include <stdint.h>

#include "engine/display.h"
#include "engine/err.h"
#include "engine/upscale.h"

/* Frames of src_w x src_h go in, frames of dst_w x dst_h go to `inner`,
 * upscaled with `filter`. Takes ownership of inner (destroyed with this
 * display, or at once on failure). NULL with err: bad sizes (upscale_plan_create),
 * an inner display with an end_stage hook, or no memory. */
image_display *display_upscale_create(image_display *inner, int src_w, int src_h, int dst_w, int dst_h,
                                      upscale_filter filter, tess_error *err);

/* Frames upscaled so far and the seconds (monotonic clock) spent upscaling
 * them, the inner display's show() not included. Only for a display made by
 * display_upscale_create, read when show() cannot run (before or after
 * pipeline_run). */
void display_upscale_time(const image_display *d, uint64_t *frames, double *upscale_s);

#endif
