/* upscale.h - render scale: a frame rendered at a fraction of the output
 * size, then upscaled to the output size with a reconstruction filter. The
 * governor of a kiosk (issue 13) trades error for time with it; `tessera
 * render --scale S --upscale F` uses it for one frame.
 *
 * IMAGES. Linear RGB, 3 floats per pixel, row-major, top row first (as
 * display.h's frame_image). The source is src_w x src_h ("low-res"), the
 * destination dst_w x dst_h, with 1 <= src_w <= dst_w and 1 <= src_h <= dst_h
 * (this module only enlarges; shrinking would need a prefilter).
 *
 * RENDER SCALE. A scale s in (0, 1] renders a W x H output at
 *   upscale_low_res_px(W, s) x upscale_low_res_px(H, s),
 *   upscale_low_res_px(n, s) = max(1, round(n * s))
 * (n * s in double, halves rounded away from zero). Per axis, so the low-res
 * image's aspect can differ from W / H by rounding: render it with the output's
 * plane aspect (camera_basis_window with plane_aspect = (float)W / H and the
 * whole window) so it covers exactly the view of the full-size image, each
 * low-res pixel a slightly non-square patch of it.
 *
 * ALIGNMENT (pixel centres, as camera.h: pixel x covers [x, x + 1) of its
 * image). Output pixel x has its centre at (x + 0.5) / dst_w of the image
 * width, which in low-res pixel coordinates (texel i's centre at i) is
 *   u = (x + 0.5) * src_w / dst_w - 0.5        (likewise v for rows)
 * computed in double. Edges are clamped: u is clamped to [0, src_w - 1] (the
 * outer half-texel repeats the edge texel), and every tap index outside
 * [0, src_w - 1] is clamped into it. With i = floor(u), t = u - i in [0, 1):
 *
 * FILTERS
 *   bilinear       out = lerp over texels i, i + 1 with weight t, as
 *                  a + t (b - a) (so a constant image stays exactly
 *                  constant), rows first (v), then columns (u).
 *   clamped-cubic  the Catmull-Rom spline (Catmull & Rom, "A class of local
 *                  interpolating splines", 1974), which is Keys' cubic
 *                  convolution with a = -0.5 (R. Keys, "Cubic convolution
 *                  interpolation for digital image processing", IEEE TASSP
 *                  29(6), 1981): 4 x 4 taps i-1 .. i+2, separable, weights
 *                    w0 = (-t^3 + 2t^2 - t) / 2     w1 = (3t^3 - 5t^2 + 2) / 2
 *                    w2 = (-3t^3 + 4t^2 + t) / 2    w3 = (t^3 - t^2) / 2
 *                  It interpolates (t = 0 gives the texel) and reproduces
 *                  polynomials up to degree 2, so smooth shading comes out
 *                  closer than with bilinear and a step edge rises steeper
 *                  (10-90 % over 0.71 of a texel instead of 0.80). Its
 *                  negative lobes ring at edges (up to 7.4 % overshoot on a
 *                  step), so each channel of the result is clamped to the
 *                  [min, max] of that channel over the 2 x 2 nearest texels
 *                  (i, i + 1) x (j, j + 1). That clamp is what makes it
 *                  edge-aware: in smooth regions the cubic already lies inside
 *                  the range and the clamp does nothing; at an edge, where the
 *                  neighbourhood jumps, it removes the overshoot and keeps the
 *                  steeper rise (the deringing of AMD FidelityFX Super
 *                  Resolution 1's EASU and of TAA's neighbourhood clamp, Karis,
 *                  "High quality temporal supersampling", SIGGRAPH 2014 course).
 *                  A constant neighbourhood gives its value exactly.
 *
 * DETERMINISM AND THREADS. An output row is a pure function of the source
 * image, the plan and its row number: each is computed by the same float
 * operations in the same order (no FMA: the build has -ffp-contract=off)
 * whichever call computes it, so rows computed in separate calls, by any
 * threads in any order, equal one full call bit for bit. A plan is read-only
 * after create: any number of threads may run upscale_plan_rows on one plan
 * at once, each with its own scratch, on disjoint row ranges. No globals.
 * When the sizes are equal (scale 1) the output is a copy, bit for bit. */
#ifndef TESSERA_UPSCALE_H
#define TESSERA_UPSCALE_H

#include <stdbool.h>
#include <stddef.h>

#include "engine/base/err.h"

typedef enum upscale_filter {
    UPSCALE_BILINEAR,
    UPSCALE_CLAMPED_CUBIC,
} upscale_filter;

/* The names upscale_filter_from_name knows, for messages. */
#define UPSCALE_FILTER_NAMES "bilinear, clamped-cubic"

/* "bilinear" or "clamped-cubic"; on failure *out is untouched and err names
 * the text and the names expected. */
bool upscale_filter_from_name(const char *name, upscale_filter *out, tess_error *err);
/* The name from_name reads back ("?" for a value outside the enum). */
const char *upscale_filter_name(upscale_filter f);

/* A render scale is a finite number in (0, 1]; false with err otherwise. */
bool upscale_scale_validate(double scale, tess_error *err);

/* max(1, round(size_px * scale)): the low-res edge for an output edge of
 * size_px >= 1 pixels at a valid scale (see RENDER SCALE). */
int upscale_low_res_px(int size_px, double scale);

/* The taps of one filter between two sizes, computed once (per scale and
 * output size) and then shared read-only. */
typedef struct upscale_plan upscale_plan;

/* NULL with err naming the problem: a size < 1, a source larger than the
 * destination on either axis, a filter outside the enum, or no memory. */
upscale_plan *upscale_plan_create(int src_w, int src_h, int dst_w, int dst_h, upscale_filter filter,
                                  tess_error *err);
void upscale_plan_destroy(upscale_plan *p); /* NULL is fine */

/* Floats of scratch upscale_plan_rows needs per call (one filtered source row). */
size_t upscale_plan_scratch_floats(const upscale_plan *p);

/* Output rows [y0, y1) of dst (the whole dst_w x dst_h image's memory; only
 * those rows are written) from the whole src image. 0 <= y0 <= y1 <= dst_h;
 * scratch holds upscale_plan_scratch_floats(p) floats, owned by the caller
 * and not shared with another call running at the same time. src and dst
 * must not overlap. */
void upscale_plan_rows(const upscale_plan *p, const float *src, float *dst, int y0, int y1, float *scratch);

/* The whole image in one call (a plan and scratch made and freed inside).
 * False with err as for upscale_plan_create. */
bool upscale_image(const float *src, int src_w, int src_h, float *dst, int dst_w, int dst_h, upscale_filter filter,
                   tess_error *err);

#endif
