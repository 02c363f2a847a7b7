/* render_ao.h - the ambient-occlusion renderers (renderer table, render.h):
 * "ao", occlusion alone, and "raytracer-ao", the raytracer with an AO term.
 *
 * Pixel value of "ao" (linear RGB):
 *   hit:  kd x A^e, where A is the filtered unoccluded fraction below, e
 *         settings.ao_exponent (RESPONSE) and kd the surface's diffuse
 *         colour (surface_describe: vertex colour, material, frame-state
 *         colour and highlight): parts keep their colour and darken in
 *         creases. (Grey AO alone is a white kd.)
 *   miss: the scene's background.
 * Lights, the ambient colour and materials' ambient factors play no part.
 *
 * RESPONSE (settings.ao_exponent e, 1..8, default 2.2). With e = 1 the pixel
 * is the light a surface would get under a uniform white sky: physically
 * right, but the display's sRGB curve (about linear^(1/2.2)) then shows
 * A = 0.7 at 0.85 of the open surface's code, and a lone object, whose
 * surface is mostly open, looks flat (the bunny's 5th-95th percentile codes
 * 196-218). With e = 2.2 the displayed code is about kd's code x A: a surface
 * that is 30 % occluded shows 30 % darker, so occlusion reads in proportion.
 * Exactly 1.0 stays 1.0 (open surfaces are kd exactly) and 0 stays 0. The
 * response is applied to each AO frame's filtered A before frames are
 * averaged (by renderer.ao.frames or the governor's accumulation), so for
 * e > 1 the accumulation converges to the mean of A_f^e, slightly brighter
 * than A^e where an N-ray estimate still varies (Jensen; dragon, 16 rays x
 * 16 frames: 0.7 of 255 codes on average, 3 at the 99th percentile); e = 1
 * keeps the exact convergence of FRAMES below. raytracer-ao ignores e: its term is
 * light (TERM), linear in A.
 *
 * DEFAULTS (render_settings_default; issue 33, docs/inspection.md has the
 * measurements): 16 rays, distance 0.2 x the scene box's diagonal, interleave
 * 4, filter 5, exponent 2.2. The exponent and the distance make the shape
 * read (on the dragon the 5th-95th percentile codes span 122 against 55 at 8
 * rays, 0.1 x, e = 1; past 0.2 x the spread grows little: 126 at 0.3 x); the
 * 16 rays keep the 4 x 4 interleave's pattern, which the response makes
 * twice as visible, below what 8 rays leave (mean FLIP 0.0099 against 0.0116
 * on the dragon against a 1024-ray reference at the same response); K = 2 or
 * 1 and a 7 x 7 filter measured worse.
 *
 * RAW TERM. At a primary hit, N = settings.ao_rays rays leave the surface
 * (origin ray_offset_origin along the geometric normal n facing the
 * viewer) in cosine-distributed directions about n from the pixel's
 * interleaved direction set (ao.h: set (x mod K, y mod K), frame = the pixel
 * sampler's stratum), rotated into the world by ao_basis_from_normal(n), with
 * length settings.ao_distance (<= 0: RENDER_AO_DISTANCE_FRACTION, 0.2, x the
 * diagonal of the scene's box, accel_scene_bounds). raw = 1 - occluded / N: the cosine-weighted
 * unoccluded fraction of the hemisphere within that distance.
 *
 * FILTER (discontinuity buffer; Keller and Heidrich 2001, Wald et al.
 * "Interactive Global Illumination", 2002). A = the mean of raw over the
 * pixels q of the ao_filter_px x ao_filter_px box around pixel p (1: off)
 * that pass all three tests against p:
 *   part:   q hit the same instance (hit.geom_id);
 *   normal: dot(n_q, n_p) >= AO_FILTER_MIN_COS (0.9: within ~26 degrees);
 *   depth:  |dot(n_p, P_q - P_p)| <= AO_FILTER_PLANE_REL x t_p (q lies
 *           within 1 % of p's distance from the eye of p's tangent plane:
 *           a depth test that a surface seen at a grazing angle passes);
 * p itself always passes. Only the occlusion term is filtered, never kd.
 * The box shrinks as AO frames accumulate (render_ao_filter_edge): AO frame
 * 0 (a moving frame, the first of a still picture's) uses the whole edge E,
 * frames 1-3 E - 2, frames 4-15 E - 4, frames 16-63 E - 6, ... (one ring
 * fewer each time the frames a pixel has averaged quadruple: the noise the
 * filter hides halves), never below 1. So accumulated frames converge to the
 * unfiltered N -> infinity picture, not to the filtered one, while the first
 * frames keep the filter's smoothness. Measured (AMD EPYC; not speed but
 * error, /tmp experiment at 480 x 270, 8 rays, interleave 4, RMSE of the
 * running mean against 64 rays x 16 frames unfiltered), after 1 / 2 / 4 / 8 /
 * 16 frames: dragon, this schedule 0.0083 / 0.0073 / 0.0062 / 0.0050 /
 * 0.0033, the 5 x 5 filter on every frame 0.0083 / 0.0076 / 0.0072 / 0.0070 /
 * 0.0069, no filter 0.0204 / 0.0137 / 0.0082 / 0.0047 / 0.0029; bunny
 * 0.0046 / 0.0043 / 0.0037 / 0.0032 / 0.0021 against 0.0046 / 0.0042 /
 * 0.0041 / 0.0040 / 0.0039 and 0.0137 / 0.0090 / 0.0052 / 0.0030 / 0.0019.
 *
 * TILES. A tile's pixels need raw terms of pixels up to (ao_filter_px - 1) / 2
 * outside it (the apron): the renderer traces them again for each tile,
 * each exactly as its own tile does (a pure function of the pixel), so an
 * image does not depend on tile size, tile order or thread count. The apron
 * costs rays: a 16 x 16 tile with the 5 x 5 filter traces 20 x 20 pixels.
 *
 * SAMPLERS. single: the pixel centre, frame 0. stratum: the stratum's jittered
 * position, frame = stratum (the governor's accumulation converges: ao.h).
 * jittered:k: the mean over the k^2 strata of what each stratum frame gives,
 * summed in stratum order and divided by k^2 (so it equals the accumulation).
 *
 * FRAMES (settings.ao_frames F, default 1; settings.ao_frame_base B, 0 but in
 * tests). Each pixel sample (stratum t: 0 for single) averages the filtered
 * colours of F AO frames at the same position, frames B + t F + f for
 * f = 0 .. F - 1: summed in float in that order (strata row-major outer,
 * frames inner, from +0) and divided by (float)(k^2 F). F = 1, B = 0 is the
 * behaviour above, bit for bit. single with F frames is what accumulating F
 * frames' direction sets would give at the pixel centre, without the
 * jittered sampler's antialiasing mixed in: N rays x F frames converge to
 * the N F-ray picture (ao.h: consecutive frames walk the one sequence). Each
 * frame traces its primary rays again, so F frames cost what F frames do.
 *
 * TERM (renderer "raytracer-ao"). The raytracer shades each primary ray as
 * render_tile does (lights, shadows, transparency, cutting planes, caps;
 * render_trace_primary) and reports the first surface the ray shows; the
 * raw term and the filter above are computed there, with that surface's
 * instance, normal and position, and the pixel is
 *   colour - ambient x (1 - A)
 * where colour is the raytracer's and ambient the part of it that is the
 * first surface's ambient light (scene ambient x material ambient x kd,
 * times the surface's opacity when it is transparent): occlusion darkens the
 * light that comes from everywhere, never the lights' direct light (their
 * shadow rays already say what blocks them). Unoccluded (A = 1) the pixel is
 * the raytracer's bit for bit. Surfaces seen through a transparent first
 * surface keep their plain ambient light; AO rays are blocked by transparent
 * surfaces as by opaque ones. Misses are the raytracer's background. The
 * apron costs primary and shadow rays too: with the 5 x 5 filter a 16 x 16
 * tile shades 20 x 20 pixels.
 *
 * COUNTS. AO rays are counted in counts->ao_rays, primary rays (apron
 * pixels included) in primary_rays, hits in primary_hits; raytracer-ao adds
 * the raytracer's shadow and secondary rays (of the apron pixels too). */
#ifndef TESSERA_RENDER_AO_H
#define TESSERA_RENDER_AO_H

#include "render.h"
#include "sampler.h"

#define AO_FILTER_MIN_COS 0.9f
#define AO_FILTER_PLANE_REL 0.01f

/* The AO ray length a view uses (world units): its settings' ao_distance, or
 * RENDER_AO_DISTANCE_FRACTION (0.2) x the scene box's diagonal when that is
 * <= 0 (0 for an empty scene). */
float render_ao_distance(const render_view *v);

/* The filter edge AO frame `frame` uses for a configured odd edge
 * filter_px (FILTER above): filter_px - 2 ceil(log4(frame + 1)), at least 1. */
int render_ao_filter_edge(int filter_px, uint32_t frame);

/* The renderer's tile function, render_ao_tile, is declared in render.h
 * (the renderer table needs it there). */

/* The whole image with `threads` threads (the caller's included) taking
 * tile_px x tile_px tiles of render_ao_tile from an atomic counter (tile_px
 * >= 1; RENDER_TILE_PX is what render_image uses). For benchmarks and tests;
 * the pipeline drives render_ao_tile through its traverser. `counts` may be
 * NULL. */
void render_ao_image(const render_view *v, const pixel_sampler *s, int threads, int tile_px, float *rgb,
                     render_counts *counts);

#endif
