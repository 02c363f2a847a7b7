/* display.h (wall) - the headless image displays: null (drops frames:
 * benchmarks of rendering alone), convert (encodes each finished frame to
 * 8-bit sRGB like scan-out, then drops it), convert-tiles (the same per tile
 * on the render threads) and dump (writes each frame through the dump
 * backend, wall/dump.h). The DRM/KMS display is wall/drm.h; the table that
 * chooses among them by name is wall/display_backend.h. */
#ifndef TESSERA_WALL_DISPLAY_H
#define TESSERA_WALL_DISPLAY_H

#include <stdbool.h>

#include "engine/render/display.h"
#include "engine/base/err.h"

/* A display that only counts frames. */
image_display *display_null_create(void);

/* A display that converts each frame to 8-bit sRGB XRGB8888, as a scan-out
 * display must, into a buffer of its own, and drops it (benchmarks). */
image_display *display_convert_create(void);

/* The same conversion done by the render threads as each tile finishes
 * (display.h's write_tile hook), into a ring of four buffers: what the DRM
 * display does with scan-out buffers (benchmarks: convert vs convert-tiles). */
image_display *display_convert_tiles_create(void);

/* A display that writes frame N of the pipeline to `pattern` with N as the
 * frame number (dump_frame_path rules: "####" or "%04d"; a pattern without
 * either gets _NNNN when `sequence`, else is one file rewritten each frame).
 * The pattern is copied. NULL with err when the pattern is invalid. */
image_display *display_dump_create(const char *pattern, bool sequence, tess_error *err);

#endif
