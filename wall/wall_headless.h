/* wall_headless.h - a display wall without a device: the same layout as the
 * DRM backend renders, written to files. Each output is a pipeline channel
 * showing its window of the wall's one image plane (wall_output_window); its
 * display writes the output's image and, once every output of a frame is in,
 * the stitched image of the whole wall with the bezels black, so tests can
 * compare both. */
#ifndef TESSERA_WALL_HEADLESS_H
#define TESSERA_WALL_HEADLESS_H

#include <stdbool.h>

#include "engine/base/camera.h"
#include "engine/render/display.h"
#include "engine/base/err.h"
#include "wall_config.h"

/* Width / height of the wall's image plane: its bounding box in mm. */
float wall_plane_aspect(const wall_config *w);

/* The part of the image plane output i shows: its active area. */
camera_window wall_output_window(const wall_config *w, int i);

/* Pixel size of the stitched image: the wall's bounding box at the finest
 * pixel pitch of its outputs. */
void wall_stitched_size(const wall_config *w, int *width_px, int *height_px);

/* One display per output (displays[i] for output i, in channel order 0..n-1,
 * every output's pixel size resolved). Output i's frames go to `pattern` with
 * "-CONNECTOR" (wall_output_label) before the extension; the stitched wall to `pattern` itself.
 * `sequence`: frame numbers in the names (dump_frame_path). `present` (NULL:
 * every output): the outputs this process drives (one machine of several:
 * cluster/); displays[i] is NULL for the others, and without all of them no
 * stitched image is written (it would be part of the wall). The displays
 * share state: destroy all of them (the pipeline does). False with err. */
bool wall_headless_displays(const wall_config *w, const char *pattern, bool sequence, const bool *present,
                            image_display **displays, tess_error *err);

/* `pattern` with "-name" inserted before the extension (or at the end). */
bool wall_output_pattern(const char *pattern, const char *name, char *out, size_t out_bytes);

#endif
