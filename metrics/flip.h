/* flip.h (metrics) - LDR-FLIP: a per-pixel perceptual error map of a test
 * image against a reference image, as published in
 *
 *   P. Andersson, J. Nilsson, T. Akenine-Moller, M. Oskarsson, K. Astrom,
 *   M. D. Fairchild: "FLIP: A Difference Evaluator for Alternating Images",
 *   Proc. ACM Comput. Graph. Interact. Tech. 3(2) (HPG 2020).
 *
 * Written here from the paper; the numbers were checked against NVlabs' C++
 * tool (metrics/README.md: agreement of the mean within 1e-4).
 *
 * INPUT. Both images are linear RGB (sRGB primaries, D65), 3 floats per
 * pixel, row-major, top row first. Each value is clamped to [0, 1] first (NaN
 * counts as 0): LDR-FLIP judges what a display shows. An 8-bit sRGB file must
 * be decoded to linear before (NVlabs' tool does the same: it decodes PNGs to
 * linear RGB, clamps, and goes from linear RGB straight to XYZ).
 *
 * THE PIPELINE, per image:
 *  colour: linear RGB -> XYZ -> YCxCz (the opponent space), each channel
 *    convolved with its contrast sensitivity filter (a Gaussian, or for Cz a
 *    sum of two, over offsets in degrees = pixels / ppd; radius 3 standard
 *    deviations of the widest), back to linear RGB clamped to [0, 1], to
 *    CIELab with the Hunt adjustment (a, b scaled by 0.01 L); then between
 *    the two images the HyAB distance |dL| + |d(a, b)|, raised to q_c = 0.7
 *    and mapped to [0, 1] with the breakpoint p_c = 0.4 of the largest
 *    distance (green against blue) going to p_t = 0.95;
 *  features: the luminance Y / Yn filtered with the first (edges) and second
 *    (points) derivatives of a Gaussian of standard deviation 0.5 * 0.082
 *    degrees (radius 3 standard deviations); the feature difference is
 *    (max(|d edge|, |d point|) / sqrt 2) ^ q_f, q_f = 0.5;
 *  error = colour_error ^ (1 - feature_difference), in [0, 1].
 * Borders repeat the edge pixel (as the reference does). Filters run
 * separably (the Cz filter as two separable terms, which is exact), every
 * sum and conversion in double.
 *
 * Identical inputs give exactly 0 everywhere. The result does not depend on
 * the thread count: each output row is computed by the same operations in
 * the same order whichever thread computes it. */
#ifndef TESSERA_FLIP_H
#define TESSERA_FLIP_H

#include <stdbool.h>

#include "engine/base/err.h"

/* FLIP's default viewer: 0.7 m from a 0.7 m wide monitor of 3840 pixels,
 * ppd = distance * pixels_per_m * pi / 180 = 67.02 pixels per degree. */
#define FLIP_DEFAULT_PPD (3840.0 * 3.14159265358979323846 / 180.0)
/* Accepted pixels per degree: below 1 the filters are narrower than a
 * pixel; above 1000 (a wall seen from 20 m) the spatial filter's radius
 * passes 135 pixels and its row buffers grow past what a metric should take. */
#define FLIP_MIN_PPD 1.0
#define FLIP_MAX_PPD 1000.0

/* Pixels per degree of a viewer distance_m from a display of pixels_per_m
 * pixels per metre, as FLIP computes it: distance * pixels_per_m * pi / 180
 * (the small-angle form: 2.5e-5 less than 2 d tan(0.5 deg)). */
double flip_ppd_of_viewer(double distance_m, double pixels_per_m);

/* Radius in pixels of the colour (contrast sensitivity) filter and of the
 * edge/point filter at `ppd` pixels per degree (67.02: 10 and 9). */
int flip_spatial_radius_px(double ppd);
int flip_feature_radius_px(double ppd);

/* The LDR-FLIP error map of `test` against `reference` (each W x H linear
 * RGB, see INPUT) into error_out[0 .. W * H), every value in [0, 1], with up
 * to `threads` threads (< 1 counts as 1). False (with err) for a size < 1,
 * a ppd outside [FLIP_MIN_PPD, FLIP_MAX_PPD], or memory running out. */
bool flip_ldr_map(const float *reference_rgb, const float *test_rgb, int width_px, int height_px, double ppd,
                  int threads, float *error_out, tess_error *err);

#endif
