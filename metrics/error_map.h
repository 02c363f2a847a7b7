/* error_map.h (metrics) - an error map (values in [0, 1]) as a picture: a
 * magma-like colour map (black - purple - orange - pale yellow, perceptually
 * ordered, as FLIP's own maps use) with a legend strip under the map: the
 * colour ramp from 0 at the left edge to 1 at the right edge, tick marks at
 * 0, 0.25, 0.5, 0.75 and 1, and their numbers where they fit. */
#ifndef TESSERA_ERROR_MAP_H
#define TESSERA_ERROR_MAP_H

#include <stdbool.h>

#include "engine/base/err.h"

/* Height in pixels of the legend strip added under a map `width_px` wide
 * (20 pixels below 640 pixels of width, and 20 more per 320 pixels). */
int error_map_legend_height_px(int width_px);

/* The colour of `value` (clamped to [0, 1]; NaN counts as 0), sRGB-encoded
 * in [0, 1]: linear interpolation between nine samples of matplotlib's magma. */
void error_map_color_srgb(double value, double srgb[3]);

/* The picture of error[0 .. W * H): *rgb_out is W x (H + legend) pixels of
 * linear RGB floats (3 per pixel, top row first, ready for dump_write_rgb),
 * freed by the caller with free(); *height_out is H + legend. False (with err)
 * for a size < 1 or memory running out. */
bool error_map_render(const float *error, int width_px, int height_px, float **rgb_out, int *height_out,
                      tess_error *err);

#endif
